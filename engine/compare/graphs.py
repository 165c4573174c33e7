"""The drawings of a comparison: the docs' option graph and state machines with the changes marked.

The pictures are the emitter's (:mod:`xabsl_studio.engine.emit.dot`, the ones ``xabsl docs`` and the
studio draw) of the **new** version, so a reader finds the same layout and element ids
(``option_N``, ``state_N``, ``leaf_S_L``, ``call_...``). What the old version had and the new one
lost is added to that DOT as extra statements (``removed_...`` ids, dashed); everything else is
marked after layout by a CSS class on the element Graphviz wrote for it (``added``, ``removed``,
``changed``, ``renamed``), styled by a ``<style>`` the SVG carries, so the SVG looks the same inline
in a page, in the studio and opened alone.

With the behavioral diff (:mod:`xabsl_studio.engine.profile.against`) the option graph's nodes can
also be filled by the change of their time share (:func:`share_colour`).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from xabsl_studio.engine import ir
from xabsl_studio.engine.compare.structure import COMMON, StructuralDiff
from xabsl_studio.engine.docs.graphs import inline, render_all
from xabsl_studio.engine.emit.dot import option_graph, quote, state_machine

__all__ = [
    "MARK_STYLE",
    "Drawings",
    "draw",
    "mark_svg",
    "option_graph_dot",
    "share_colour",
    "share_fills",
    "state_machine_dot",
]

#: The marks' colours (also the legend's): added, removed, changed, renamed.
COLOURS = {"added": "#1a7f37", "removed": "#cf222e", "changed": "#bf8700", "renamed": "#8250df"}

#: The class of a marked SVG's root: its own style applies inside it only, also inlined in a page.
SVG_CLASS = "xabsl-compare"
_IN = f"svg.{SVG_CLASS}"
#: The CSS every marked SVG carries.
MARK_STYLE = (
    "".join(
        f"{_IN} g.{mark} polygon, {_IN} g.{mark} ellipse, {_IN} g.{mark} path "
        f"{{ stroke: {colour}; stroke-width: 2.5px; }} "
        f"{_IN} g.{mark} text {{ fill: {colour}; font-weight: bold; }} "
        for mark, colour in COLOURS.items()
    )
    + f"{_IN} g.removed path, {_IN} g.node.removed polygon {{ stroke-dasharray: 5 3; }} "
)

_GROUP = re.compile(r'<g id="([^"]+)" class="(node|edge)">')
#: the first shape of a node group (its outline; Graphviz writes ``fill`` first)
_SHAPE = re.compile(r'<(path|polygon|ellipse) fill="[^"]*"')


def _append(dot: str, lines: Sequence[str]) -> str:
    """``dot`` with ``lines`` before its closing brace (extra nodes, edges and attributes)."""
    body = dot.rstrip()
    assert body.endswith("}"), "the emitter's DOT ends with the graph's closing brace"
    return body[:-1] + "".join(f"  {line}\n" for line in lines) + "}\n"


def share_colour(delta: float) -> str:
    """The fill of an option whose time share changed by ``delta`` (A − B, a fraction of the ticks).

    Blue for more time, rose for less, white for none; full colour at a change of 20 points.
    """
    strength = min(1.0, abs(delta) / 0.2)
    to = (47, 111, 222) if delta > 0 else (214, 51, 132)
    r, g, b = (round(255 + (c - 255) * strength * 0.75) for c in to)
    return f"#{r:02x}{g:02x}{b:02x}"


def option_graph_dot(
    diff: StructuralDiff, shares: Mapping[str, tuple[float, str]] | None = None
) -> tuple[str, dict[str, str]]:
    """The option graph of the new version, with what the old one lost; and the marks by element id.

    ``shares``: per option (new name) the change of its time share and a tooltip for it.
    """
    old, new = diff.old, diff.new
    renamed_from = {n: o for o, n in diff.option_renames.items()}
    marks: dict[str, str] = {}
    extra: list[str] = []
    for name, option in new.options.items():
        status = diff.status(name)
        if status is not None:
            marks[f"option_{option.index}"] = status
        if status == "renamed":
            extra.append(f"{quote('o:' + name)} [label={quote(f'{name} (was {renamed_from[name]})')}];")
    for name, behavior in new.behaviors.items():
        if name not in old.behaviors:
            marks[f"behavior_{behavior.index}"] = "added"

    def calls(program: ir.Program, mapping: Mapping[str, str]) -> set[tuple[str, str, str]]:
        found = set()
        for name, option in program.options.items():
            for state in option.states:
                for action in state.actions:
                    if isinstance(action, ir.OptionCall):
                        found.add((mapping.get(name, name), "o", mapping.get(action.option, action.option)))
                    elif isinstance(action, ir.BehaviorCall):
                        found.add((mapping.get(name, name), "b", action.behavior))
        return found

    before, after = calls(old, diff.option_renames), calls(new, {})
    for caller, kind, callee in sorted(after - before):
        callee_index = new.options[callee].index if kind == "o" else new.behaviors[callee].index
        marks[f"call_{new.options[caller].index}_{kind}{callee_index}"] = "added"
    removed_nodes: set[str] = set()
    for name, option in old.options.items():
        if name not in new.options and name not in diff.option_renames:
            removed_nodes.add("o:" + name)
            extra.append(
                f"{quote('o:' + name)} [id={quote(f'removed_option_{option.index}')}, label={quote(name)}, "
                f'shape=box, style="rounded,dashed", color="{COLOURS["removed"]}", tooltip="removed"];'
            )
    for name, behavior in old.behaviors.items():
        if name not in new.behaviors and any(k == "b" and c == name for _, k, c in before):
            removed_nodes.add("b:" + name)
            extra.append(
                f"{quote('b:' + name)} [id={quote(f'removed_behavior_{behavior.index}')}, label={quote(name)}, "
                f'shape=ellipse, style=dashed, color="{COLOURS["removed"]}", tooltip="removed"];'
            )
    for n, (caller, kind, callee) in enumerate(sorted(before - after)):
        if caller not in new.options and "o:" + caller not in removed_nodes:
            continue
        target = f"{kind}:{callee}"
        if kind == "o" and callee not in new.options and target not in removed_nodes:
            continue
        if kind == "b" and callee not in new.behaviors and target not in removed_nodes:
            continue
        extra.append(
            f"{quote('o:' + caller)} -> {quote(target)} [id={quote(f'removed_call_{n}')}, style=dashed, "
            f'color="{COLOURS["removed"]}", tooltip="call removed"];'
        )
    for node in removed_nodes:
        marks[f"removed_{'option' if node.startswith('o:') else 'behavior'}_{_old_index(old, node)}"] = "removed"
    for n in range(len(before - after)):
        marks[f"removed_call_{n}"] = "removed"
    for name, (_delta, tooltip) in (shares or {}).items():
        if name in new.options:
            extra.append(f"{quote('o:' + name)} [tooltip={quote(tooltip)}];")
    return _append(option_graph(new, None), extra), marks


def share_fills(program: ir.Program, shares: Mapping[str, tuple[float, str]]) -> dict[str, str]:
    """The fill of every option node (by element id) whose time share changed by ``shares[name][0]``."""
    return {
        f"option_{program.options[name].index}": share_colour(delta)
        for name, (delta, _tooltip) in shares.items()
        if name in program.options
    }


def _old_index(old: ir.Program, node: str) -> int:
    kind, name = node.split(":", 1)
    return old.options[name].index if kind == "o" else old.behaviors[name].index


def state_machine_dot(diff: StructuralDiff, name: str) -> tuple[str, dict[str, str]]:
    """The state machine of option ``name`` (new version) with its changes; and the marks by element id."""
    new_option = diff.new.options[name]
    old_name = next((o for o, n in diff.option_renames.items() if n == name), name)
    old_option = diff.old.options.get(old_name)
    marks: dict[str, str] = {}
    extra: list[str] = []
    status = diff.status(name)
    if old_option is None or status == "added":
        for state in new_option.states:
            marks[f"state_{state.index}"] = "added"
            for leaf in ir.leaves(state.decision):
                marks[f"leaf_{state.index}_{leaf.leaf}"] = "added"
        return state_machine(new_option), marks
    renames = diff.state_renames.get(name, {})
    renamed_from = {n: o for o, n in renames.items()}
    new_states = {s.name for s in new_option.states}
    for state in new_option.states:
        state_status = diff.state_status(name, state.name)
        if state_status is not None:
            marks[f"state_{state.index}"] = state_status
        if state_status == "renamed":
            extra.append(
                f"{quote('s:' + state.name)} [label={quote(f'{state.name} (was {renamed_from[state.name]})')}];"
            )
        if state_status == "added":
            for leaf in ir.leaves(state.decision):
                marks[f"leaf_{state.index}_{leaf.leaf}"] = "added"
    removed_states: dict[str, str] = {}
    for state in old_option.states:
        if state.name not in renames and state.name not in new_states:
            node = f"s:{state.name}"
            removed_states[state.name] = node
            extra.append(
                f"{quote(node)} [id={quote(f'removed_state_{state.index}')}, label={quote(state.name)}, shape=box, "
                f'style="rounded,dashed", color="{COLOURS["removed"]}", tooltip="removed"];'
            )
            marks[f"removed_state_{state.index}"] = "removed"
    old_states = {s.index: s for s in old_option.states}
    for change in diff.changes:
        if change.option != name or change.kind not in ("transition", "condition"):
            continue
        if change.change in ("added", "changed"):
            for ref in change.new_leaves:
                marks[f"leaf_{ref.state}_{ref.leaf}"] = change.change
        if change.change == "removed" or (change.kind == "transition" and change.change == "changed"):
            for ref in change.old_leaves:
                state = old_states[ref.state]
                leaf = next(t for t in ir.leaves(state.decision) if t.leaf == ref.leaf)
                source = renames.get(state.name, state.name)
                target = renames.get(leaf.target or "", leaf.target or "")
                if leaf.stay or target == source or (change.state == COMMON and source not in new_states):
                    continue
                if (source not in new_states and source not in removed_states) or (
                    target not in new_states and target not in removed_states
                ):
                    continue
                edge = f"removed_leaf_{ref.state}_{ref.leaf}"
                extra.append(
                    f"{quote('s:' + source)} -> {quote('s:' + target)} [id={quote(edge)}, style=dashed, "
                    f'color="{COLOURS["removed"]}", tooltip={quote("was: " + " && ".join(change.path or ()))}];'
                )
                marks[edge] = "removed"
    return _append(state_machine(new_option), extra), marks


def mark_svg(svg: str, marks: Mapping[str, str], fills: Mapping[str, str] | None = None) -> str:
    """``svg`` with each marked element's class extended, ``fills`` (by node id) painted, the marks' style inside.

    A fill is an inline style on the node's shape, so it holds against any page's stylesheet.
    """

    def replace(match: re.Match[str]) -> str:
        mark = marks.get(match.group(1))
        return match.group(0) if mark is None else f'<g id="{match.group(1)}" class="{match.group(2)} {mark}">'

    marked = _GROUP.sub(replace, svg)
    for node, colour in (fills or {}).items():
        start = marked.find(f'<g id="{node}" class="node')
        if start < 0:
            continue
        shape = _SHAPE.search(marked, start)
        if shape is not None:
            painted = f'<{shape.group(1)} style="fill:{colour}" fill="{colour}"'
            marked = marked[: shape.start()] + painted + marked[shape.end() :]
    start = marked.find("<svg")
    close = marked.find(">", start)
    if start < 0 or close < 0:
        return marked
    opening = marked[start:close]
    opening = opening.replace("<svg", f'<svg class="{SVG_CLASS}"', 1) if "class=" not in opening else opening
    return marked[:start] + opening + ">" + f"\n<style>{MARK_STYLE}</style>" + marked[close + 1 :]


@dataclass
class Drawings:
    """The marked SVGs of a comparison (inline markup, no XML prolog)."""

    option_graph: str
    #: per changed or added option (new name): its marked state machine
    state_machines: dict[str, str] = field(default_factory=dict)


def draw(
    diff: StructuralDiff,
    shares: Mapping[str, tuple[float, str]] | None = None,
    jobs: int | None = None,
) -> Drawings:
    """Lay out the option graph and the state machine of every changed or added option.

    Raises:
        GraphvizMissing: when ``dot`` is not installed.
        GraphLayoutError: when ``dot`` rejects a graph.
    """
    graph_dot, graph_marks = option_graph_dot(diff, shares)
    fills = share_fills(diff.new, shares) if shares else None
    names = [n for n in diff.new.options if diff.status(n) == "added"] + diff.changed_options
    names = [n for n in diff.new.options if n in set(names)]
    machines = [state_machine_dot(diff, n) for n in names]
    svgs = render_all([graph_dot, *(dot for dot, _ in machines)], jobs)
    drawings = Drawings(inline(mark_svg(svgs[0], graph_marks, fills)))
    for name, (_dot, marks), svg in zip(names, machines, svgs[1:], strict=True):
        drawings.state_machines[name] = inline(mark_svg(svg, marks))
    return drawings
