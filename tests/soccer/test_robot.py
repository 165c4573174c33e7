"""The walking robot: speed, turn-rate and acceleration limits, walk_to, kicks (examples/soccer/robot.py)."""

from __future__ import annotations

import math

from xabsl_studio.examples.soccer.game import GameState
from xabsl_studio.examples.soccer.robot import MotionMode

from .conftest import place, playing_world, run_ticks


def ball_speed(world) -> float:
    return math.hypot(*world.physics.ball_velocity())


def test_kick_moves_the_ball_in_the_kick_direction():
    world = playing_world(1)
    place(world, 0, 0.0, 0.0, 0.0)
    world.place_ball(0.25, 0.0)  # 70 mm in front of the robot's surface
    world.agents[0].motion.kick_strength = 1.0
    world.agents[0].motion.kick_direction = 20.0
    run_ticks(world, 1)
    vx, vy = world.physics.ball_velocity()
    assert math.hypot(vx, vy) > 3.0
    assert math.isclose(math.degrees(math.atan2(vy, vx)), 20.0, abs_tol=1.0)
    run_ticks(world, 40)
    bx, by = world.physics.ball_position()
    assert bx > 2.0
    assert math.isclose(math.degrees(math.atan2(by, bx - 0.25)), 20.0, abs_tol=2.0)


def test_kick_direction_is_relative_to_the_heading():
    world = playing_world(1)
    place(world, 0, 0.0, 0.0, 90.0)
    world.place_ball(0.0, 0.25)
    world.agents[0].motion.kick_strength = 0.5
    run_ticks(world, 1)
    vx, vy = world.physics.ball_velocity()
    assert vy > 1.5
    assert abs(vx) < 0.05


def test_kick_with_the_ball_far_away_does_nothing():
    world = playing_world(1)
    place(world, 0, 0.0, 0.0, 0.0)
    world.place_ball(0.6, 0.0)
    world.agents[0].motion.kick_strength = 1.0
    run_ticks(world, 1)
    assert ball_speed(world) == 0.0
    assert world.agents[0].motion.kick_strength == 0.0  # the request is an event, consumed


def test_kick_with_the_ball_behind_or_beside_does_nothing():
    for bx, by in [(-0.25, 0.0), (0.0, 0.25), (0.12, 0.2)]:  # behind, beside, 59 degrees left
        world = playing_world(1)
        place(world, 0, 0.0, 0.0, 0.0)
        world.place_ball(bx, by)
        world.agents[0].motion.kick_strength = 1.0
        run_ticks(world, 1)
        assert ball_speed(world) == 0.0, (bx, by)


def test_kick_only_while_playing():
    world = playing_world(1)
    world.game.state = GameState.READY
    place(world, 0, 0.0, 0.0, 0.0)
    world.place_ball(0.25, 0.0)
    world.agents[0].motion.kick_strength = 1.0
    loop = run_ticks(world, 1)
    assert ball_speed(world) == 0.0
    assert loop.ticks == 1


def test_kick_cooldown():
    world = playing_world(1)
    robot = world.agents[0]
    place(world, 0, 0.0, 0.0, 0.0)
    world.place_ball(0.25, 0.0)
    robot.motion.kick_strength = 0.2
    loop = run_ticks(world, 1)
    assert ball_speed(world) > 0.0
    world.place_ball(0.25, 0.0)  # put it back at once: the leg is not ready yet
    robot.motion.kick_strength = 1.0
    run_ticks(world, 1, loop)
    assert ball_speed(world) == 0.0
    assert not robot.robot.kick_ready(loop.now_ms)
    run_ticks(world, 40, loop)  # one second later
    world.place_ball(0.25, 0.0)
    place(world, 0, 0.0, 0.0, 0.0)
    robot.motion.kick_strength = 1.0
    run_ticks(world, 1, loop)
    assert ball_speed(world) > 3.0


def velocities_under(command: dict, ticks: int = 120):
    world = playing_world(1)
    place(world, 0, 0.0, 0.0, 0.0)
    world.place_ball(3.0, 2.0)
    motion = world.agents[0].motion
    motion.mode = MotionMode.WALK
    for key, value in command.items():
        setattr(motion, key, value)
    seen = []
    loop = None
    for _ in range(ticks):
        loop = run_ticks(world, 1, loop)
        vx, vy, omega = world.physics.robot_velocity(world.agents[0].index)
        theta = world.physics.robot_pose(world.agents[0].index)[2]
        c, s = math.cos(theta), math.sin(theta)
        seen.append((c * vx + s * vy, -s * vx + c * vy, omega))
    return seen


def test_forward_speed_is_limited():
    seen = velocities_under({"vx": 2000.0})
    assert max(v[0] for v in seen) <= 0.25 + 1e-3
    assert seen[-1][0] > 0.249


def test_backward_and_sideways_speeds_are_limited():
    assert min(v[0] for v in velocities_under({"vx": -2000.0})) >= -0.15 - 1e-3
    assert max(abs(v[1]) for v in velocities_under({"vy": 2000.0})) <= 0.15 + 1e-3


def test_diagonal_walking_is_limited_elliptically():
    forward, sideways, _ = velocities_under({"vx": 2000.0, "vy": 2000.0})[-1]
    assert (forward / 0.25) ** 2 + (sideways / 0.15) ** 2 <= 1.0 + 1e-2
    assert forward > 0.1
    assert sideways > 0.05


def test_turn_rate_is_limited():
    seen = velocities_under({"vrot": 720.0})
    assert max(abs(v[2]) for v in seen) <= 1.0 + 1e-3
    assert seen[-1][2] > 0.99


def test_acceleration_is_limited():
    seen = velocities_under({"vx": 250.0}, ticks=12)
    # 1 m/s^2: at most 25 mm/s more per 25 ms tick, so full speed takes ten ticks
    assert seen[0][0] <= 0.025 + 1e-3
    assert seen[4][0] <= 0.125 + 1e-3
    assert seen[11][0] > 0.249


def test_robots_stand_still_in_set():
    world = playing_world(1)
    world.game.state = GameState.SET
    world.place_ball(2.0, 2.0)
    place(world, 0, 0.0, 0.0, 0.0)
    motion = world.agents[0].motion
    motion.mode, motion.vx = MotionMode.WALK, 200.0
    run_ticks(world, 40)
    x, y, _ = world.physics.robot_pose(world.agents[0].index)
    assert math.hypot(x, y) < 1e-6


def test_walk_to_reaches_a_team_frame_target():
    world = playing_world(1)
    # team 1 attacks -x in the first half: its team frame is the world turned by 180 degrees
    red = world.agents[1]
    assert world.game.side[red.team_index] == -1
    place(world, 1, 0.0, 0.0, 0.0)
    world.place_ball(3.0, 2.5)
    red.motion.mode = MotionMode.WALK_TO
    red.motion.target_x, red.motion.target_y, red.motion.target_rot = -1000.0, 500.0, 90.0
    run_ticks(world, 40 * 20)
    x, y, theta = world.physics.robot_pose(red.index)
    assert math.isclose(x, 1.0, abs_tol=0.03)
    assert math.isclose(y, -0.5, abs_tol=0.03)
    # team heading 90 degrees is world heading -90 degrees for a team attacking -x
    assert math.isclose(math.remainder(theta + math.pi / 2, 2 * math.pi), 0.0, abs_tol=0.06)
