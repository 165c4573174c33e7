"""The walking robot: what a behavior can command, and how the legs carry it out.

A behavior writes a :class:`MotionRequest` (behavior units: mm, mm/s, degrees, deg/s); once per
behavior tick :meth:`Robot.act` turns it into a velocity for the physics within the limits of
an SPL-like holonomic walk, and performs a requested kick if the ball is where a foot can reach.

Walk modes:

* ``STAND``: stop (decelerating within the acceleration limits).
* ``WALK``: walk at ``(vx, vy, vrot)`` in the robot frame (x forward, y left, ccw positive).
* ``WALK_TO``: walk to ``(target_x, target_y, target_rot)`` in the *team frame* (own goal at
  negative x, see ``field``), with a proportional controller that respects the same limits;
  far from the target (> 0.6 m) the robot faces the target, near it turns to ``target_rot``.

Limits (:class:`WalkLimits`): 0.25 m/s forward, 0.15 m/s backward and sideways (combined
elliptically, so walking diagonally at full speed on both axes is not possible), 1 rad/s turn
rate, and acceleration limits, applied per tick.

Kicks are events, not modes: ``kick_strength > 0`` asks for a kick in this tick and is cleared
by ``act`` whether it happened or not, so a behavior keeps asking while it wants to kick. A kick
happens only while kicking is allowed (game state PLAYING), when the cooldown since the last kick
has passed, and when the ball is close (at most ``reach`` between the surfaces of robot and ball)
and in front (within ``half_angle`` of the heading). It sets the ball's velocity to
``strength * max_speed`` in direction ``kick_direction`` (degrees from the heading, limited to
+-90) by an impulse; the ball then rolls under the physics' rolling resistance.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from xabsl_studio.examples.soccer.physics import SoccerPhysics
from xabsl_studio.examples.soccer.units import M_PER_MM, RAD_PER_DEG, normalize_rad


class MotionMode(enum.IntEnum):
    """How the legs interpret a motion request (values usable as an XABSL enumeration)."""

    STAND = 0
    WALK = 1
    WALK_TO = 2


_STAND = MotionMode.STAND
_WALK = MotionMode.WALK


@dataclass(slots=True)
class MotionRequest:
    """The commands a behavior writes (output symbols), in behavior units.

    Attributes:
        mode: ``STAND``, ``WALK`` or ``WALK_TO``; persists until changed.
        vx, vy: walk velocity in the robot frame [mm/s] (x forward, y left), mode ``WALK``.
        vrot: turn rate [deg/s], counter-clockwise positive, mode ``WALK``.
        target_x, target_y: walk target in the team frame [mm], mode ``WALK_TO``.
        target_rot: heading to reach at the target in the team frame [deg], mode ``WALK_TO``.
        kick_strength: 0 (no kick) .. 1 (strongest); an event, cleared after every tick.
        kick_direction: direction of the kick relative to the heading [deg], -90..90.
    """

    mode: MotionMode = MotionMode.STAND
    vx: float = 0.0
    vy: float = 0.0
    vrot: float = 0.0
    target_x: float = 0.0
    target_y: float = 0.0
    target_rot: float = 0.0
    kick_strength: float = 0.0
    kick_direction: float = 0.0


@dataclass(frozen=True, slots=True)
class WalkLimits:
    """Speed and acceleration limits of the walk, in SI units, and the kick's envelope."""

    max_forward: float = 0.25  # m/s
    max_backward: float = 0.15  # m/s
    max_sideways: float = 0.15  # m/s
    max_turn: float = 1.0  # rad/s
    max_acceleration: float = 1.0  # m/s^2, per axis
    max_turn_acceleration: float = 4.0  # rad/s^2
    #: Gains of the WALK_TO controller [1/s]: how fast an offset is closed before saturation.
    walk_to_gain: float = 1.5
    walk_to_turn_gain: float = 2.0
    #: Beyond this distance WALK_TO turns towards the target, closer it turns to the target heading.
    walk_to_face_distance: float = 0.6  # m
    #: WALK_TO stops within these tolerances instead of dithering around the target.
    walk_to_tolerance: float = 0.02  # m
    walk_to_turn_tolerance: float = 0.05  # rad
    kick_reach: float = 0.15  # m between robot surface and ball surface
    kick_half_angle: float = math.radians(30.0)
    kick_max_speed: float = 4.0  # m/s given to the ball by a full-strength kick
    kick_cooldown_ms: int = 1000


class Robot:
    """One robot's legs: applies motion requests to its body in the physics.

    Args:
        physics: the space holding the robot's body.
        index: the robot's body index in ``physics``.
        limits: walk and kick limits.
    """

    __slots__ = ("_driven", "_last_act_ms", "index", "last_kick_ms", "limits", "physics", "vrot", "vx", "vy")

    def __init__(self, physics: SoccerPhysics, index: int, limits: WalkLimits | None = None) -> None:
        self.physics = physics
        self.index = index
        self.limits = limits or WalkLimits()
        # The walk's current velocity in the robot frame (SI), what the acceleration limits act on.
        self.vx = 0.0
        self.vy = 0.0
        self.vrot = 0.0
        self.last_kick_ms: int | None = None
        self._last_act_ms: int | None = None
        self._driven = (0.0, 0.0, 0.0)

    def kick_ready(self, now_ms: int) -> bool:
        """Tell whether the kick cooldown has passed."""
        last = self.last_kick_ms
        return last is None or now_ms - last >= self.limits.kick_cooldown_ms

    def halt(self) -> None:
        """Stop at once (after a referee placement); the walk restarts from zero velocity."""
        self.vx = self.vy = self.vrot = 0.0
        self._driven = (0.0, 0.0, 0.0)
        self.physics.drive(self.index, 0.0, 0.0, 0.0)

    def act(
        self,
        request: MotionRequest,
        now_ms: int,
        pose: tuple[float, float, float],
        side: int,
        may_move: bool,
        may_kick: bool,
    ) -> bool:
        """Carry out one tick of ``request``; return True if a kick hit the ball.

        Args:
            request: the behavior's commands; its kick fields are cleared.
            now_ms: the tick's time; the time since the previous call bounds the acceleration.
            pose: the robot's world pose (x, y, heading) [m, rad] at this tick.
            side: the direction the robot's team attacks (+1 or -1), to read ``WALK_TO`` targets.
            may_move: False in game states where robots must stand (INITIAL, SET, FINISHED).
            may_kick: False outside the PLAYING state.
        """
        # Runs for every robot every tick (a quarter of a match's time before it was written
        # flat): the clamp is inline, enum members are module constants (an IntEnum member
        # lookup costs ~80 ns in 3.11) and the acceleration limit uses comparisons instead of
        # min/max calls (the same values for every non-NaN input).
        lim = self.limits
        last = self._last_act_ms
        dt = 0.025 if last is None or now_ms <= last else (now_ms - last) / 1000.0
        self._last_act_ms = now_ms
        x, y, theta = pose

        mode = request.mode
        if not may_move or mode == _STAND:
            # Clamping zero changes nothing.
            want_x = want_y = want_rot = 0.0
        else:
            if mode == _WALK:
                want_x = request.vx * M_PER_MM
                want_y = request.vy * M_PER_MM
                want_rot = request.vrot * RAD_PER_DEG
            else:
                want_x, want_y, want_rot = self._walk_to(request, x, y, theta, side)
            # Elliptic limit: the walk cannot reach full forward and full sideways speed together.
            r = math.hypot(want_x / (lim.max_forward if want_x >= 0.0 else lim.max_backward), want_y / lim.max_sideways)
            if r > 1.0:
                want_x /= r
                want_y /= r
            turn = lim.max_turn
            want_rot = turn if want_rot > turn else -turn if want_rot < -turn else want_rot

        dv = lim.max_acceleration * dt
        dw = lim.max_turn_acceleration * dt
        d = want_x - self.vx
        self.vx = vx = self.vx + (dv if d > dv else -dv if d < -dv else d)
        d = want_y - self.vy
        self.vy = vy = self.vy + (dv if d > dv else -dv if d < -dv else d)
        d = want_rot - self.vrot
        self.vrot = vrot = self.vrot + (dw if d > dw else -dw if d < -dw else d)

        if vx == 0.0 and vy == 0.0:
            command = (0.0, 0.0, vrot)
        else:
            c, s = math.cos(theta), math.sin(theta)
            command = (c * vx - s * vy, s * vx + c * vy, vrot)
        # A standing robot (most of them, most of the time) needs no call into the physics.
        if command != self._driven:
            self._driven = command
            self.physics.drive(self.index, command[0], command[1], command[2])

        kicked = False
        strength = request.kick_strength
        if strength > 0.0 and may_kick and self.kick_ready(now_ms):
            kicked = self._kick(min(strength, 1.0), request.kick_direction, x, y, theta)
            if kicked:
                self.last_kick_ms = now_ms
        request.kick_strength = 0.0
        return kicked

    def _walk_to(
        self, request: MotionRequest, x: float, y: float, theta: float, side: int
    ) -> tuple[float, float, float]:
        lim = self.limits
        # The team frame maps to the world frame by the sign of ``side`` (``field.from_team_frame``).
        dx, dy = request.target_x * M_PER_MM * side - x, request.target_y * M_PER_MM * side - y
        c, s = math.cos(theta), math.sin(theta)
        rel_x, rel_y = c * dx + s * dy, -s * dx + c * dy
        distance = math.hypot(rel_x, rel_y)
        if distance > lim.walk_to_face_distance:
            # Far away, face the target: forward is the walk's fastest direction.
            turn = math.atan2(rel_y, rel_x)
        else:
            target_theta = request.target_rot * RAD_PER_DEG + (0.0 if side > 0 else math.pi)
            turn = normalize_rad(target_theta - theta)
        if distance < lim.walk_to_tolerance:
            rel_x = rel_y = 0.0
        if abs(turn) < lim.walk_to_turn_tolerance:
            turn = 0.0
        return lim.walk_to_gain * rel_x, lim.walk_to_gain * rel_y, lim.walk_to_turn_gain * turn

    def _kick(self, strength: float, direction_deg: float, x: float, y: float, theta: float) -> bool:
        lim = self.limits
        physics = self.physics
        bx, by = physics.ball_position()
        dx, dy = bx - x, by - y
        gap = math.hypot(dx, dy) - physics.robot_params.radius - physics.ball_params.radius
        if gap > lim.kick_reach:
            return False
        if abs(normalize_rad(math.atan2(dy, dx) - theta)) > lim.kick_half_angle:
            return False
        direction = theta + max(-90.0, min(90.0, direction_deg)) * RAD_PER_DEG
        speed = strength * lim.kick_max_speed
        vx, vy = physics.ball_velocity()
        physics.push_ball(speed * math.cos(direction) - vx, speed * math.sin(direction) - vy)
        return True
