"""A scripted placeholder controller: every player chases the ball and kicks at the opponent goal.

PLACEHOLDER, for tests and the physics benchmark only. The real soccer team is XABSL behavior
(``examples/soccer/behavior``) run by the engine; this class exists so that the world can be
exercised before that team exists, and so that physics and perception can be measured without
engine time. It reads only the robot's world model and writes only its motion request and team
message, exactly the interface the XABSL bindings use.

Policy, in team frame (own goal at -x): in READY walk to the kick-off position; in PLAYING, if
the ball estimate is older than two seconds turn on the spot to find it; otherwise walk to a point
behind the ball on the line from the opponent goal through the ball, and kick towards the goal
when the ball is close in front.
"""

from __future__ import annotations

import math

from xabsl_studio.examples.soccer.game import GameState
from xabsl_studio.examples.soccer.perception import WorldModel
from xabsl_studio.examples.soccer.robot import MotionMode, MotionRequest
from xabsl_studio.examples.soccer.units import DEG_PER_RAD, normalize_deg
from xabsl_studio.examples.soccer.world import SoccerWorld

_OPPONENT_GOAL_X = 4500.0  # mm, team frame
_BEHIND_BALL = 250.0  # mm: where to stand behind the ball before kicking


class ChaseBallController:
    """Placeholder brain: chase the ball and kick towards the opponent goal (not XABSL)."""

    __slots__ = ("motion", "wm")

    def __init__(self, perception: WorldModel, motion: MotionRequest) -> None:
        self.wm = perception
        self.motion = motion

    def execute(self, now_ms: int) -> None:
        """Walk to the ball and kick it towards the opponent goal."""
        wm, motion = self.wm, self.motion
        state = wm.game_state
        if state == GameState.READY:
            motion.mode = MotionMode.WALK_TO
            motion.target_x, motion.target_y, motion.target_rot = wm.kickoff_x, wm.kickoff_y, 0.0
            return
        if state != GameState.PLAYING:
            motion.mode = MotionMode.STAND
            return
        wm.outgoing["ball_distance"] = wm.ball_distance
        if wm.ball_time_since_seen > 2000:
            motion.mode = MotionMode.WALK
            motion.vx, motion.vy, motion.vrot = 0.0, 0.0, 60.0
            return

        # Direction from the ball to the opponent goal, in team frame.
        gx, gy = _OPPONENT_GOAL_X - wm.ball_x, -wm.ball_y
        goal_dir = math.atan2(gy, gx)
        goal_angle_rel = normalize_deg(goal_dir * DEG_PER_RAD - wm.rotation)
        if wm.ball_distance < 320.0 and abs(wm.ball_angle) < 25.0 and abs(goal_angle_rel) < 35.0:
            motion.kick_strength = 1.0
            motion.kick_direction = goal_angle_rel
        # Stand behind the ball facing the goal; the walk's P-controller does the rest.
        motion.mode = MotionMode.WALK_TO
        motion.target_x = wm.ball_x - _BEHIND_BALL * math.cos(goal_dir)
        motion.target_y = wm.ball_y - _BEHIND_BALL * math.sin(goal_dir)
        motion.target_rot = goal_dir * DEG_PER_RAD


def plug_scripted_team(world: SoccerWorld) -> None:
    """Give every agent of a soccer world a :class:`ChaseBallController` (tests, benchmarks)."""
    for agent in world.agents:
        agent.controller = ChaseBallController(agent.perception, agent.motion)
