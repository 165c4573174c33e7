"""The soccer world's setup API, world commands, and a test that starts from a tick of a recording."""

from __future__ import annotations

from pathlib import Path

import pytest

from xabsl_studio.engine.testing.runner import run_case
from xabsl_studio.engine.testing.spec import parse_suite
from xabsl_studio.examples.soccer.setup import arrange, setup_from_scene
from xabsl_studio.examples.soccer.world import build_world

SOCCER = Path(__file__).resolve().parents[2] / "examples" / "soccer"


def test_arrange_places_and_sets_the_game() -> None:
    world = build_world(1, players_per_team=2)
    arrange(
        world, {"game_state": "playing", "kickoff": "red", "ball": [1000, -500], "robots": {"red2": [200, 300, 90]}}
    )
    scene = world.dynamic_scene()
    assert scene["ball"] == [1000, -500]
    assert scene["robots"][3] == [200, 300, 90.0]
    assert world.status()["game_state"] == "playing" and world.status()["kickoff_team"] == "red"
    names = [a.name for a in world.agents]
    assert setup_from_scene(scene, world.status(), names)["robots"]["red2"] == [200.0, 300.0, 90.0]


@pytest.mark.parametrize(
    ("setup", "message"),
    [
        ({"weather": "rain"}, "unknown soccer setup key(s) weather"),
        ({"game_state": "halftime"}, "game_state must be one of"),
        ({"kickoff": "blue"}, "kickoff goes with game_state"),
        ({"ball": [99999, 0]}, "is off the field"),
        ({"ball": [0, float("nan")]}, "finite numbers"),
        ({"robots": {"green1": [0, 0, 0]}}, "no robot 'green1'"),
        ({"robots": {"blue1": [0, 0]}}, "robots.blue1 must be [x, y, heading]"),
    ],
)
def test_arrange_refuses_bad_setups(setup: dict[str, object], message: str) -> None:
    world = build_world(1, players_per_team=2)
    before = world.dynamic_scene()
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)").replace("[", r"\[")):
        arrange(world, setup)
    assert world.dynamic_scene() == before  # nothing changed


def suite(body: str, tmp: Path) -> str:
    return f'[suite]\npath = "{SOCCER}"\noptions = {{ robots = 1 }}\nseed = 4\nrobot = "blue1"\n{body}'


def test_from_a_tick_of_a_recording(tmp_path: Path) -> None:
    # A failing test of a plain seeded match leaves a deterministic recording ...
    failing = suite(
        '[[test]]\nname = "rec"\nduration = 3\n[[test.expect]]\nnever = true\noption = "play_soccer"', tmp_path
    )
    [case] = parse_suite(failing, tmp_path / "a.xabsl-test.toml").cases
    result = run_case(case, tmp_path / "rec")
    assert result.status == "failed" and result.recording is not None
    # ... and a test can start from one of its ticks (re-simulated from the seed and checked).
    body = f"""
[[test]]
name = "fork"
duration = 1
from = {{ recording = "{result.recording}", tick = 30 }}
[[test.expect]]
at = 0
option = "play_soccer"
state = "init"
[[test.expect]]
name = "initial ends 1 s into the match: 0.25 s after tick 30"
within = 0.3
option = "play_soccer"
state = "ready"
"""
    [fork] = parse_suite(suite(body, tmp_path), tmp_path / "b.xabsl-test.toml").cases
    forked = run_case(fork)
    assert forked.ok, forked.report()
    # Beyond the recording: refused with the recording's message.
    [late] = parse_suite(
        suite(body.replace("tick = 30", "tick = 5000"), tmp_path), tmp_path / "c.xabsl-test.toml"
    ).cases
    refused = run_case(late)
    assert refused.status == "error" and "outside the recording" in (refused.error or "")


def test_world_commands_at_their_time(tmp_path: Path) -> None:
    errands = SOCCER.parent / "errands"
    text = f"""
[suite]
path = "{errands}"
[[test]]
name = "unknown command"
commands = [{{ at = 0.5, name = "explode" }}]
[[test.expect]]
always = true
option = "execute_plan"
"""
    [case] = parse_suite(text, tmp_path / "e.xabsl-test.toml").cases
    result = run_case(case)
    assert result.status == "error" and "command explode" in (result.error or "")
