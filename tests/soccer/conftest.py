"""Shared helpers for the soccer world tests: worlds in a known state, driven tick by tick."""

from __future__ import annotations

import math

import pytest

from xabsl_studio.engine.host import BehaviorLoop
from xabsl_studio.examples.soccer.game import GameRules, GameState
from xabsl_studio.examples.soccer.perception import SensorModel
from xabsl_studio.examples.soccer.world import SoccerWorld, build_world


def playing_world(players_per_team: int = 1, seed: int = 0, **options) -> SoccerWorld:
    """A world without noise, already in PLAYING, robots standing where kick-off put them."""
    options.setdefault("sensor", SensorModel.exact())
    options.setdefault("rules", GameRules(half_duration_s=600.0))
    world = build_world(seed, players_per_team=players_per_team, **options)
    world.game.state = GameState.PLAYING
    return world


def place(world: SoccerWorld, agent_index: int, x: float, y: float, heading_deg: float = 0.0) -> None:
    world.place_robot(world.agents[agent_index], x, y, math.radians(heading_deg))


def run_ticks(world: SoccerWorld, ticks: int, loop: BehaviorLoop | None = None) -> BehaviorLoop:
    loop = loop or BehaviorLoop(world)
    for _ in range(ticks):
        loop.tick()
    return loop


@pytest.fixture
def world1() -> SoccerWorld:
    """One robot per team, PLAYING, exact perception."""
    return playing_world(1)
