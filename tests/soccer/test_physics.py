"""The pymunk space: ball rolling resistance, robot bodies and collisions (examples/soccer/physics.py)."""

from __future__ import annotations

import itertools
import math

from xabsl_studio.examples.soccer.field import FieldDimensions
from xabsl_studio.examples.soccer.physics import SoccerPhysics

DT = 1 / 120


def test_ball_slows_down_monotonically_and_stops():
    physics = SoccerPhysics(FieldDimensions())
    physics.place_ball(-3.0, 0.0)
    physics.push_ball(3.0, 0.0)
    speeds = []
    for _ in range(120 * 20):
        physics.step(DT)
        speeds.append(math.hypot(*physics.ball_velocity()))
    assert speeds[0] < 3.0
    assert all(b <= a for a, b in itertools.pairwise(speeds))
    assert speeds[-1] == 0.0
    x, y = physics.ball_position()
    # rolled forward a plausible distance (several metres) and stayed on its line
    assert 3.0 < x + 3.0 < 7.0
    assert abs(y) < 1e-9


def test_a_faster_ball_rolls_further():
    distances = []
    for speed in (1.0, 2.0):
        physics = SoccerPhysics(FieldDimensions())
        physics.place_ball(-4.0, 0.0)
        physics.push_ball(speed, 0.0)
        for _ in range(120 * 20):
            physics.step(DT)
        distances.append(physics.ball_position()[0] + 4.0)
    assert distances[0] < distances[1]


def test_walls_keep_the_ball_on_the_carpet():
    physics = SoccerPhysics(FieldDimensions())
    physics.place_ball(0.0, 2.5)
    physics.push_ball(0.0, 5.0)
    for _ in range(120 * 10):
        physics.step(DT)
        assert abs(physics.ball_position()[1]) < physics.dims.wall_y
    # it bounced back from the wall
    assert physics.ball_position()[1] < physics.dims.wall_y - 0.1


def test_a_post_deflects_the_ball():
    physics = SoccerPhysics(FieldDimensions())
    post_x, post_y = physics.dims.posts()[3]
    physics.place_ball(post_x - 1.0, post_y)
    physics.push_ball(2.0, 0.0)
    for _ in range(120 * 3):
        physics.step(DT)
    assert physics.ball_position()[0] < post_x


def test_driven_robots_collide_and_do_not_overlap():
    physics = SoccerPhysics(FieldDimensions())
    a = physics.add_robot(-1.0, 0.0, 0.0)
    b = physics.add_robot(1.0, 0.0, math.pi)
    radius = physics.robot_params.radius
    min_gap = float("inf")
    for _ in range(120 * 10):
        physics.drive(a, 0.25, 0.0, 0.0)
        physics.drive(b, -0.25, 0.0, 0.0)
        physics.step(DT)
        (ax, ay, _), (bx, by, _) = physics.robot_pose(a), physics.robot_pose(b)
        min_gap = min(min_gap, math.hypot(bx - ax, by - ay) - 2 * radius)
    # they met in the middle (no passing through) and never sank into each other by more than
    # the solver's slop of a few millimetres
    ax, bx = physics.robot_pose(a)[0], physics.robot_pose(b)[0]
    assert ax < bx
    assert abs(ax + bx) < 0.05
    assert min_gap > -0.01


def test_a_robot_follows_its_commanded_velocity():
    physics = SoccerPhysics(FieldDimensions())
    r = physics.add_robot(0.0, 0.0, 0.0)
    for _ in range(120):
        physics.drive(r, 0.2, -0.1, 0.5)
        physics.step(DT)
    vx, vy, omega = physics.robot_velocity(r)
    assert math.isclose(vx, 0.2, abs_tol=1e-3)
    assert math.isclose(vy, -0.1, abs_tol=1e-3)
    assert math.isclose(omega, 0.5, abs_tol=1e-3)
    x, _, theta = physics.robot_pose(r)
    assert math.isclose(x, 0.2, abs_tol=0.02)
    assert math.isclose(theta, 0.5, abs_tol=0.02)


def test_a_standing_robot_pushes_the_ball_away_when_walking_into_it():
    physics = SoccerPhysics(FieldDimensions())
    r = physics.add_robot(-1.0, 0.0, 0.0)
    physics.place_ball(-0.7, 0.0)
    for _ in range(240):
        physics.drive(r, 0.25, 0.0, 0.0)
        physics.step(DT)
    assert physics.ball_position()[0] > -0.4


def test_placing_a_robot_stops_it():
    physics = SoccerPhysics(FieldDimensions())
    r = physics.add_robot(0.0, 0.0, 0.0)
    physics.drive(r, 0.25, 0.0, 1.0)
    physics.step(DT)
    physics.place_robot(r, 2.0, 1.0, 1.0)
    assert physics.robot_velocity(r) == (0.0, 0.0, 0.0)
    for _ in range(120):
        physics.step(DT)
    x, y, theta = physics.robot_pose(r)
    # the joints' warm start carries a trace of the old command into the first step: < 1 mm
    assert math.hypot(x - 2.0, y - 1.0) < 1e-3
    assert abs(theta - 1.0) < 1e-3


def test_direct_chipmunk_accessors_agree_with_pymunk_properties():
    # physics.py bypasses pymunk's properties on the per-tick path; this pins them together.
    physics = SoccerPhysics(FieldDimensions())
    r = physics.add_robot(0.5, -0.25, 0.3)
    physics.place_ball(1.0, 0.5)
    physics.push_ball(0.4, -0.2)
    physics.drive(r, 0.2, -0.1, 0.5)
    assert tuple(physics.controls[r].velocity) == (0.2, -0.1)
    assert physics.controls[r].angular_velocity == 0.5
    for _ in range(12):
        physics.step(1 / 120)
    xs, ys, thetas = [0.0], [0.0], [0.0]
    assert physics.read_poses(xs, ys, thetas) == tuple(physics.ball.position) == physics.ball_position()
    body = physics.robots[r]
    assert (xs[0], ys[0], thetas[0]) == (body.position.x, body.position.y, body.angle)
    assert physics.ball_velocity() == tuple(physics.ball.velocity)
