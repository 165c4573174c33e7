"""The message definitions are the truth: the TypeScript is generated from them, real messages follow them."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import httpx2 as httpx
from pydantic import TypeAdapter

from tests.server.conftest import LiveServer, WsClient
from xabsl_studio.server.protocol import commands, replies
from xabsl_studio.server.protocol.tsgen import TS_FILE, generate

SERVER_MESSAGE: TypeAdapter[Any] = TypeAdapter(replies.ServerMessage)


def test_the_committed_typescript_is_generated_from_the_python_definitions() -> None:
    assert TS_FILE.read_text(encoding="utf-8") == generate(), (
        "web/src/messages.gen.ts drifted from server/protocol/: "
        "run `python -m xabsl_studio.server.protocol.tsgen --write`"
    )


def test_every_op_has_a_result_type_and_a_dataclass() -> None:
    assert set(replies.RESULTS) == set(commands.OPS)
    assert len(commands.OPS) == 26


def _check(message: dict[str, Any]) -> None:
    """``message`` validates as the ServerMessage its ``type`` names (extra keys fail)."""
    SERVER_MESSAGE.validate_python(message)


def _result(client: WsClient, op: str, **args: Any) -> Any:
    reply = client.command(op, **args)
    _check(reply)
    assert reply["ok"], reply
    if replies.RESULTS[op] is None:
        assert reply["result"] is None
    else:
        TypeAdapter(replies.RESULTS[op]).validate_python(reply["result"])
    return reply["result"]


def test_real_messages_follow_the_definitions(live_demo: LiveServer, client_for: Any, demo_dir: Path) -> None:
    client = client_for(live_demo)
    hello = client.until(lambda msg: msg["type"] == "hello")
    _check(hello)
    for _ in range(5):
        _check(client.frame_after())
    _result(client, "force_option", robot=0, option="approach_ball", params={"stop_at": 5})
    _result(client, "override_input", robot=1, symbol="ball.seen", value=True)
    frame = client.wait_frame(lambda f: "forced" in f["robots"][0] and "overrides" in f["robots"][1])
    _check(frame)
    _result(client, "explain", robot=0, option="approach_ball")
    _result(client, "pause")
    _result(client, "step", ticks=2)
    _result(client, "speed", speed=2)
    _result(client, "history", t0=0, t1=10_000)
    chunk = client.until(lambda msg: msg["type"] == "history")
    _check(chunk)
    _result(client, "status")
    _result(client, "release", robot=0)
    _result(client, "release_input", robot=1)
    _result(client, "select_agent", robot=0, agent="searcher")
    _result(client, "reset_agent", robot=0)
    _result(client, "resume")
    _result(client, "reload")
    _result(client, "reset", seed=2)
    _check(client.wait_hello("reset"))
    bad = client.command("release", robot=99)
    _check(bad)
    assert bad["ok"] is False
    path = "options/play.xabsl"
    with httpx.Client(base_url=live_demo.url) as http:
        current = http.get(f"/api/files/{path}").json()
        saved = http.put(f"/api/files/{path}", json={"text": current["text"] + "\n", "version": current["version"]})
        assert saved.status_code == 200, saved.text
    client.until(lambda msg: msg["type"] == "event" and msg["event"] == "file")
    events = [msg for msg in client.other if msg["type"] == "event"]
    assert {e["event"] for e in events} >= {"compile", "file"}  # the compile comes first
    for event in events:
        _check(event)
