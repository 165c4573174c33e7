"""The websocket ``query`` command: a replay answers over its recording, a live session refuses."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from pydantic import TypeAdapter

from tests.server.conftest import LiveServer
from xabsl_studio.engine.query import query_recording
from xabsl_studio.server.protocol.replies import QueryAnswer
from xabsl_studio.server.session.live import Session
from xabsl_studio.server.session.replay import ReplaySession

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 2 v 2 soccer match of 20 s recorded headless by the command line."""
    path = tmp_path_factory.mktemp("query") / "match.mcap"
    command = [sys.executable, "-m", "xabsl_studio.engine.cli", "run", "examples/soccer", "--duration", "20"]
    command += ["--players", "2", "--record", str(path)]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    subprocess.run(command, cwd=ROOT, env=env, check=True, capture_output=True)
    return path


@pytest.fixture
def replay(recorded: Path) -> Iterator[LiveServer]:
    with LiveServer(ReplaySession(recorded)) as server:
        yield server


def test_a_replay_answers_the_intervals_of_its_recording(replay: LiveServer, client_for: Any, recorded: Path) -> None:
    client = client_for(replay)
    client.frame_after()
    names = [r["name"] for r in client.hello["structure"]["robots"]]
    for condition in ("kick.active", "ball.distance < 400 && game.state == playing", "striker.state == approach"):
        reply = client.command("query", condition=condition)
        assert reply["ok"], reply
        result = reply["result"]
        TypeAdapter(QueryAnswer).validate_python(result)  # the wire shape is the typed one
        expected = query_recording(recorded, condition)
        assert expected.intervals, condition
        assert [(i["name"], i["first_seq"], i["last_seq"], i["first_t"], i["last_t"]) for i in result["intervals"]] == [
            (i.robot, i.first_seq, i.last_seq, i.first_t_ms, i.last_t_ms) for i in expected.intervals
        ]
        assert all(names[i["robot"]] == i["name"] for i in result["intervals"])
        assert (result["ticks"], result["matched"], result["unknown"]) == (
            expected.ticks,
            expected.matched,
            expected.unknown,
        )
        assert result["skipped"] == expected.skipped


def test_one_robot_and_refusals(replay: LiveServer, client_for: Any) -> None:
    client = client_for(replay)
    client.frame_after()
    names = [r["name"] for r in client.hello["structure"]["robots"]]
    robot = names.index("red2")
    reply = client.command("query", condition="kick.active", robot=robot)
    assert reply["ok"] and {i["name"] for i in reply["result"]["intervals"]} == {"red2"}
    bad = client.command("query", condition="striker.state == kik")
    assert not bad["ok"] and bad["error"].startswith("condition: 1:18: option striker has no state 'kik'")
    nobody = client.command("query", condition="kick.active", robot=77)
    assert not nobody["ok"] and "no XABSL robot 77" in nobody["error"]
    typo = client.command("query", condition="kick.active", robots=[1])
    assert not typo["ok"]  # an argument the command does not have is an error, not ignored


def _runs(ticks: list[dict[str, Any]], check: Any) -> list[tuple[str, int, int]]:
    """(robot, first seq, last seq) of the runs of consecutive ticks where ``check(robot dict)`` holds."""
    found: list[tuple[str, int, int]] = []
    names = sorted({r["name"] for tick in ticks for r in tick["robots"] if r.get("path")})
    for name in names:
        start = last = None
        for tick in [*ticks, None]:
            robot = None if tick is None else next((r for r in tick["robots"] if r["name"] == name), None)
            if tick is not None and robot is not None and robot.get("path") and check(robot):
                if start is not None and tick["seq"] == last + 1:  # type: ignore[operator]
                    last = tick["seq"]
                    continue
                if start is not None:
                    found.append((name, start, last))  # type: ignore[arg-type]
                start = last = tick["seq"]
                continue
            if start is not None:
                found.append((name, start, last))  # type: ignore[arg-type]
            start = last = None
    return sorted(found, key=lambda r: (r[1], names.index(r[0])))


def test_a_live_session_answers_over_its_history(soccer_session: Session, client_for: Any) -> None:
    """Checked against the REST activation log (``/api/log``: the ring with names), read by an HTTP client."""
    with LiveServer(soccer_session) as server:
        client = client_for(server)
        client.wait_frame(lambda f: f["seq"] >= 700, timeout=120)
        assert client.command("pause")["ok"]
        with urllib.request.urlopen(server.url + "/api/log", timeout=60) as response:
            ticks = [json.loads(line) for line in response.read().splitlines()]
        assert len(ticks) > 600
        program = client.program(0)
        playing = next(e["elements"] for e in program["enums"] if e["name"] == "game.state").index("game.state.playing")

        def state(robot: dict[str, Any], option: str) -> str | None:
            return next((n["state"] for n in robot["path"] if n.get("option") == option), None)

        cases = {
            "play_soccer.state == ready": lambda r: state(r, "play_soccer") == "ready",
            "ball.distance < 1500 && game.state == playing": lambda r: (
                r["inputs"]["ball.distance"] < 1500 and r["inputs"]["game.state"] == playing
            ),
            "go_to_position.active": lambda r: state(r, "go_to_position") is not None,
        }
        names = [r["name"] for r in client.hello["structure"]["robots"]]
        for condition, check in cases.items():
            reply = client.command("query", condition=condition)
            assert reply["ok"], reply
            TypeAdapter(QueryAnswer).validate_python(reply["result"])
            shown = [(i["name"], i["first_seq"], i["last_seq"]) for i in reply["result"]["intervals"]]
            home = {n for n in names if n.startswith("blue")}
            expected = _runs(ticks, check)
            if condition != "ball.distance < 1500 && game.state == playing":
                expected = [e for e in expected if e[0] in home]  # the chase team has no such option
            assert shown == expected, condition
            assert shown, condition
        bad = client.command("query", condition="ball.distance >")
        assert not bad["ok"] and bad["error"].startswith("condition: 1:16: ")
