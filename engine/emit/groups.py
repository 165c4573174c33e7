"""Option groups and the grouped option graph: a team-sized graph reduced to what fits a screen.

A *group* is the options of one source folder (relative to the folder all option files share);
a set whose options all sit in one folder is grouped by name prefix (``striker_…``), its
namespace in all but syntax. The basic behaviors the graph calls form one more group. Each
group is drawn either *collapsed* (one node standing for all its options, edges merged) or
expanded as a cluster labelled with the folder, so an overview of 180 options is a dozen
readable nodes and one folder is opened at a time.

Element ids follow :mod:`.dot` so that the studio highlights either picture the same way: options
``option_<index>``, behaviors ``behavior_<index>``, a collapsed group ``group_<n>`` (its position
in :func:`option_groups`), calls between two drawn options ``call_<i>_<o|b><j>`` as in the plain
graph, and every edge that touches a collapsed group ``gcall_<from>_<to>`` with ``from``/``to``
``g<n>``, ``o<index>`` or ``b<index>``.
"""

from __future__ import annotations

import posixpath
from collections.abc import Collection
from dataclasses import dataclass

from xabsl_studio.engine import ir
from xabsl_studio.engine.emit.dot import quote, reachable_options

#: The key of the group of basic behaviors (no folder can be called so: it has parentheses).
BEHAVIORS = "(basic behaviors)"
#: A collapse list naming every group.
ALL = "*"


@dataclass(frozen=True, slots=True)
class OptionGroup:
    """The options (IC indices) of one folder or name prefix, or the called basic behaviors."""

    key: str
    options: tuple[int, ...] = ()
    behaviors: tuple[int, ...] = ()

    @property
    def size(self) -> int:
        """Options and behaviors in the group."""
        return len(self.options) + len(self.behaviors)

    def as_dict(self) -> dict[str, object]:
        """The group as JSON (``/api/graph-groups``)."""
        return {"key": self.key, "options": list(self.options), "behaviors": list(self.behaviors)}


def _folder(option: ir.Option) -> str:
    return posixpath.dirname((option.file or "").replace("\\", "/"))


def _common_folder(folders: list[str]) -> str:
    parts = [f.split("/") for f in folders if f]
    if not parts or len(parts) < len(folders):
        return ""
    common: list[str] = []
    for level in zip(*parts, strict=False):
        if len(set(level)) != 1:
            break
        common.append(level[0])
    return "/".join(common)


def _prefix(name: str) -> str:
    return name.split("_", 1)[0] if "_" in name else name


def option_groups(program: ir.Program, names: list[str]) -> tuple[OptionGroup, ...]:
    """The groups of options ``names`` (in order of first appearance), then the behaviors'."""
    options = [program.options[n] for n in names if n in program.options]
    folders = [_folder(o) for o in options]
    common = _common_folder(folders)
    keys = [f.removeprefix(common).strip("/") or "." for f in folders]
    if len(set(keys)) < 2:  # one folder: group by name prefix
        keys = [_prefix(o.name) for o in options]
    members: dict[str, list[int]] = {}
    for option, key in zip(options, keys, strict=True):
        members.setdefault(key, []).append(option.index)
    groups = [OptionGroup(key, tuple(indices)) for key, indices in members.items()]
    called = sorted(
        {
            program.behaviors[a.behavior].index
            for o in options
            for s in o.states
            for a in s.actions
            if isinstance(a, ir.BehaviorCall) and a.behavior in program.behaviors
        }
    )
    if called:
        groups.append(OptionGroup(BEHAVIORS, behaviors=tuple(called)))
    return tuple(groups)


def _calls(option: ir.Option) -> list[tuple[str, str]]:
    called: list[tuple[str, str]] = []
    for state in option.states:
        for action in state.actions:
            if isinstance(action, ir.OptionCall) and ("o", action.option) not in called:
                called.append(("o", action.option))
            elif isinstance(action, ir.BehaviorCall) and ("b", action.behavior) not in called:
                called.append(("b", action.behavior))
    return called


_STYLE = (
    'graph [rankdir=LR, fontname="Helvetica", fontsize=12, bgcolor="transparent", nodesep=0.25, ranksep=0.5, '
    'newrank=true, labeljust=l, style="rounded,dashed", color="#9aa7b8"];\n'
    '  node [fontname="Helvetica", fontsize=12];\n'
    '  edge [fontname="Helvetica", fontsize=9, arrowsize=0.7];\n'
)


def grouped_option_graph(
    program: ir.Program, root: str | None, collapsed: Collection[str]
) -> tuple[str, tuple[OptionGroup, ...]]:
    """The DOT of the option graph below ``root``, grouped; and the groups.

    The groups named in ``collapsed`` are one node each (:data:`ALL` collapses all), the others
    clusters.
    Keys in ``collapsed`` that name no group are ignored: a reload may have removed a folder.
    """
    names = reachable_options(program, root) if root else list(program.options)
    groups = option_groups(program, names)
    closed = {g.key for g in groups} if ALL in collapsed else set(collapsed)
    option_at = {o.index: o for o in program.options.values()}
    behavior_at = {b.index: b for b in program.behaviors.values()}
    # the drawn node of each option and behavior: its own, or its collapsed group's
    shown: dict[tuple[str, int], tuple[str, str]] = {}
    for n, group in enumerate(groups):
        for kind, indices in (("o", group.options), ("b", group.behaviors)):
            for index in indices:
                element = f"{'option' if kind == 'o' else 'behavior'}_{index}"
                own = (f"{kind}{index}", element)
                shown[(kind, index)] = (f"g{n}", f"group_{n}") if group.key in closed else own
    lines = [f"digraph {quote('option_graph')} {{", "  " + _STYLE]
    for n, group in enumerate(groups):
        if group.key in closed:
            what = "basic behaviors" if group.key == BEHAVIORS else "options"
            label = f"{group.key}\\n{group.size} {what}" if group.key != BEHAVIORS else f"{group.size} {what}"
            members = [option_at[i].name for i in group.options] + [behavior_at[i].name for i in group.behaviors]
            listed = ", ".join(members[:24]) + (" …" if group.size > 24 else "")
            tooltip = f"{group.key}: {listed} (click to expand)"
            lines.append(
                f'  {quote(f"g{n}")} [id={quote(f"group_{n}")}, label="{label}", shape=folder, '
                f'style=filled, fillcolor="#e3ebf7", tooltip={quote(tooltip)}];'
            )
            continue
        lines.append(f"  subgraph {quote(f'cluster_{n}')} {{")
        lines.append(f"    id={quote(f'cluster_{n}')}; label={quote(group.key)}; tooltip={quote(group.key)};")
        for index in group.options:
            option = option_at[index]
            lines.append(
                f"    {quote(f'o{index}')} [id={quote(f'option_{index}')}, label={quote(option.name)}, shape=box, "
                f'style="rounded,filled", fillcolor="#eef3fb", tooltip={quote(option.doc or option.name)}];'
            )
        for index in group.behaviors:
            behavior = behavior_at[index]
            lines.append(
                f"    {quote(f'b{index}')} [id={quote(f'behavior_{index}')}, label={quote(behavior.name)}, "
                f'shape=ellipse, style=filled, fillcolor="#f4f4f4", tooltip={quote(behavior.doc or behavior.name)}];'
            )
        lines.append("  }")
    edges: dict[tuple[str, str], str] = {}
    for name in names:
        option = program.options[name]
        source, _ = shown[("o", option.index)]
        for kind, callee in _calls(option):
            table = program.options if kind == "o" else program.behaviors
            if callee not in table:
                continue  # a partial program: the plain graph draws these dashed
            callee_index = table[callee].index
            target, _ = shown[(kind, callee_index)]
            if source == target or (source, target) in edges:
                continue
            plain = source[0] != "g" and target[0] != "g"
            plain_id = f"call_{option.index}_{kind}{callee_index}"
            edges[(source, target)] = plain_id if plain else f"gcall_{source}_{target}"
    for (source, target), edge_id in edges.items():
        lines.append(f"  {quote(source)} -> {quote(target)} [id={quote(edge_id)}];")
    lines.append("}")
    return "\n".join(lines) + "\n", groups
