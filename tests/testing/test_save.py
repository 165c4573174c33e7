""" "Save as test": the draft is a valid suite that reproduces the tester's situation and passes."""

from __future__ import annotations

import gc
import shutil
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from tests.server.conftest import LiveServer
from xabsl_studio.engine.runtime.breakpoints import Breakpoint
from xabsl_studio.engine.testing.runner import run_case
from xabsl_studio.engine.testing.save import DraftError, draft_file_name, draft_test, hit_expects, toml_value
from xabsl_studio.engine.testing.spec import load_suite
from xabsl_studio.examples.soccer.studio import SoccerExample
from xabsl_studio.server.session.live import Session

REPO = Path(__file__).resolve().parents[2]


def test_toml_values_and_names() -> None:
    assert toml_value({"a b": [1, 2.5, True], "c": 'x"y'}) == '{ "a b" = [1, 2.5, true], c = "x\\"y" }'
    assert draft_file_name("Goalie clears!") == "goalie_clears.xabsl-test.toml"
    with pytest.raises(DraftError):
        toml_value(float("nan"))
    with pytest.raises(DraftError):
        draft_file_name("!!!")


def test_draft_reproduces_a_forced_option(tmp_path: Path) -> None:
    behavior = REPO / "tests" / "testing" / "behavior"
    text = draft_test(
        name="helper turns",
        robot="robot1",
        tests_folder=tmp_path,
        example_path=behavior,
        world=None,
        options={"robots": 1},
        seed=4,
        setup=None,
        force=("option", "helper", {"rate": 20}),
        overrides={"go": True},
        active=[("helper", "turning")],
        behaviors=["turn"],
        duration=2.0,
    )
    file = tmp_path / "helper.xabsl-test.toml"
    file.write_text(text)
    [case] = load_suite(file).cases
    assert case.force == ("option", "helper", {"rate": 20})
    assert case.inputs == ((0, {"go": True}),)
    result = run_case(case)
    assert result.ok, result.report()


@pytest.fixture
def soccer_server(tmp_path: Path) -> Iterator[LiveServer]:
    folder = tmp_path / "soccer"
    folder.mkdir()
    for name in ("behavior", "chase"):
        shutil.copytree(REPO / "examples" / "soccer" / name, folder / name)
    session = Session(SoccerExample(folder, players_per_team=2, half_duration_s=600), seed=5, speed=5.0)
    with LiveServer(session) as server:
        yield server
    session.stop()
    del session
    gc.collect()


def test_endpoint_saves_a_test_that_passes(soccer_server: LiveServer) -> None:
    deadline = time.monotonic() + 20
    while soccer_server.session.ring.latest is None or soccer_server.session.generation is None:
        assert time.monotonic() < deadline, "no frame from the simulation"
        time.sleep(0.05)
    body = {
        "name": "blue2 walks to a position",
        "robot": "blue2",
        "force": {"kind": "option", "name": "go_to_position", "params": {"x": -1000, "y": 500, "rot": 0}},
        "active": [["go_to_position", "walk"]],
        "behaviors": ["walk_to"],
        "duration": 3,
        "save": True,
    }
    with httpx.Client(base_url=soccer_server.url, timeout=20) as client:
        answer = client.post("/api/tests/draft", json=body)
        assert answer.status_code == 200, answer.text
        data = answer.json()
        assert data["saved"] and data["path"] == "tests/blue2_walks_to_a_position.xabsl-test.toml"
        again = client.post("/api/tests/draft", json=body)
        assert again.status_code == 409
        assert client.post("/api/tests/draft", json={**body, "robot": "green7"}).status_code == 409
        assert client.post("/api/tests/draft", json={**body, "duration": -1}).status_code == 422
    file = soccer_server.session.example.root / data["path"]
    assert file.read_text() == data["text"]
    [case] = load_suite(file).cases
    assert set(case.setup) >= {"game_state", "ball", "robots"}
    assert case.force is not None and case.force[1] == "go_to_position"
    result = run_case(case)
    assert result.ok, result.report()


def test_a_breakpoint_becomes_what_the_format_can_assert() -> None:
    def expects(**fields: object) -> tuple[list[dict[str, object]], list[str]]:
        return hit_expects(Breakpoint(id=1, **fields), 4.0)  # type: ignore[arg-type]

    assert expects(kind="enter_option", option="striker") == ([{"within": 4.0, "option": "striker"}], [])
    assert expects(kind="enter_state", option="striker", state="kick")[0] == [
        {"within": 4.0, "option": "striker", "state": "kick"}
    ]
    blocks, notes = expects(kind="leaf", option="striker", state="kick", leaf=2)
    assert blocks == [{"within": 4.0, "option": "striker", "state": "kick"}] and "leaf 2" in notes[0]
    blocks, notes = expects(kind="leave_state", option="striker", state="kick")
    assert blocks == [] and "leaving striker.kick" in notes[0]
    assert expects(kind="condition", condition="ball.distance <= 300")[0] == [
        {"within": 4.0, "symbol": "ball.distance", "between": [-1e300, 300]}
    ]
    assert expects(kind="condition", condition="!ball.seen")[0] == [
        {"within": 4.0, "symbol": "ball.seen", "equals": False}
    ]
    blocks, notes = expects(kind="condition", condition="role == role.striker && ball.x > -1.5")
    assert blocks == [
        {"within": 4.0, "symbol": "role", "equals": "role.striker"},
        {"within": 4.0, "symbol": "ball.x", "above": -1.5},
    ]
    assert "same tick" in notes[1]
    for condition in ("ball.x + ball.y > 3", "a > 1 || b > 1", "(a > 1)", "role < role.striker"):
        blocks, notes = expects(kind="condition", condition=condition)
        assert blocks == [] and condition.split()[0] in notes[0], condition


def test_a_draft_from_a_hit_says_what_it_cannot_assert(tmp_path: Path) -> None:
    point = Breakpoint(id=3, kind="leave_option", option="helper")
    text = draft_test(
        name="helper stops",
        robot="robot1",
        tests_folder=tmp_path,
        example_path=REPO / "tests" / "testing" / "behavior",
        world=None,
        options={},
        seed=1,
        setup=None,
        force=None,
        overrides={},
        active=[("helper", "turning")],
        behaviors=[],
        hit=(point, "robot1", 120, 1200),
    )
    assert text.startswith("# Saved from breakpoint `leave helper` that hit on robot1 after tick 120 (t = 1.2 s)")
    assert '# the breakpoint waited for leaving helper; a test cannot assert "stops being active"' in text
    assert 'option = "helper"\nstate = "turning"' in text  # what was active stays the starting point
