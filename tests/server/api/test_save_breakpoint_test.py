"""Save as test from a breakpoint hit: the draft starts from the world at the hit's tick, asserts the
breakpoint's target, parses and passes under the behavior test runner."""

from __future__ import annotations

import gc
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import orjson
import pytest

from tests.server.conftest import LiveServer
from xabsl_studio.engine.testing.cli import main as xabsl_test
from xabsl_studio.engine.testing.runner import run_case
from xabsl_studio.engine.testing.spec import load_suite
from xabsl_studio.examples.soccer.studio import SoccerExample
from xabsl_studio.server.session.live import Session

REPO = Path(__file__).resolve().parents[3]


@pytest.fixture
def soccer(tmp_path: Path) -> Iterator[LiveServer]:
    folder = tmp_path / "soccer"
    folder.mkdir()
    for name in ("behavior", "chase"):
        shutil.copytree(REPO / "examples" / "soccer" / name, folder / name)
    example = SoccerExample(folder, players_per_team=2, half_duration_s=600)
    session = Session(example, seed=5, speed=5.0, state_dir=tmp_path / "state")
    with LiveServer(session) as server:
        yield server
    session.stop()
    del session
    gc.collect()


def _hit(client: Any) -> dict[str, Any]:
    return client.until(lambda m: m["type"] == "event" and m["event"] == "breakpoint", timeout=60)


def _robot_name(server: LiveServer, robot: int) -> str:
    generation = server.session.generation
    assert generation is not None
    agents = orjson.loads(generation.scene_bytes)["agents"]
    return str(next(a["name"] for i, a in enumerate(agents) if a.get("id", i) == robot))


def _draft(server: LiveServer, event: dict[str, Any], name: str, **extra: Any) -> httpx.Response:
    body = {
        "name": name,
        "robot": _robot_name(server, event["robot"]),
        "hit": {"program": event["program"], "breakpoint": event["breakpoint"], "seq": event["seq"]},
        "duration": 4,
        "save": True,
        **extra,
    }
    with httpx.Client(base_url=server.url, timeout=30) as http:
        return http.post("/api/tests/draft", json=body)


def test_a_draft_from_a_hit_parses_and_passes(soccer: LiveServer, client_for: Any) -> None:
    client = client_for(soccer)
    client.wait_hello("connect")
    assert client.command("set_breakpoint", kind="enter_state", option="play_soccer", state="ready")["ok"]
    event = _hit(client)
    answer = _draft(soccer, event, "enters ready")
    assert answer.status_code == 200, answer.text
    data = answer.json()
    text = data["text"]
    assert "# Saved from breakpoint `enter play_soccer.ready`" in text
    assert f"after tick {event['seq']}" in text
    file = soccer.session.example.root / data["path"]
    [case] = load_suite(file).cases
    assert {"ball", "robots", "game_state"} <= set(case.setup)
    [expect] = case.expects
    assert (expect.option, expect.state) == ("play_soccer", "ready")
    result = run_case(case)
    assert result.ok, result.report()

    # a condition of two comparisons: one symbol assertion each, and a comment that says what is lost
    assert client.command("remove_breakpoint", breakpoint=event["breakpoint"])["ok"]
    reply = client.command("set_breakpoint", kind="condition", condition="game.state == playing && ball.distance > 0")
    assert reply["ok"], reply
    assert client.command("resume")["ok"]
    event = _hit(client)
    answer = _draft(soccer, event, "starts playing")
    assert answer.status_code == 200, answer.text
    text = answer.json()["text"]
    assert "cannot say that they hold in the same tick" in text
    [case] = load_suite(soccer.session.example.root / answer.json()["path"]).cases
    assert [(e.symbol, e.comparator) for e in case.expects] == [("game.state", "equals"), ("ball.distance", "above")]
    assert case.setup["game_state"] == "playing"
    result = run_case(case)
    assert result.ok, result.report()

    # both files through `xabsl test` (the command line): exit 0, both passed
    assert xabsl_test([str(soccer.session.example.root / "tests"), "--no-recordings", "-q"]) == 0

    # a removed breakpoint, a tick the history no longer has
    assert client.command("remove_breakpoint", breakpoint=event["breakpoint"])["ok"]
    assert _draft(soccer, event, "gone", save=False).status_code == 409
    assert client.command("set_breakpoint", kind="enter_option", option="play_soccer")["ok"]
    listed = client.command("list_breakpoints")["result"]["breakpoints"]
    old = {**event, "breakpoint": listed[0]["breakpoint"], "seq": 0}
    assert _draft(soccer, old, "too old", save=False).status_code == 409
