"""``xabsl mcp`` spoken to by real clients: the ``mcp`` package's stdio client, and one written from the spec.

The server runs as its own process (``python -m xabsl_studio.server.mcp``), confined to a folder
holding two runs of one seed that differ by a known edit (tests/compare/runs.py: ``approach_ball``
goes ``near`` below 600 mm instead of 900 mm). The answers are checked against the edit and against
the recorded inputs read by the recording reader, not against the tools' own code.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import anyio
import pytest
from mcp.client.session import ClientSession
from mcp.client.stdio import StdioServerParameters, stdio_client

from tests.compare.runs import Runs, record_runs
from xabsl_studio.engine.record import Recording

TOOLS = {"compile", "activation", "why", "why_not", "diverge", "profile", "query"}


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Runs]:
    yield record_runs(tmp_path_factory.mktemp("mcp"))


def server_command(root: Path) -> list[str]:
    return [sys.executable, "-m", "xabsl_studio.server.mcp", "--root", str(root)]


def environment() -> dict[str, str]:
    return {"PYTHONPATH": os.environ.get("PYTHONPATH", "")}


def first_divergence(runs: Runs) -> tuple[int, float]:
    """The first tick where blue2's approach_ball is ``near`` in the original and not in the edited run (a scan)."""
    with Recording(runs.original) as a, Recording(runs.edited) as b:
        for va, vb in zip(a.ticks(), b.ticks(), strict=False):
            near_a = "approach_ball.near" in _states(va.agents["blue2"])
            near_b = "approach_ball.near" in _states(vb.agents["blue2"])
            if near_a != near_b:
                return va.seq, float(vb.agents["blue2"].inputs["ball.distance"])  # type: ignore[arg-type]
    raise AssertionError("the runs never differ on blue2")


def _states(agent: Any) -> set[str]:
    description = agent.program.description["options"]
    return {f"{description[n[2]]['name']}.{description[n[2]]['states'][n[3]]['name']}" for n in agent.path if n[0] == 0}


def call(session: ClientSession, name: str, **arguments: Any) -> Any:
    return session.call_tool(name, arguments)


def test_an_assistant_asks_why_not_and_where_two_runs_part(runs: Runs) -> None:
    root = runs.original.parent
    seq, distance = first_divergence(runs)
    assert 600 <= distance < 900

    async def session() -> None:
        params = StdioServerParameters(command=sys.executable, args=server_command(root)[1:], env=environment())
        async with stdio_client(params) as (read, write), ClientSession(read, write) as client:
            info = await client.initialize()
            assert info.server_info.name == "xabsl"
            assert {t.name for t in (await client.list_tools()).tools} == TOOLS

            # where the runs part: blue2's approach_ball, at the tick the scan found
            parted = await call(client, "diverge", a="original.mcap", b="edited.mcap")
            assert not parted.is_error, parted.content
            earliest = parted.structured_content["earliest"]
            assert (earliest["agent"], earliest["seq"], earliest["option"]) == ("blue2", seq, "approach_ball")
            assert "ball.distance < 600" in parted.structured_content["text"]

            # "why did blue2 not go to near?" in the edited run, at that tick
            answer = await call(
                client, "why_not", recording="edited.mcap", robot="blue2", option="approach_ball", state="near", seq=seq
            )
            result = answer.structured_content
            assert not answer.is_error and result["exact"] and not result["went"]
            (route,) = result["routes"]
            blocker = route["conditions"][route["blocked_at"]]
            assert (blocker["text"], blocker["branch"], blocker["value"]) == ("ball.distance < 600", True, False)
            shown = float(blocker["comparisons"][0].split("(")[1].split(")")[0])
            assert shown == pytest.approx(distance, abs=5e-4), "the value the decision read, as recorded"
            # ... while the original run went there, for the old threshold, from the same distance
            why = await call(client, "why", recording="original.mcap", robot="blue2", option="approach_ball", seq=seq)
            assert why.structured_content["target"] == "near"
            assert why.structured_content["conditions"][0]["text"] == "ball.distance < 900"
            # the same tick by time (the studio's timeline in seconds)
            t_s = result["t_ms"] / 1000
            path = await call(client, "activation", recording="edited.mcap", robot="blue2", time_s=t_s)
            assert path.structured_content["seq"] == seq
            assert any(line.strip() == "approach_ball.far" for line in path.structured_content["path"])

            profile = (
                await call(client, "profile", recording="original.mcap", robots=["blue2"], top=3)
            ).structured_content
            with Recording(runs.original) as recording:
                assert profile["ticks"] == len(recording)
            assert profile["agents"]["blue2"]["options"][0] == {
                **profile["agents"]["blue2"]["options"][0],
                "share": 1.0,
            }

            compiled = await call(client, "compile", agents_file="edited/behavior/agents.xabsl")
            assert compiled.structured_content["ok"] and compiled.structured_content["errors"] == 0

            # what cannot be answered is an error result with its reason, and the server goes on
            outside = await call(client, "why", recording="../elsewhere.mcap", robot="blue2", option="x", seq=1)
            assert outside.is_error and "outside the folders this server reads" in outside.content[0].text
            nobody = await call(client, "why", recording="edited.mcap", robot="blue9", option="striker", seq=seq)
            assert nobody.is_error and "no agent 'blue9'" in nobody.content[0].text
            no_tick = await call(client, "activation", recording="edited.mcap", robot="blue2")
            assert no_tick.is_error and "time_s" in no_tick.content[0].text
            no_state = await call(
                client, "why_not", recording="edited.mcap", robot="blue2", option="approach_ball", state="x", seq=seq
            )
            assert no_state.is_error and "no state x" in no_state.content[0].text

    anyio.run(session)


def test_an_assistant_queries_every_tick_where_an_option_is_in_a_state(runs: Runs) -> None:
    """The ``query`` tool: the ticks where blue2's approach_ball is in ``near``, as an independent scan finds them."""
    with Recording(runs.edited) as recording:
        expected = {v.seq for v in recording.ticks() if "approach_ball.near" in _states(v.agents["blue2"])}
    assert expected, "the run never goes near: the check would prove nothing"

    async def session() -> None:
        params = StdioServerParameters(
            command=sys.executable, args=server_command(runs.original.parent)[1:], env=environment()
        )
        async with stdio_client(params) as (read, write), ClientSession(read, write) as client:
            await client.initialize()
            answer = await call(
                client, "query", recording="edited.mcap", condition="approach_ball.state == near", robot="blue2"
            )
            assert not answer.is_error, answer.content
            intervals = answer.structured_content["intervals"]
            found = {seq for i in intervals for seq in range(i["first_seq"], i["last_seq"] + 1)}
            assert found == expected and {i["robot"] for i in intervals} == {"blue2"}
            bad = await call(client, "query", recording="edited.mcap", condition="approach_ball.state == ")
            assert bad.is_error and "1:24: syntax error" in bad.content[0].text

    anyio.run(session)


def test_compile_diagnostics_point_at_file_line_col(runs: Runs, tmp_path: Path) -> None:
    broken = tmp_path / "broken"
    (broken / "options").mkdir(parents=True)
    for path in runs.edited_behavior.rglob("*.xabsl"):
        target = broken / path.relative_to(runs.edited_behavior)
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(path.read_bytes())
    option = broken / "options" / "approach_ball.xabsl"
    option.write_text(option.read_text(encoding="utf-8").replace("goto near;", "goto nowhere;", 1), encoding="utf-8")

    async def session() -> None:
        params = StdioServerParameters(command=sys.executable, args=server_command(tmp_path)[1:], env=environment())
        async with stdio_client(params) as (read, write), ClientSession(read, write) as client:
            await client.initialize()
            result = (await call(client, "compile", agents_file="broken/agents.xabsl")).structured_content
            assert not result["ok"] and result["errors"] >= 1
            error = next(d for d in result["diagnostics"] if d["severity"] == "error")
            assert error["file"].endswith("approach_ball.xabsl") and "nowhere" in error["message"]
            line = next(i for i, text in enumerate(option.read_text().splitlines(), 1) if "goto nowhere" in text)
            assert error["span"]["line"] == line
            assert f"approach_ball.xabsl:{line}:" in result["text"]

    anyio.run(session)


def test_a_client_written_from_the_spec_over_newline_delimited_json_rpc(runs: Runs) -> None:
    """MCP's stdio transport: one JSON-RPC message per line; initialize, initialized, tools/list, tools/call."""
    process = subprocess.Popen(
        server_command(runs.original.parent),
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=environment(),
    )
    assert process.stdin is not None and process.stdout is not None

    def ask(message: dict[str, Any]) -> dict[str, Any]:
        assert process.stdin is not None and process.stdout is not None
        process.stdin.write(json.dumps(message) + "\n")
        process.stdin.flush()
        reply: dict[str, Any] = json.loads(process.stdout.readline())
        assert reply["jsonrpc"] == "2.0" and reply["id"] == message["id"]
        return reply

    try:
        hello = ask(
            {
                "jsonrpc": "2.0",
                "id": 1,
                "method": "initialize",
                "params": {
                    "protocolVersion": "2025-06-18",
                    "capabilities": {},
                    "clientInfo": {"name": "spec", "version": "1"},
                },
            }
        )
        assert hello["result"]["protocolVersion"] == "2025-06-18" and "tools" in hello["result"]["capabilities"]
        process.stdin.write(json.dumps({"jsonrpc": "2.0", "method": "notifications/initialized"}) + "\n")
        listed = ask({"jsonrpc": "2.0", "id": 2, "method": "tools/list"})
        tools = {t["name"]: t for t in listed["result"]["tools"]}
        assert set(tools) == TOOLS
        assert set(tools["why_not"]["inputSchema"]["required"]) == {"recording", "robot", "option", "state"}
        answer = ask(
            {
                "jsonrpc": "2.0",
                "id": 3,
                "method": "tools/call",
                "params": {
                    "name": "why",
                    "arguments": {"recording": "original.mcap", "robot": "blue1", "option": "play_soccer", "seq": 100},
                },
            }
        )["result"]
        assert answer["isError"] is False and answer["structuredContent"]["option"] == "play_soccer"
        assert json.loads(answer["content"][0]["text"]) == answer["structuredContent"]
        unknown = ask({"jsonrpc": "2.0", "id": 4, "method": "tools/call", "params": {"name": "kick", "arguments": {}}})
        assert ("error" in unknown) or unknown["result"]["isError"]
    finally:
        process.stdin.close()
        assert process.wait(timeout=30) == 0
        process.stdout.close()
        assert process.stderr is not None
        process.stderr.close()


def test_without_the_mcp_package_the_command_says_what_to_install() -> None:
    # `None` in sys.modules makes `import mcp` fail as a missing package does
    code = "import sys; sys.modules['mcp'] = None; from xabsl_studio.server.mcp.cli import main; sys.exit(main([]))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=environment(), timeout=60)
    assert done.returncode == 2
    assert done.stderr.strip() == "xabsl mcp: the mcp package is missing (pip install 'mcp>=2.3,<3')"
