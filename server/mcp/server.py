"""The MCP server of ``xabsl mcp``: the tools of :mod:`xabsl_studio.server.mcp.tools` over stdio.

Built on the ``mcp`` package's ``MCPServer`` (its tools' input schemas come from the signatures
below, their descriptions from the docstrings). A tool that cannot answer raises the package's
``ToolError`` with the reason, which the client receives as an error result
(``isError``) for the assistant to read; a crash is reported by the package without its text.
"""

from __future__ import annotations

from typing import Any

from mcp.server.mcpserver import MCPServer
from mcp.server.mcpserver.exceptions import ToolError

from xabsl_studio import __version__
from xabsl_studio.server.mcp import tools
from xabsl_studio.server.mcp.tools import Roots, ToolProblem

__all__ = ["build_server", "serve_stdio"]

INSTRUCTIONS = """\
Answers about XABSL behaviors (hierarchies of state machines) and recordings of their runs
(.mcap files written by `xabsl run ... --record` or the studio). A tick is given as time_s
(behavior time in seconds, as the studio's timeline shows) or seq (the tick number). Start with
`activation` to see which options and states a robot ran at a tick, then `why` for the decision
an option took and `why_not` for a state it did not go to; values are those the decision read
in that tick, `?` where it read none. `diverge` compares two runs of one seed, `profile` sums a
run up, `query` finds the ticks where an XABSL condition holds, `compile` checks a behavior set."""


def build_server(roots: Roots) -> MCPServer:
    """The server with every tool bound to ``roots``."""
    # stdout is the protocol's; the package logs each refused call to stderr at INFO: keep warnings only
    server = MCPServer("xabsl", version=__version__, instructions=INSTRUCTIONS, log_level="WARNING")

    def answer(tool: Any, *args: Any) -> dict[str, Any]:
        try:
            result: dict[str, Any] = tool(roots, *args)
        except ToolProblem as problem:
            raise ToolError(str(problem)) from None
        return result

    def compile(agents_file: str) -> dict[str, Any]:
        """Compile an XABSL behavior set (its agents file): ok, and every error and warning at file:line:col."""
        return answer(tools.compile_behavior, agents_file)

    def activation(recording: str, robot: str, time_s: float | None = None, seq: int | None = None) -> dict[str, Any]:
        """The activation path of a robot at one tick of a recording: the options with their states, by depth."""
        return answer(tools.activation, recording, robot, time_s, seq)

    def why(
        recording: str, robot: str, option: str, time_s: float | None = None, seq: int | None = None
    ) -> dict[str, Any]:
        """Why an option of a robot took its transition at a tick: each condition on the way, with its values."""
        return answer(tools.why, recording, robot, option, time_s, seq)

    def why_not(
        recording: str, robot: str, option: str, state: str, time_s: float | None = None, seq: int | None = None
    ) -> dict[str, Any]:
        """Why an option of a robot did NOT go to a state at a tick: each route there and the condition blocking it."""
        return answer(tools.why_not, recording, robot, option, state, time_s, seq)

    def diverge(a: str, b: str, robots: list[str] | None = None) -> dict[str, Any]:
        """Where two recordings of one seed first act differently: per robot the tick, both paths and both whys."""
        return answer(tools.divergence, a, b, robots)

    def profile(recording: str, robots: list[str] | None = None, top: int = 10) -> dict[str, Any]:
        """A recording summed up per robot: its top options by share of time, coverage, oscillations."""
        return answer(tools.profile_summary, recording, robots, top)

    def query(recording: str, condition: str, robot: str | None = None) -> dict[str, Any]:
        """The tick intervals of a recording where an XABSL condition holds ('ball.distance > 500 && ...')."""
        return answer(tools.query, recording, condition, robot)

    for tool in (compile, activation, why, why_not, diverge, profile, query):
        server.add_tool(tool, name=tool.__name__)
    return server


def serve_stdio(roots: Roots) -> None:
    """Serve one client on stdin/stdout until it closes them."""
    build_server(roots).run("stdio")
