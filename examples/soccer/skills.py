"""Basic behaviors of the soccer robot: the leaf skills XABSL options call (§2.2, §3.5).

Each class here is one ``behavior`` declared in ``behavior/basic_behaviors.xabsl``. A basic
behavior is the host's half of a call such as ``walk_to(x = 0, y = 0, rot = 0);``: the engine
sets the declared parameters, then calls :meth:`execute`, which translates them into the
robot's :class:`~xabsl_studio.examples.soccer.robot.MotionRequest`. The legs (``robot.Robot.act``) carry the
request out after every agent's behavior ran, within the walk's speed and acceleration limits.

How to write one for your own robot:

* subclass :class:`SoccerSkill` (which keeps the world model and the motion request of *one*
  robot), set ``name`` to the XABSL name and ``parameters`` to the declared parameters **in
  declaration order**, and override ``execute``;
* read the parameters in ``execute`` by position, ``self.parameter_values[self.parameter_offset + k]``
  for the k-th declared parameter: a list read costs far less than ``self.param("x")`` (a dict
  lookup), and ``execute`` runs once per tick per robot;
* write only the motion request: never the world model, never the engine.

Units are the behavior units of the whole example: mm, mm/s, degrees, deg/s, and positions and
directions in the team frame (own goal at negative x, 0 degrees points at the opponent goal).
A ``direction`` parameter is always a *field* direction; the skill turns it into the robot frame.
"""

from __future__ import annotations

import math
from typing import ClassVar

from xabsl_studio.engine.runtime import BasicBehavior
from xabsl_studio.engine.types import Kind
from xabsl_studio.examples.soccer.perception import WorldModel
from xabsl_studio.examples.soccer.robot import MotionMode, MotionRequest
from xabsl_studio.examples.soccer.units import RAD_PER_DEG, normalize_deg

_STAND = MotionMode.STAND
_WALK = MotionMode.WALK
_WALK_TO = MotionMode.WALK_TO

#: Fastest forward walk [mm/s]; the legs clamp anything faster (``robot.WalkLimits``).
MAX_FORWARD = 250.0
#: Fastest turn [deg/s] (1 rad/s).
MAX_TURN = 57.0


class SoccerSkill(BasicBehavior):
    """A basic behavior bound to one robot: reads its world model, writes its motion request.

    The engine attaches its parameter storage after construction:
    ``self.parameter_values[self.parameter_offset + k]`` is the k-th declared parameter.
    (``BasicBehavior.param(name)`` reads the same value through a dict; skills index the list
    directly on the per-tick path.)
    """

    def __init__(self, perception: WorldModel, motion: MotionRequest) -> None:
        super().__init__()
        self.wm = perception
        self.motion = motion


class Stand(SoccerSkill):
    """``stand()``: stop walking (decelerating within the walk's limits)."""

    name: ClassVar[str] = "stand"

    def execute(self) -> None:
        """Request no motion this tick."""
        self.motion.mode = _STAND


class Walk(SoccerSkill):
    """``walk(vx, vy, rot)``: walk at a velocity in the robot frame [mm/s, mm/s, deg/s]."""

    name: ClassVar[str] = "walk"
    parameters: ClassVar = (("vx", Kind.DECIMAL), ("vy", Kind.DECIMAL), ("rot", Kind.DECIMAL))

    def execute(self) -> None:
        """Request the robot-frame velocity (the legs clamp it to their limits)."""
        v, b, m = self.parameter_values, self.parameter_offset, self.motion
        m.mode = _WALK
        m.vx, m.vy, m.vrot = v[b], v[b + 1], v[b + 2]


class Turn(SoccerSkill):
    """``turn(rate)``: turn on the spot [deg/s, counter-clockwise positive]."""

    name: ClassVar[str] = "turn"
    parameters: ClassVar = (("rate", Kind.DECIMAL),)

    def execute(self) -> None:
        """Request a turn on the spot at ``rate``."""
        m = self.motion
        m.mode = _WALK
        m.vx = m.vy = 0.0
        m.vrot = self.parameter_values[self.parameter_offset]


class WalkTo(SoccerSkill):
    """``walk_to(x, y, rot)``: walk to a field pose [mm, mm, deg] (team frame).

    Far from the target the legs face it (forward is the fastest direction); near it they turn
    to ``rot`` (see ``robot.MotionMode.WALK_TO``).
    """

    name: ClassVar[str] = "walk_to"
    parameters: ClassVar = (("x", Kind.DECIMAL), ("y", Kind.DECIMAL), ("rot", Kind.DECIMAL))

    def execute(self) -> None:
        """Request a walk to the field pose, converted from the team frame."""
        v, b, m = self.parameter_values, self.parameter_offset, self.motion
        m.mode = _WALK_TO
        m.target_x, m.target_y, m.target_rot = v[b], v[b + 1], v[b + 2]


class GoToBall(SoccerSkill):
    """``go_to_ball(distance, direction)``: walk to ``distance`` mm behind the ball, facing ``direction``.

    "Behind" is seen from ``direction`` (a field direction): the target is on the line through
    the ball along ``direction``, on the near side. The skill does not walk around the ball; an
    option that approaches from the wrong side must first walk to a point beside it.
    """

    name: ClassVar[str] = "go_to_ball"
    parameters: ClassVar = (("distance", Kind.DECIMAL), ("direction", Kind.DECIMAL))

    def execute(self) -> None:
        """Request a walk to the point ``distance`` behind the ball, facing ``direction``."""
        v, b, m, wm = self.parameter_values, self.parameter_offset, self.motion, self.wm
        distance, direction = v[b], v[b + 1]
        a = direction * RAD_PER_DEG
        m.mode = _WALK_TO
        m.target_x = wm.ball_x - distance * math.cos(a)
        m.target_y = wm.ball_y - distance * math.sin(a)
        m.target_rot = direction


class Dribble(SoccerSkill):
    """``dribble(direction)``: walk into the ball, keeping it in front, steering towards ``direction``.

    The ball is pushed by the robot's body. Forward speed drops while the ball is off-centre or
    the heading is far from ``direction``, so the robot does not lose the ball in a turn.
    """

    name: ClassVar[str] = "dribble"
    parameters: ClassVar = (("direction", Kind.DECIMAL),)

    def execute(self) -> None:
        """Request a walk into the ball, steering towards ``direction``."""
        wm, m = self.wm, self.motion
        turn = normalize_deg(self.parameter_values[self.parameter_offset] - wm.rotation)
        off_centre = wm.ball_rel_y
        m.mode = _WALK
        m.vx = MAX_FORWARD * max(0.2, 1.0 - abs(turn) / 60.0 - abs(off_centre) / 150.0)
        m.vy = max(-150.0, min(150.0, 2.5 * off_centre))
        m.vrot = max(-MAX_TURN, min(MAX_TURN, 2.0 * turn))


class Kick(SoccerSkill):
    """``kick(direction, strength)``: kick the ball towards a field ``direction`` [deg], ``strength`` 0..1.

    Asks the legs for a kick in this tick (the request is an event, repeated every tick while the
    option stays here) and creeps towards the ball so that it comes into reach. The legs only
    kick when the ball is within reach and within 30 degrees of the heading, and not during the
    one-second cooldown after a kick (``motion.kick_ready`` tells the behavior).
    """

    name: ClassVar[str] = "kick"
    parameters: ClassVar = (("direction", Kind.DECIMAL), ("strength", Kind.DECIMAL))

    def execute(self) -> None:
        """Request a kick towards ``direction`` and creep to the point behind the ball."""
        v, b, m, wm = self.parameter_values, self.parameter_offset, self.motion, self.wm
        direction = v[b]
        m.kick_strength = v[b + 1]
        m.kick_direction = normalize_deg(direction - wm.rotation)
        a = direction * RAD_PER_DEG
        m.mode = _WALK_TO
        m.target_x = wm.ball_x - 180.0 * math.cos(a)
        m.target_y = wm.ball_y - 180.0 * math.sin(a)
        m.target_rot = direction


#: Every skill of the soccer robot, in the order ``basic_behaviors.xabsl`` declares them.
SKILLS: tuple[type[SoccerSkill], ...] = (Stand, Walk, Turn, WalkTo, GoToBall, Dribble, Kick)
