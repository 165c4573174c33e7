"""IR -> Graphviz DOT: the option graph of an agent and the state machine of each option.

Every node and edge carries an ``id`` built from IR indices, so the SVG that ``dot -Tsvg``
renders has element ids the studio can address to highlight the live activation path without
relayouting (the UI toggles CSS classes on these ids):

* option graph: ``option_<option index>``, ``behavior_<basic behavior index>``,
  edges ``call_<caller index>_<o|b><callee index>``;
* state machine: ``state_<state index>``, ``leaf_<state index>_<leaf id>`` for each transition
  (one edge per decision-tree leaf that changes the state), ``initial`` for the entry arrow.

Ids use underscores because Graphviz writes ``-`` in ids as the entity ``&#45;``.

The renderers return DOT text (data first, as py_trees' ``dot_tree`` returns a graph); running
``dot`` is the caller's business (:func:`render_svg`).
"""

from __future__ import annotations

import shutil
import subprocess

from xabsl_studio.engine import ir
from xabsl_studio.engine.errors import EmitError

_GRAPH_STYLE = (
    'graph [rankdir=LR, fontname="Helvetica", fontsize=11, bgcolor="transparent", nodesep=0.25, ranksep=0.45];\n'
    '  node [fontname="Helvetica", fontsize=11];\n'
    '  edge [fontname="Helvetica", fontsize=9, arrowsize=0.7];\n'
)


def quote(text: str) -> str:
    """A DOT string literal."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def _shorten(text: str, limit: int = 48) -> str:
    return text if len(text) <= limit else text[: limit - 1] + "…"


def reachable_options(program: ir.Program, root: str) -> list[str]:
    """The options reachable from ``root`` through subsequent-option calls, in IC order."""
    seen: set[str] = set()
    stack = [root]
    while stack:
        name = stack.pop()
        if name in seen or name not in program.options:
            continue
        seen.add(name)
        for state in program.options[name].states:
            stack.extend(a.option for a in state.actions if isinstance(a, ir.OptionCall))
    return [name for name in program.options if name in seen]


def option_graph(program: ir.Program, root: str | None = None) -> str:
    """The option graph (options and basic behaviors, edges for calls) as DOT.

    Args:
        program: the checked program.
        root: restrict to what this option reaches (an agent's root); all options if None.
    """
    names = reachable_options(program, root) if root else list(program.options)
    lines = ["digraph option_graph {", "  " + _GRAPH_STYLE]
    behaviors: dict[str, ir.BasicBehavior] = {}
    edges: list[str] = []
    # A partial program (a behavior with errors, xabsl_studio.engine.lang.Compilation.partial) lacks the options
    # of files that do not parse: they are drawn dashed, so the graph still shows who calls them.
    missing: list[str] = [root] if root and root not in program.options else []
    for name in names:
        option = program.options[name]
        tooltip = option.doc or name
        lines.append(
            f"  {quote('o:' + name)} [id={quote(f'option_{option.index}')}, label={quote(name)}, "
            f'shape=box, style="rounded,filled", fillcolor="#eef3fb", tooltip={quote(tooltip)}];'
        )
        called: list[tuple[str, str]] = []
        for state in option.states:
            for action in state.actions:
                if isinstance(action, ir.OptionCall) and ("o", action.option) not in called:
                    called.append(("o", action.option))
                elif isinstance(action, ir.BehaviorCall) and ("b", action.behavior) not in called:
                    called.append(("b", action.behavior))
        for kind, callee in called:
            if kind == "o" and callee not in program.options:
                if callee not in missing:
                    missing.append(callee)
                edges.append(f"  {quote('o:' + name)} -> {quote('o:' + callee)} [style=dashed];")
                continue
            if kind == "o":
                callee_index = program.options[callee].index
                target = quote("o:" + callee)
            else:
                behavior = program.behaviors[callee]
                behaviors[callee] = behavior
                callee_index = behavior.index
                target = quote("b:" + callee)
            edge_id = f"call_{option.index}_{kind}{callee_index}"
            edges.append(f"  {quote('o:' + name)} -> {target} [id={quote(edge_id)}];")
    for name, behavior in behaviors.items():
        lines.append(
            f"  {quote('b:' + name)} [id={quote(f'behavior_{behavior.index}')}, label={quote(name)}, "
            f'shape=ellipse, style=filled, fillcolor="#f4f4f4", tooltip={quote(behavior.doc or name)}];'
        )
    for name in missing:
        lines.append(
            f"  {quote('o:' + name)} [id={quote('missing_' + name)}, label={quote(name + ' (does not compile)')}, "
            f'shape=box, style="rounded,dashed", color="#c0392b", tooltip="this option\'s file has errors"];'
        )
    lines.extend(edges)
    lines.append("}")
    return "\n".join(lines) + "\n"


def state_machine(option: ir.Option) -> str:
    """The state machine of one option as DOT: states, and one edge per state-changing leaf."""
    lines = [f"digraph {quote('option ' + option.name)} {{", "  " + _GRAPH_STYLE, "  graph [ordering=out];"]
    lines.append('  "__initial" [id="initial", shape=point, width=0.12, label=""];')
    lines.append("  node [fontsize=14];")  # state names: legible at a smaller zoom than the labels
    for state in option.states:
        calls = [
            a.option if isinstance(a, ir.OptionCall) else a.behavior
            for a in state.actions
            if isinstance(a, ir.OptionCall | ir.BehaviorCall)
        ]
        label = state.name if not calls else f"{state.name}\\n→ {_shorten(', '.join(calls), 32)}"
        shape = "doublecircle" if state.target else "circle" if len(state.name) < 4 and not calls else "box"
        style = '"rounded,filled"' if shape == "box" else "filled"
        extra = ", peripheries=2" if state.target and shape == "box" else ""
        lines.append(
            f'  {quote("s:" + state.name)} [id={quote(f"state_{state.index}")}, label="{_escape_label(label)}", '
            f'shape={shape}, style={style}, fillcolor="#ffffff"{extra}, tooltip={quote(state.doc or state.name)}];'
        )
    initial = option.state(option.initial_state) if option.initial_state in {s.name for s in option.states} else None
    if initial is not None:
        lines.append(f'  "__initial" -> {quote("s:" + initial.name)} [id="initial_edge"];')
    for state in option.states:
        # Edges in decision order with ``ordering=out``: the transitions of a state leave it in the
        # order its decision tries them (top to bottom), each label numbered by that order.
        leaves = [
            leaf
            for leaf in ir.leaves(state.decision)
            if leaf.target is not None and leaf.target != state.name and leaf.target in {s.name for s in option.states}
        ]
        for number, leaf in enumerate(leaves, start=1):
            assert leaf.target is not None
            path = ir.leaf_path(state.decision, leaf.leaf)
            condition = " && ".join(node.text if taken else f"!({node.text})" for node, taken in path)
            large = len(option.states) > _LARGE_MACHINE
            label = _transition_label(path, number if len(leaves) > 1 else None, _LARGE_LABEL if large else _LABEL_LINE)
            lines.append(
                f"  {quote('s:' + state.name)} -> {quote('s:' + leaf.target)} "
                f"[id={quote(f'leaf_{state.index}_{leaf.leaf}')}, {'xlabel' if large else 'label'}={quote(label)}, "
                f"tooltip={quote(f'{number}. {condition}' if len(leaves) > 1 else condition or 'always')}];"
            )
    lines.append("}")
    return "\n".join(lines) + "\n"


def _transition_label(path: list[tuple[ir.If, bool]], number: int | None = None, limit: int = 0) -> str:
    """An edge's label: the conditions that must hold, numbered by decision order (tooltip: the path).

    Not the negations of the ifs before the leaf: they made every label of a state start alike.
    A condition longer than a line is cut at a word with "…": long labels tangled big machines
    (issue 31), and the tooltip and the option view's transition list show it whole.
    """
    limit = limit or _LABEL_LINE
    taken = [node.text for node, went in path if went]
    text = " && ".join(taken) if taken else ("else" if path else "always")
    if number is not None:
        text = f"{number}. {text}"
    if len(text) <= limit:
        return text
    cut = text[: limit - 2]
    if " " in cut:
        cut = cut[: cut.rindex(" ")]
    return cut.rstrip(" &|(") + " …"


#: Characters of a transition label in a state machine (one line).
_LABEL_LINE = 36
#: Above this many states a machine's labels are shorter still (the number and a word or two)
#: and placed after the layout (``xlabel``): as part of the layout, label text widened every rank
#: it crossed and a 30-state machine took ``dot`` 7 s instead of 0.6 s. The option view lists
#: the conditions whole.
_LARGE_MACHINE = 12
_LARGE_LABEL = 20


def _escape_label(text: str) -> str:
    return text.replace('"', '\\"')


class GraphvizMissing(EmitError, RuntimeError):
    """The Graphviz ``dot`` program is not installed."""


def render_svg(dot_source: str, timeout: float = 20.0) -> str:
    """Lay out ``dot_source`` with Graphviz ``dot`` and return the SVG text.

    Raises:
        GraphvizMissing: when ``dot`` is not on the PATH.
        subprocess.CalledProcessError: when ``dot`` rejects the input.
    """
    executable = shutil.which("dot")
    if executable is None:
        raise GraphvizMissing("Graphviz 'dot' is not installed (Debian: apt-get install graphviz)")
    result = subprocess.run(
        [executable, "-Tsvg"], input=dot_source.encode("utf-8"), capture_output=True, timeout=timeout, check=True
    )
    return result.stdout.decode("utf-8")
