"""Forks of a recorded match: with the unchanged behavior exactly the recording, edited it differs."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from xabsl_studio.engine.host import BehaviorLoop
from xabsl_studio.engine.record import Recorder, Recording, RecordingError
from xabsl_studio.engine.record.fork import resimulate, switch_programs
from xabsl_studio.engine.record.writer import engines_of
from xabsl_studio.examples.soccer.run import DEFAULT_AWAY, DEFAULT_HOME, build_world, load_team

TICKS = 800  # into PLAYING (pre-game is about 16 s = 640 ticks)
FORK_AT = 700
SEED = 9


def key_of(agent: object) -> str:
    return ("behavior", "chase")[agent.team_index]  # type: ignore[attr-defined]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("fork") / "match.mcap"
    world = build_world(SEED, load_team(DEFAULT_HOME), load_team(DEFAULT_AWAY), players=2)
    recorder = Recorder.for_world(path, world, key_of, example="soccer", behavior_hz=40, physics_hz=120)
    loop = BehaviorLoop(world)
    for _ in range(TICKS):
        now = loop.now_ms
        loop.tick()
        recorder.tick(now)
    recorder.close()
    return path


def build(seed: int) -> object:
    return build_world(seed, load_team(DEFAULT_HOME), load_team(DEFAULT_AWAY), players=2)


def test_a_fork_with_the_unchanged_behavior_continues_exactly_like_the_recording(recorded: Path) -> None:
    with Recording(recorded) as recording:
        loop = resimulate(recording, build, FORK_AT)  # type: ignore[arg-type]
        world = loop.world
        engines = engines_of(world)
        for view in recording.ticks(FORK_AT, TICKS):
            assert loop.now_ms == view.t
            loop.tick()
            assert world.dynamic_scene() == view.scene, view.seq
            for agent, engine in zip(world.agents, engines, strict=True):
                assert engine is not None
                assert engine.activation() == view.agents[agent.name].tree(), (view.seq, agent.name)


def test_a_fork_with_an_edited_behavior_differs_from_the_fork_tick_on(recorded: Path, tmp_path: Path) -> None:
    shutil.copytree(DEFAULT_AWAY.parent / "behavior", tmp_path / "behavior")  # the chase team includes its files
    chase = tmp_path / "chase"
    shutil.copytree(DEFAULT_AWAY, chase)
    ball = chase / "chase_ball.xabsl"
    text = ball.read_text()
    assert "go_to_ball(distance = 250" in text
    ball.write_text(text.replace("go_to_ball(distance = 250", "go_to_ball(distance = 400"))
    edited = load_team(chase)
    with Recording(recorded) as recording:
        loop = resimulate(recording, build, FORK_AT)  # type: ignore[arg-type]
        assert switch_programs(loop.world, {"chase": edited}, key_of) == 2
        engines = engines_of(loop.world)
        first_difference = None
        for view in recording.ticks(FORK_AT, TICKS):
            loop.tick()
            trees = [e.activation() for e in engines if e is not None]
            recorded_trees = [view.agents[a.name].tree() for a in loop.world.agents]
            if trees != recorded_trees and first_difference is None:
                first_difference = view.seq
        assert first_difference == FORK_AT  # the first tick after the switch calls go_to_ball with 400


def test_a_fork_checks_that_the_world_is_the_recorded_one(recorded: Path) -> None:
    with Recording(recorded) as recording:
        with pytest.raises(RecordingError, match="differs from the recording"):
            resimulate(recording, lambda seed: build(seed + 1), 750)  # type: ignore[arg-type,return-value]
        with pytest.raises(RecordingError, match="outside the recording"):
            resimulate(recording, build, TICKS)  # type: ignore[arg-type]
