"""The referee: game states, halves, goals, outs and kick-off placement (examples/soccer/game.py)."""

from __future__ import annotations

import math

import pytest

from xabsl_studio.examples.soccer.field import FieldDimensions, from_team_frame
from xabsl_studio.examples.soccer.game import GameController, GameRules, GameState, kickoff_position

from .conftest import place, playing_world, run_ticks

DT = 1 / 120


class FakeReferee:
    def __init__(self) -> None:
        self.calls: list[tuple] = []

    def place_ball(self, x: float, y: float) -> None:
        self.calls.append(("ball", round(x, 6), round(y, 6)))

    def place_for_kickoff(self, only_misplaced: bool) -> None:
        self.calls.append(("kickoff", only_misplaced))


def controller(**rules) -> GameController:
    return GameController(FieldDimensions(), GameRules(**rules), ball_radius=0.05)


def advance(game: GameController, seconds: float, referee: FakeReferee, ball=(0.0, 0.0)) -> None:
    # the clock counts whole microseconds (8333 per 120 Hz step): one extra step absorbs rounding
    for _ in range(round(seconds / DT) + 1):
        game.step(DT, ball[0], ball[1], referee)


def test_phases_initial_ready_set_playing():
    game, ref = controller(initial_s=1.0, ready_s=5.0, set_s=2.0), FakeReferee()
    assert game.state == GameState.INITIAL
    assert not game.may_move
    advance(game, 1.0, ref)
    assert game.state == GameState.READY
    assert game.may_move and not game.may_kick
    advance(game, 5.0, ref)
    assert game.state == GameState.SET
    assert not game.may_move
    # entering SET, misplaced robots and the ball are put on their kick-off spots
    assert ref.calls == [("kickoff", True), ("ball", 0.0, 0.0)]
    advance(game, 2.0, ref)
    assert game.state == GameState.PLAYING
    assert game.may_move and game.may_kick


def test_the_half_clock_runs_only_while_playing():
    game, ref = controller(half_duration_s=10.0, initial_s=1.0, ready_s=1.0, set_s=1.0), FakeReferee()
    advance(game, 3.0, ref)
    assert game.state == GameState.PLAYING
    assert game.half_time_left_ms == pytest.approx(10_000, abs=20)
    advance(game, 4.0, ref)
    assert game.half_time_left_ms == pytest.approx(6_000, abs=20)


def test_two_halves_swap_sides_then_finish():
    game, ref = controller(half_duration_s=2.0, initial_s=0.5, ready_s=0.5, set_s=0.5), FakeReferee()
    assert (game.half, game.side, game.kickoff_team) == (1, [1, -1], 0)
    advance(game, 1.5 + 2.0, ref)
    assert game.state == GameState.INITIAL
    assert (game.half, game.side, game.kickoff_team) == (2, [-1, 1], 1)
    assert ("kickoff", False) in ref.calls  # everybody is carried to the new half
    advance(game, 1.5 + 2.0, ref)
    assert game.state == GameState.FINISHED
    assert game.finished
    advance(game, 5.0, ref)
    assert game.state == GameState.FINISHED


def test_goal_only_when_the_ball_wholly_crossed_the_line_between_the_posts():
    game, ref = controller(), FakeReferee()
    game.state = GameState.PLAYING
    # on the line (the ball still touches it): no goal
    game.step(DT, 4.5 + 0.025 + 0.049, 0.0, ref)
    assert game.score == [0, 0]
    game.step(DT, 4.5 + 0.025 + 0.051, 0.3, ref)
    # team 0 attacks +x in the first half
    assert game.score == [1, 0]
    assert game.state == GameState.READY
    assert game.kickoff_team == 1  # the team that conceded kicks off
    assert len(game.goals_log) == 1


def test_goal_for_the_team_attacking_that_goal():
    game, ref = controller(), FakeReferee()
    game.state = GameState.PLAYING
    game.step(DT, -4.7, -0.2, ref)
    assert game.score == [0, 1]
    assert game.kickoff_team == 0


def test_ball_over_the_side_line_goes_to_the_nearest_throw_in_point():
    game, ref = controller(), FakeReferee()
    game.state = GameState.PLAYING
    game.step(DT, 1.234, 3.1, ref)
    assert ref.calls == [("ball", 1.234, 2.6)]
    game.step(DT, -4.4, -3.2, ref)
    assert ref.calls[-1] == ("ball", -4.1, -2.6)
    assert game.outs == 2
    assert game.state == GameState.PLAYING


def test_ball_over_the_goal_line_beside_the_goal():
    game, ref = controller(), FakeReferee()
    game.state = GameState.PLAYING
    game.step(DT, 4.7, 1.5, ref)
    assert ref.calls == [("ball", 3.5, 2.6)]
    game.step(DT, -4.9, -0.9, ref)
    assert ref.calls[-1] == ("ball", -3.5, -2.6)
    assert game.score == [0, 0]


def test_no_outs_or_goals_outside_playing():
    game, ref = controller(initial_s=100.0), FakeReferee()
    game.step(DT, 4.8, 0.0, ref)
    game.step(DT, 0.0, 3.5, ref)
    assert ref.calls == []
    assert game.score == [0, 0]


def test_kickoff_positions_are_in_the_own_half_and_the_defenders_outside_the_circle():
    for number in range(1, 8):
        for kicking in (False, True):
            x, y, _ = kickoff_position(number, kicking)
            assert x < 0.0
            if not kicking:
                assert math.hypot(x, y) > 0.75


# --------------------------------------------------------------------------- with the world


def push_ball_into(world, x_sign: int) -> None:
    world.place_ball(x_sign * 4.2, 0.0)
    world.physics.push_ball(x_sign * 2.0, 0.0)


def test_goal_in_the_world_scores_and_restarts_with_kickoff():
    world = playing_world(3, rules=GameRules(ready_s=2.0, set_s=1.0))
    for i in range(len(world.agents)):  # scatter the robots away from their kick-off poses
        place(world, i, -3.0 + 0.8 * i, 2.0, 45.0)
    push_ball_into(world, +1)
    loop = run_ticks(world, 20)
    assert world.game.score == [1, 0]
    assert world.status()["score"] == [1, 0]
    assert world.game.state == GameState.READY
    assert world.status()["kickoff_team"] == "red"
    states = []
    for _ in range(40 * 4):
        run_ticks(world, 1, loop)
        states.append(world.game.state)
    assert GameState.SET in states
    assert states[-1] == GameState.PLAYING
    # in SET the referee put everybody on the kick-off poses (red kicks off) and the ball in the centre
    assert world.physics.ball_position() == (0.0, 0.0)
    for agent in world.agents:
        side = world.game.side[agent.team_index]
        kx, ky, _ = kickoff_position(agent.number, kicking=agent.team == "red")
        wx, wy = from_team_frame(kx, ky, side)
        x, y, _ = world.physics.robot_pose(agent.index)
        assert math.hypot(x - wx, y - wy) < 0.05, agent.name


def test_ball_out_in_the_world_is_put_back_at_the_throw_in_point():
    world = playing_world(1)
    world.place_ball(2.0, 2.9)
    world.physics.push_ball(0.0, 1.5)
    run_ticks(world, 20)
    assert world.game.outs == 1
    x, y = world.physics.ball_position()
    assert math.isclose(y, 2.6, abs_tol=1e-6)
    assert math.isclose(x, 2.0, abs_tol=0.01)
    assert world.game.state == GameState.PLAYING
