"""The websocket ``query`` command: a replay answers over its recording, a live session refuses."""

from __future__ import annotations

import os
import subprocess
import sys
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


def test_a_live_session_refuses_and_says_where_to_go(soccer_session: Session, client_for: Any) -> None:
    with LiveServer(soccer_session) as server:
        client = client_for(server)
        client.frame_after()
        reply = client.command("query", condition="kick.active")
        assert not reply["ok"] and "query answers over a recording" in reply["error"]
