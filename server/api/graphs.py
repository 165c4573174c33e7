"""Option-graph and state-machine pictures: DOT from ``xabsl_studio.engine.emit.dot``, SVG from Graphviz, cached.

Laying out a graph costs tens of milliseconds of ``dot``; the picture only changes when the DOT
text changes, so SVGs are cached by a hash of the DOT source (which is also the ETag). The cache
is a small LRU: a hundred options after a few edits stay well under a few megabytes.
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict

from xabsl_studio.engine.emit.dot import option_graph, render_svg, state_machine
from xabsl_studio.engine.emit.groups import OptionGroup, grouped_option_graph
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.server.protocol.errors import ServerError


class GraphError(ServerError, LookupError):
    """No such agent or option in the program."""


class GraphCache:
    """SVG text by DOT hash (thread safe; renders outside the lock)."""

    def __init__(self, capacity: int = 256) -> None:
        self.capacity = capacity
        self._svgs: OrderedDict[str, str] = OrderedDict()
        self._lock = threading.Lock()
        self.renders = 0

    def svg(self, dot: str) -> tuple[str, str]:
        """``(svg, etag)`` of a DOT source."""
        digest = hashlib.sha256(dot.encode("utf-8")).hexdigest()[:24]
        with self._lock:
            cached = self._svgs.get(digest)
            if cached is not None:
                self._svgs.move_to_end(digest)
                return cached, digest
        svg = render_svg(dot)
        with self._lock:
            self.renders += 1
            self._svgs[digest] = svg
            while len(self._svgs) > self.capacity:
                self._svgs.popitem(last=False)
        return svg, digest


def graph_root(program: Program, agent: str | None, root: str | None = None) -> str | None:
    """The option the graph starts at, None for a program without agents (all options).

    ``root`` (a robot's forced root), else the root of XABSL agent ``agent`` (default: the first).
    """
    if root is not None:
        if root not in program.options:
            raise GraphError(f"no option {root!r} in this behavior")
        return root
    if not program.agents:
        return None
    chosen = next((a for a in program.agents if a.name == agent), None) if agent else program.agents[0]
    if chosen is None:
        raise GraphError(f"no agent {agent!r} in this behavior")
    return chosen.root


def option_graph_dot(program: Program, agent: str | None, root: str | None = None) -> str:
    """The DOT of the option graph below the root of XABSL agent ``agent`` (default: the first).

    ``root``: below that option instead (a robot's forced root).
    """
    return option_graph(program, graph_root(program, agent, root))


def grouped_graph_dot(
    program: Program, agent: str | None, root: str | None, collapsed: list[str]
) -> tuple[str, tuple[OptionGroup, ...]]:
    """The grouped option graph (folders as clusters, ``collapsed`` ones as one node) and its groups."""
    return grouped_option_graph(program, graph_root(program, agent, root), collapsed)


def state_machine_dot(program: Program, option: str) -> str:
    """The DOT of one option's state machine; ``option`` is a name or an integer id."""
    found = program.options.get(option)
    if found is None and option.isdigit():
        found = next((o for o in program.options.values() if o.index == int(option)), None)
    if found is None:
        raise GraphError(f"no option {option!r} in this behavior")
    return state_machine(found)
