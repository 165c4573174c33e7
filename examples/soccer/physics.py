"""The pymunk space of the soccer world: ball, robot bodies, goal posts, nets and border walls.

This module is the only one that touches pymunk; everything here is in SI units (m, rad, s).

Models, chosen to be cheap at 120 Hz with ten robots:

* Ball: a 0.1 m dynamic disc. Rolling resistance on carpet is modelled in ``step`` as a
  velocity-proportional damping plus a constant deceleration, so a kicked ball slows down
  smoothly and comes to a full stop (pure exponential damping never stops). It is applied in
  Python to the one ball body once per step rather than through a per-body ``velocity_func``
  callback, which pymunk would call for every body.
* Robots: dynamic discs with mass, driven like the pymunk "tank" example: each robot is tied
  to a body-less kinematic *control body* by a ``PivotJoint`` (linear) and a ``GearJoint``
  (angular), both with ``max_bias = 0`` so they only match velocities, and with a maximum
  force/torque. Setting the control body's velocity makes the robot walk at that velocity as
  long as the force suffices; a robot pushing another one stalls instead of passing through it,
  and a standing robot resists being pushed like feet on carpet.
* Goal posts are static discs, nets and border walls static segments.

Per-tick reads and writes (poses, ball, the legs' velocity commands) call Chipmunk through
pymunk's cffi module ``pymunk._chipmunk.lib`` on the bodies' ``_body`` pointers. pymunk's
properties cost ~4x more: ``body.velocity = v`` goes through a Python ``__setattr__`` mixin and a
property (1.4 us for velocity + angular velocity vs 0.39 us direct), ``body.position`` builds a
``Vec2d`` (1.0 us for position + angle vs 0.3 us). That was ~10 % of a whole match. The pymunk
version is pinned to 7.x (pyproject) and ``tests/soccer/test_physics.py`` checks these accessors
against pymunk's public properties.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import pymunk
from pymunk._chipmunk import lib as _cp

from xabsl_studio.examples.soccer.field import FieldDimensions

# Collision types, so tests and rules can tell shapes apart.
BALL = 1
ROBOT = 2
STATIC = 3


@dataclass(frozen=True, slots=True)
class BallParameters:
    """The SPL ball (a 100 mm foam-rubber ball) and its rolling resistance on carpet."""

    radius: float = 0.05
    mass: float = 0.045
    #: Velocity-proportional resistance [1/s]; dominates at high speed.
    damping: float = 0.35
    #: Constant rolling deceleration [m/s^2]; brings the ball to a stop.
    rolling_deceleration: float = 0.25
    elasticity: float = 0.6
    friction: float = 0.2


@dataclass(frozen=True, slots=True)
class RobotBodyParameters:
    """A NAO-sized robot footprint: a 0.26 m disc of 5.5 kg."""

    radius: float = 0.13
    mass: float = 5.5
    #: Largest force the legs exert to follow the commanded velocity [N].
    max_force: float = 60.0
    #: Largest torque the legs exert to follow the commanded turn rate [N m].
    max_torque: float = 5.0
    elasticity: float = 0.0
    friction: float = 0.3


class SoccerPhysics:
    """The pymunk space with the field furniture, one ball and any number of robots.

    Robots are addressed by the index ``add_robot`` returns (the world's agent order).
    """

    def __init__(
        self,
        dims: FieldDimensions,
        ball: BallParameters | None = None,
        robot: RobotBodyParameters | None = None,
        iterations: int = 6,
    ) -> None:
        self.dims = dims
        self.ball_params = ball or BallParameters()
        self.robot_params = robot or RobotBodyParameters()
        self.space = pymunk.Space()
        # Six solver iterations are plenty for a handful of discs without stacking, and cheaper
        # than pymunk's default ten.
        self.space.iterations = iterations
        self._add_static(dims)

        bp = self.ball_params
        self.ball = pymunk.Body(bp.mass, pymunk.moment_for_circle(bp.mass, 0.0, bp.radius))
        ball_shape = pymunk.Circle(self.ball, bp.radius)
        ball_shape.elasticity = bp.elasticity
        ball_shape.friction = bp.friction
        ball_shape.collision_type = BALL
        self.space.add(self.ball, ball_shape)

        self.robots: list[pymunk.Body] = []
        self.controls: list[pymunk.Body] = []
        # Chipmunk pointers of the bodies, for the direct calls (see the module docstring).
        self._ball_ptr = self.ball._body
        self._robot_ptrs: list[object] = []
        self._control_ptrs: list[object] = []
        self._damping_dt = -1.0
        self._damping_factor = 1.0

    def _add_static(self, dims: FieldDimensions) -> None:
        static = self.space.static_body
        shapes: list[pymunk.Shape] = []
        for x1, y1, x2, y2 in dims.walls():
            shapes.append(pymunk.Segment(static, (x1, y1), (x2, y2), 0.02))
        for side in (-1, 1):
            net = dims.net(side)
            for a, b in itertools.pairwise(net):
                shapes.append(pymunk.Segment(static, a, b, 0.01))
        for x, y in dims.posts():
            shapes.append(pymunk.Circle(static, dims.post_radius, (x, y)))
        for shape in shapes:
            shape.elasticity = 0.5
            shape.friction = 0.3
            shape.collision_type = STATIC
        self.space.add(*shapes)

    # ---------------------------------------------------------------------------------- robots

    def add_robot(self, x: float, y: float, theta: float) -> int:
        """Add a robot at a world pose; returns its index."""
        rp = self.robot_params
        body = pymunk.Body(rp.mass, pymunk.moment_for_circle(rp.mass, 0.0, rp.radius))
        body.position = (x, y)
        body.angle = theta
        shape = pymunk.Circle(body, rp.radius)
        shape.elasticity = rp.elasticity
        shape.friction = rp.friction
        shape.collision_type = ROBOT
        control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        control.position = (x, y)
        pivot = pymunk.PivotJoint(control, body, (0.0, 0.0), (0.0, 0.0))
        pivot.max_bias = 0.0
        pivot.max_force = rp.max_force
        gear = pymunk.GearJoint(control, body, 0.0, 1.0)
        gear.max_bias = 0.0
        gear.max_force = rp.max_torque
        self.space.add(body, shape, control, pivot, gear)
        self.robots.append(body)
        self.controls.append(control)
        self._robot_ptrs.append(body._body)
        self._control_ptrs.append(control._body)
        return len(self.robots) - 1

    def drive(self, index: int, vx: float, vy: float, omega: float) -> None:
        """Command a robot's world-frame velocity [m/s] and turn rate [rad/s] until the next call."""
        # The control body's position never matters: both pivot anchors sit on their body's
        # centre of gravity, so the joint's lever arms are zero and, with max_bias = 0, it only
        # equates velocities. Not moving it saves a call into C per robot and tick.
        control = self._control_ptrs[index]
        _cp.cpBodySetVelocity(control, (vx, vy))
        _cp.cpBodySetAngularVelocity(control, omega)

    def place_robot(self, index: int, x: float, y: float, theta: float) -> None:
        """Teleport a robot (referee placement) and stop it."""
        body = self.robots[index]
        body.position = (x, y)
        body.angle = theta
        body.velocity = (0.0, 0.0)
        body.angular_velocity = 0.0
        self.drive(index, 0.0, 0.0, 0.0)
        self.space.reindex_shapes_for_body(body)

    def robot_pose(self, index: int) -> tuple[float, float, float]:
        """Robot ``index``'s pose: x, y (mm) and heading (rad)."""
        body = self.robots[index]
        x, y = body.position
        return x, y, body.angle

    def read_poses(self, xs: list[float], ys: list[float], thetas: list[float]) -> tuple[float, float]:
        """Fill ``xs``/``ys``/``thetas`` with every robot's pose [m, rad]; return the ball position."""
        get_position, get_angle = _cp.cpBodyGetPosition, _cp.cpBodyGetAngle
        for i, body in enumerate(self._robot_ptrs):
            p = get_position(body)
            xs[i] = p.x
            ys[i] = p.y
            thetas[i] = get_angle(body)
        p = get_position(self._ball_ptr)
        return p.x, p.y

    def robot_velocity(self, index: int) -> tuple[float, float, float]:
        """Robot ``index``'s velocity: vx, vy (mm/s) and turn rate (rad/s)."""
        body = self.robots[index]
        vx, vy = body.velocity
        return vx, vy, body.angular_velocity

    # ------------------------------------------------------------------------------------ ball

    def place_ball(self, x: float, y: float) -> None:
        """Put the ball at a world point, at rest (referee placement)."""
        self.ball.position = (x, y)
        self.ball.velocity = (0.0, 0.0)
        self.ball.angular_velocity = 0.0
        self.space.reindex_shapes_for_body(self.ball)

    def ball_position(self) -> tuple[float, float]:
        """The ball's position (mm)."""
        p = _cp.cpBodyGetPosition(self._ball_ptr)
        return p.x, p.y

    def ball_velocity(self) -> tuple[float, float]:
        """The ball's velocity (mm/s)."""
        v = _cp.cpBodyGetVelocity(self._ball_ptr)
        return v.x, v.y

    def push_ball(self, dvx: float, dvy: float) -> None:
        """Change the ball's velocity by (dvx, dvy) m/s: the impulse of a kick."""
        m = self.ball_params.mass
        self.ball.apply_impulse_at_world_point((m * dvx, m * dvy), self.ball.position)

    # ------------------------------------------------------------------------------------ step

    def step(self, dt: float) -> None:
        """Advance the space by ``dt`` seconds, then apply the ball's rolling resistance."""
        self.space.step(dt)
        ball = self._ball_ptr
        v = _cp.cpBodyGetVelocity(ball)
        vx, vy = v.x, v.y
        if vx == 0.0 and vy == 0.0:
            return
        if dt != self._damping_dt:
            self._damping_dt = dt
            self._damping_factor = math.exp(-self.ball_params.damping * dt)
        speed = math.hypot(vx, vy)
        new_speed = speed * self._damping_factor - self.ball_params.rolling_deceleration * dt
        if new_speed <= 0.0:
            _cp.cpBodySetVelocity(ball, (0.0, 0.0))
            _cp.cpBodySetAngularVelocity(ball, 0.0)
        else:
            scale = new_speed / speed
            _cp.cpBodySetVelocity(ball, (vx * scale, vy * scale))
