"""Pictures to take away: the option graph, a state machine, an activation path as SVG, PNG or PDF.

The DOT is the studio's and the documentation's (:mod:`xabsl_studio.engine.emit.dot`), so a
picture looks like what the user saw; this module only adds what a picture on paper needs and
runs Graphviz:

* a white background instead of the studio's transparent one (a PNG pasted on a dark wiki page
  stays readable), and a title;
* for an activation path (what one robot ran in one tick): the options and basic behaviors that
  ran filled, each option's active state under its name, the calls that were made drawn thick;
  in a state machine, the active state and the transition that fired.

Attributes are added as DOT statements after the emitter's (a node statement naming an existing
node merges attributes); the emitter's edge statements carry ids (``call_<caller>_o<callee>``,
``leaf_<state>_<leaf>``) and get their extra attributes by id.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

from xabsl_studio.engine import ir
from xabsl_studio.engine.emit.dot import GraphvizMissing, option_graph, quote, state_machine
from xabsl_studio.engine.errors import EmitError

#: Picture formats and their media types.
FORMATS: dict[str, str] = {"svg": "image/svg+xml", "png": "image/png", "pdf": "application/pdf"}
#: Pixels per inch of a PNG: sharp enough for a slide or a paper, not a poster.
PNG_DPI = 144
#: What ran: fill and line colours (the studio's active path colours, darker for print).
ACTIVE_FILL, ACTIVE_LINE = "#ffe08a", "#b8860b"


class PictureError(EmitError, RuntimeError):
    """Graphviz could not draw a picture (the message quotes it)."""


def _add(dot: str, statements: Iterable[str]) -> str:
    body = dot.rstrip()
    assert body.endswith("}"), "the emitter's DOT ends with the graph's closing brace"
    return body[:-1] + "".join(f"  {s}\n" for s in statements) + "}\n"


def for_paper(dot: str, title: str | None = None) -> str:
    """``dot`` with a white background and, if given, a title above the graph."""
    statements = ['graph [bgcolor="white", pad=0.2];']
    if title:
        statements.append(f'graph [label={quote(title)}, labelloc="t", labeljust="l", fontsize=14];')
    return _add(dot, statements)


def _with_edge_attributes(dot: str, ids: set[str], attributes: str) -> str:
    """Add ``attributes`` to the edge statements whose ``id`` is in ``ids``."""
    if not ids:
        return dot

    def edit(match: re.Match[str]) -> str:
        return match.group(0)[:-2] + f", {attributes}];" if match.group(1) in ids else match.group(0)

    return re.sub(r'-> [^\n]*\[id="([A-Za-z0-9_]+)"[^\n]*\];', edit, dot)


@dataclass(frozen=True, slots=True)
class Ran:
    """What ran in one tick: options with their active state, basic behaviors, the calls made."""

    states: dict[str, str]
    behaviors: frozenset[str]
    #: (caller option, "o" or "b", callee name)
    calls: frozenset[tuple[str, str, str]]
    #: option -> (state whose decision ran, the leaf that fired)
    decisions: dict[str, tuple[str, int]]

    @classmethod
    def from_path(cls, program: ir.Program, path: Sequence[Sequence[Any]]) -> Ran:
        """What ran in a compact activation path (a frame's or a recording's ``path``) of ``program``.

        Nodes come in pre-order with their depth (docs/protocol.md, the path's layout): an option
        ``[0, depth, option id, state, option time, state time, decided in, leaf, params]``, a
        basic behavior ``[1, depth, behavior id, time, params]``; the caller of a node is the last
        option one level up.

        Raises:
            ValueError: a node naming an option, state or behavior ``program`` does not have.
        """
        options = {o.index: o for o in program.options.values()}
        behaviors = {b.index: b for b in program.behaviors.values()}
        states: dict[str, str] = {}
        decisions: dict[str, tuple[str, int]] = {}
        ran_behaviors: set[str] = set()
        calls: set[tuple[str, str, str]] = set()
        callers: list[str] = []  # the option at each depth on the way down
        try:
            for node in path:
                kind, depth, index = int(node[0]), int(node[1]), int(node[2])
                del callers[depth:]
                caller = callers[depth - 1] if 0 < depth <= len(callers) else None
                if kind == 0:
                    option = options[index]
                    states[option.name] = option.states[int(node[3])].name
                    decisions[option.name] = (option.states[int(node[6])].name, int(node[7]))
                    if caller is not None:
                        calls.add((caller, "o", option.name))
                    callers.append(option.name)
                else:
                    behavior = behaviors[index].name
                    ran_behaviors.add(behavior)
                    if caller is not None:
                        calls.add((caller, "b", behavior))
        except (KeyError, IndexError, TypeError, ValueError) as error:
            raise ValueError(f"the path does not fit this behavior ({type(error).__name__}: {error})") from None
        return cls(states, frozenset(ran_behaviors), frozenset(calls), decisions)


def activation_graph(program: ir.Program, ran: Ran, root: str | None, title: str | None = None) -> str:
    """The option graph below ``root`` with what ran emphasized (see the module docstring)."""
    dot = option_graph(program, root)
    statements: list[str] = []
    for option, state in ran.states.items():
        if option in program.options:
            label = quote(option + "\n▸ " + state)
            statements.append(
                f"{quote('o:' + option)} [label={label}, fillcolor={quote(ACTIVE_FILL)}, "
                f"color={quote(ACTIVE_LINE)}, penwidth=2.2];"
            )
    for behavior in sorted(ran.behaviors):
        if behavior in program.behaviors:
            statements.append(
                f"{quote('b:' + behavior)} [fillcolor={quote(ACTIVE_FILL)}, color={quote(ACTIVE_LINE)}, penwidth=2.2];"
            )
    ids = set()
    for caller, kind, callee in ran.calls:
        if caller not in program.options:
            continue
        callees = program.options if kind == "o" else program.behaviors
        found = callees.get(callee)
        if found is not None:
            index = found.index
            ids.add(f"call_{program.options[caller].index}_{kind}{index}")
    dot = _with_edge_attributes(dot, ids, f"color={quote(ACTIVE_LINE)}, penwidth=2.6")
    return for_paper(_add(dot, statements), title)


def activation_machine(option: ir.Option, ran: Ran | None, title: str | None = None) -> str:
    """The state machine of ``option``; with ``ran``, its active state and the transition that fired."""
    dot = state_machine(option)
    state = ran.states.get(option.name) if ran is not None else None
    if ran is None or state is None:
        return for_paper(dot, title)
    statements = [f"{quote('s:' + state)} [fillcolor={quote(ACTIVE_FILL)}, color={quote(ACTIVE_LINE)}, penwidth=2.4];"]
    decided_in, leaf = ran.decisions.get(option.name, ("", -1))
    by_name = {s.name: s for s in option.states}
    ids = {f"leaf_{by_name[decided_in].index}_{leaf}"} if decided_in in by_name else set()
    dot = _with_edge_attributes(dot, ids, f"color={quote(ACTIVE_LINE)}, penwidth=2.6, fontcolor={quote(ACTIVE_LINE)}")
    return for_paper(_add(dot, statements), title)


def render(dot: str, format: str, timeout: float = 60.0) -> bytes:
    """Lay out ``dot`` with Graphviz and return the picture in ``format`` (a key of :data:`FORMATS`).

    Raises:
        ValueError: an unknown format.
        GraphvizMissing: ``dot`` is not installed.
        PictureError: Graphviz failed or took longer than ``timeout`` seconds.
    """
    if format not in FORMATS:
        raise ValueError(f"unknown picture format {format!r} ({', '.join(FORMATS)})")
    executable = shutil.which("dot")
    if executable is None:
        raise GraphvizMissing("Graphviz 'dot' is not installed (Debian: apt-get install graphviz)")
    command = [executable, f"-T{format}"]
    if format == "png":
        command.append(f"-Gdpi={PNG_DPI}")
    try:
        result = subprocess.run(command, input=dot.encode("utf-8"), capture_output=True, timeout=timeout, check=True)
    except subprocess.CalledProcessError as error:
        detail = error.stderr.decode("utf-8", "replace").strip() if error.stderr else str(error)
        raise PictureError(f"Graphviz could not draw the picture: {detail}") from None
    except subprocess.TimeoutExpired:
        raise PictureError(f"Graphviz took longer than {timeout:g} s") from None
    return result.stdout
