"""Behavior sanity of the example team: roles, reaching the ball, the bindings, the compile."""

from __future__ import annotations

import math
from collections import Counter

import pytest

from xabsl_studio.engine.host import BehaviorLoop
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.examples.soccer.bindings import Role, XabslController
from xabsl_studio.examples.soccer.game import GameState
from xabsl_studio.examples.soccer.run import DEFAULT_AWAY, DEFAULT_HOME, build_world, load_team

HOME = load_team(DEFAULT_HOME)
AWAY = load_team(DEFAULT_AWAY)


def test_the_team_compiles_clean_with_at_least_30_options():
    compilation = compile_file(str(DEFAULT_HOME / "agents.xabsl"))
    print([str(d) for d in compilation.diagnostics])
    assert compilation.diagnostics == []
    assert len(compilation.program.options) >= 30


def test_the_chase_team_compiles_without_errors():
    compilation = compile_file(str(DEFAULT_AWAY / "agents.xabsl"))
    # It shares the team's namespaces and uses a few of their symbols: only unused-symbol lint.
    assert {d.code for d in compilation.diagnostics} <= {"unused-symbol", "unused-behavior"}
    assert len(compilation.program.options) == 2


def _roles(world, team: int) -> list[int]:
    return [a.perception.outgoing.get("role", 0) for a in world.agents if a.team_index == team]


def test_one_goalie_and_mostly_one_striker_during_play():
    world = build_world(5, HOME, AWAY, half_duration_s=60.0)
    loop = BehaviorLoop(world)
    playing = unique_striker = 0
    strikers = Counter()
    while not world.finished:
        loop.tick()
        if world.game.state != GameState.PLAYING or world.game.state_ns < 3e9:
            continue  # kick-off: the defending team waits without a role
        roles = _roles(world, 0)
        playing += 1
        assert roles.count(Role.GOALIE) == 1 and roles[0] == Role.GOALIE, roles
        strikers[roles.count(Role.STRIKER)] += 1
        unique_striker += roles.count(Role.STRIKER) == 1
    print(f"ticks {playing}, strikers per tick {dict(strikers)}")
    assert playing > 3000
    assert unique_striker / playing >= 0.9
    for agent in world.agents:
        assert agent.controller.fault is None, agent.controller.fault


def test_every_field_role_is_played():
    world = build_world(2, HOME, AWAY, half_duration_s=30.0)
    loop = BehaviorLoop(world)
    seen = Counter()
    while not world.finished:
        loop.tick()
        seen.update(_roles(world, 0))
    print(dict(seen))
    assert {Role.GOALIE, Role.STRIKER, Role.SUPPORTER, Role.DEFENDER} <= set(seen)


@pytest.mark.parametrize(("ball_x", "ball_y"), [(2.0, 1.5), (-1.5, -2.0), (0.5, 2.5)])
def test_the_striker_reaches_a_ball_anywhere_within_20_seconds(ball_x, ball_y):
    world = build_world(3, HOME, AWAY, half_duration_s=600.0)
    for agent in world.agents[5:]:
        agent.controller = None  # the opponents stand still: only the home team moves
    world.game.state = GameState.PLAYING
    world.place_ball(ball_x, ball_y)
    loop = BehaviorLoop(world)
    for tick in range(20 * 40):
        loop.tick()
        bx, by = world.physics.ball_position()
        for agent in world.agents[:5]:
            x, y = world.physics.robots[agent.index].position
            if agent.perception.outgoing.get("role") == Role.STRIKER and math.hypot(x - bx, y - by) < 0.4:
                print(f"{agent.name} reached the ball after {tick / 40:.1f} s")
                return
    pytest.fail("no striker reached the ball within 20 s")


def test_bindings_cover_every_symbol_and_behavior_the_team_declares():
    world = build_world(0, HOME, AWAY, players=1)
    controller = world.agents[0].controller
    assert isinstance(controller, XabslController)
    assert controller.engine.root_actions.agent == "soccer"


def test_team_message_outputs_are_written_in_place():
    world = build_world(0, HOME, AWAY, players=2, half_duration_s=10.0)
    outgoing = world.agents[1].perception.outgoing
    loop = BehaviorLoop(world)
    for _ in range(400):
        loop.tick()
    assert world.agents[1].perception.outgoing is outgoing
    assert {"role", "time_to_ball", "x", "y", "ball_x", "ball_y", "ball_age"} <= set(outgoing)
    assert outgoing["time_to_ball"] < 1e6
