"""A short soccer match recorded once for the query tests (2 v 2: the example team and the chase team)."""

from __future__ import annotations

from pathlib import Path

import pytest

from xabsl_studio.engine.host import BehaviorLoop
from xabsl_studio.engine.record import Recorder, Recording, TickView
from xabsl_studio.examples.soccer.run import DEFAULT_AWAY, DEFAULT_HOME, build_world, load_team

TICKS = 1600  # the pre-game (about 16 s at 40 Hz) and 24 s of play: kicks, shots, role changes


@pytest.fixture(scope="package")
def match(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The recording's path."""
    path = tmp_path_factory.mktemp("query") / "match.mcap"
    home, away = load_team(DEFAULT_HOME), load_team(DEFAULT_AWAY)
    world = build_world(5, home, away, players=2)
    loop = BehaviorLoop(world)
    recorder = Recorder(
        path, world, {"behavior": home, "chase": away}, example="soccer", behavior_hz=40, physics_hz=120
    )
    for _ in range(TICKS):
        now = loop.now_ms
        loop.tick()
        recorder.tick(now)
    recorder.close()
    return path


@pytest.fixture(scope="package")
def views(match: Path) -> list[TickView]:
    """Every tick of the recording, decoded by the recording reader."""
    with Recording(match) as recording:
        return list(recording.ticks())
