"""The soccer world: the host contract (``xabsl_studio.engine.host.World``) over physics, referee and robots.

``build_world(seed)`` makes a match of two teams ("blue" = team 0, "red" = team 1) of 5 players
(1..7) on an SPL-like field. Each :class:`SoccerAgent` is one robot:

* ``agent.perception`` (:class:`~xabsl_studio.examples.soccer.perception.WorldModel`): what its behavior
  reads, in mm / degrees / ms, positions in the team frame (own goal at negative x);
* ``agent.motion`` (:class:`~xabsl_studio.examples.soccer.robot.MotionRequest`): what its behavior commands;
* ``agent.perception.outgoing``: the team message payload its behavior fills;
* ``agent.controller``: the brain slot, an XABSL engine (or, in tests, ``scripted``).

A behavior tick for the world is: ``sense`` (a physics snapshot read once per tick, team
messages delivered, each world model refreshed), ``controller.execute``, ``act`` (motion
requests to the legs, team messages sent), then ``step`` at the physics rate (pymunk, then the
referee looks at the ball). Determinism: every random number comes from one numpy ``Generator``
seeded with ``seed``, time is counted in integer nanoseconds, and nothing reads the wall clock.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from xabsl_studio.engine.host import AgentController, Scene
from xabsl_studio.examples.soccer import field
from xabsl_studio.examples.soccer.field import FieldDimensions, from_team_frame
from xabsl_studio.examples.soccer.game import MAX_PLAYERS, GameController, GameRules, GameState, kickoff_position
from xabsl_studio.examples.soccer.perception import (
    GaussianNoise,
    SensorModel,
    Snapshot,
    TeamChannel,
    WorldModel,
    perceive,
)
from xabsl_studio.examples.soccer.physics import BallParameters, RobotBodyParameters, SoccerPhysics
from xabsl_studio.examples.soccer.robot import MotionRequest, Robot, WalkLimits
from xabsl_studio.examples.soccer.units import DEG_PER_RAD, MM_PER_M, normalize_rad

TEAM_NAMES = ("blue", "red")

_READY = GameState.READY
_PLAYING = GameState.PLAYING
TEAM_COLORS = ("#1f6fd1", "#d1341f")


class SoccerAgent:
    """One robot of the match, as the host loop and the behavior bindings see it.

    ``name`` is the team name and the player number (``"blue3"``); number 1 is the goalie.
    """

    __slots__ = (
        "_world",
        "controller",
        "index",
        "motion",
        "name",
        "number",
        "perception",
        "robot",
        "team",
        "team_index",
    )

    def __init__(self, world: SoccerWorld, index: int, team_index: int, number: int, robot: Robot) -> None:
        self._world = world
        self.index = index
        self.team_index = team_index
        self.team = TEAM_NAMES[team_index]
        self.number = number
        self.name = f"{self.team}{number}"
        self.robot = robot
        self.controller: AgentController | None = None
        self.perception = WorldModel(number=number)
        self.motion = MotionRequest()

    def sense(self, now_ms: int) -> None:
        """Refresh ``perception`` from the world at ``now_ms`` (host hook)."""
        self._world._sense(self, now_ms)

    def act(self, now_ms: int) -> None:
        """Carry out ``motion`` and send the team message (host hook)."""
        self._world._act(self, now_ms)

    def __repr__(self) -> str:
        return f"SoccerAgent({self.name!r})"


class SoccerWorld:
    """A match between two robot teams; implements ``xabsl_studio.engine.host.World`` and the game's ``Referee``.

    Args:
        seed: the only source of randomness (perception noise).
        players_per_team: 1..7 robots per team.
        rules: game durations and placement rules.
        sensor: field of view, range, noise and team-message latency of every robot.
        dims: field dimensions.
        limits: walk and kick limits of every robot.

    Raises:
        ValueError: for a number of players outside 1..7.
    """

    def __init__(
        self,
        seed: int,
        players_per_team: int = 5,
        rules: GameRules | None = None,
        sensor: SensorModel | None = None,
        dims: FieldDimensions | None = None,
        limits: WalkLimits | None = None,
        ball: BallParameters | None = None,
        robot_body: RobotBodyParameters | None = None,
    ) -> None:
        if not 1 <= players_per_team <= MAX_PLAYERS:
            raise ValueError(f"players_per_team must be in 1..{MAX_PLAYERS}, got {players_per_team}")
        self.seed = seed
        self.rng = np.random.default_rng(seed)
        self.dims = dims or FieldDimensions()
        self.rules = rules or GameRules()
        self.sensor = sensor or SensorModel()
        self.physics = SoccerPhysics(self.dims, ball, robot_body)
        self.game = GameController(self.dims, self.rules, self.physics.ball_params.radius)
        self.players_per_team = players_per_team

        agents: list[SoccerAgent] = []
        for team_index in (0, 1):
            for number in range(1, players_per_team + 1):
                index = self.physics.add_robot(0.0, 0.0, 0.0)
                robot = Robot(self.physics, index, limits)
                agents.append(SoccerAgent(self, index, team_index, number, robot))
        self._agents = agents
        n = players_per_team
        self._opponents = (range(n, 2 * n), range(0, n))
        self._team_models = ([a.perception for a in agents[:n]], [a.perception for a in agents[n:]])
        latency = self.sensor.message_latency_ms
        self.channels = (TeamChannel(latency), TeamChannel(latency))
        self._delivered_ms = [-1, -1]
        self._last_sent_ms = [-(10**9)] * len(agents)
        self.noise = GaussianNoise(self.rng)
        self._game_info: list[tuple[int, int, bool, int, int, int, int]] = [(0, 1, False, 0, 0, 0, 1)] * 2
        # Per agent: its kick-off position [mm] when the other team kicks off, and when its own
        # team does (indexed by ``own_kickoff``: a tuple index, not a dict lookup, every sense).
        self._kickoff_mm = [
            tuple(
                (kickoff_position(a.number, kicking)[0] * MM_PER_M, kickoff_position(a.number, kicking)[1] * MM_PER_M)
                for kicking in (False, True)
            )
            for a in agents
        ]
        self._snapshot = Snapshot(len(agents))
        self._steps = 0
        self._snapshot_steps = -1

        self.place_for_kickoff(only_misplaced=False)
        self.place_ball(0.0, 0.0)

    # ------------------------------------------------------------------------- host contract

    @property
    def agents(self) -> Sequence[SoccerAgent]:
        """Every robot of both teams, blue first."""
        return self._agents

    @property
    def finished(self) -> bool:
        """Whether the game controller ended the match."""
        return self.game.finished

    @property
    def time_ms(self) -> int:
        """Simulated time since kick-off (ms)."""
        return self.game.time_ms

    def step(self, dt: float) -> None:
        """Advance physics by ``dt`` seconds, then let the referee judge the ball's position."""
        physics = self.physics
        physics.step(dt)
        self._steps += 1
        bx, by = physics.ball_position()
        self.game.step(dt, bx, by, self)

    def static_scene(self) -> Scene:
        """Return the field (see ``field.static_scene``), teams, agents and body sizes, in mm."""
        scene: Scene = {"kind": "soccer", "units": {"length": "mm", "angle": "deg", "time": "ms"}}
        scene.update(field.static_scene(self.dims))
        scene["teams"] = [{"name": n, "color": c} for n, c in zip(TEAM_NAMES, TEAM_COLORS, strict=True)]
        scene["agents"] = [{"name": a.name, "team": a.team, "number": a.number} for a in self._agents]
        scene["robot_radius"] = round(self.physics.robot_params.radius * MM_PER_M)
        scene["ball_radius"] = round(self.physics.ball_params.radius * MM_PER_M)
        return scene

    def dynamic_scene(self) -> Scene:
        """Return the moving things in world-frame mm / degrees, compact.

        ``{"t": ms, "ball": [x, y], "robots": [[x, y, heading_deg], ...] (agent order),
        "state": game state id, "score": [blue, red]}``; ints except headings (0.1 degree).
        """
        physics = self.physics
        bx, by = physics.ball.position
        robots = []
        for body in physics.robots:
            x, y = body.position
            robots.append([round(x * MM_PER_M), round(y * MM_PER_M), round(normalize_rad(body.angle) * DEG_PER_RAD, 1)])
        return {
            "t": self.time_ms,
            "ball": [round(bx * MM_PER_M), round(by * MM_PER_M)],
            "robots": robots,
            "state": int(self.game.state),
            "score": list(self.game.score),
        }

    def status(self) -> Scene:
        """Return the referee's view: time, state, half, score, sides, kick-off, goals, outs."""
        game = self.game
        return {
            "time_ms": self.time_ms,
            "finished": game.finished,
            "game_state": game.state.name.lower(),
            "half": game.half,
            "half_time_left_ms": game.half_time_left_ms,
            "teams": list(TEAM_NAMES),
            "score": list(game.score),
            "sides": list(game.side),
            "kickoff_team": TEAM_NAMES[game.kickoff_team],
            "goals": [{"time_ms": t, "team": TEAM_NAMES[team]} for t, team in game.goals_log],
            "outs": game.outs,
        }

    # ------------------------------------------------------------------------------ referee

    def place_ball(self, x: float, y: float) -> None:
        """Put the ball at rest at a world point [m]."""
        self.physics.place_ball(x, y)
        self._snapshot_steps = -1

    def place_robot(self, agent: SoccerAgent, x: float, y: float, heading: float) -> None:
        """Put a robot at rest at a world pose [m, rad] (referee, tests, the studio's drag)."""
        self.physics.place_robot(agent.index, x, y, heading)
        agent.robot.halt()
        self._snapshot_steps = -1

    def place_for_kickoff(self, only_misplaced: bool) -> None:
        """Put robots on their kick-off poses: all of them, or those not within the tolerance."""
        game = self.game
        tolerance = self.rules.placement_tolerance
        for agent in self._agents:
            side = game.side[agent.team_index]
            kx, ky, kth = kickoff_position(agent.number, game.kickoff_team == agent.team_index)
            wx, wy = from_team_frame(kx, ky, side)
            wth = kth if side > 0 else kth + math.pi
            if only_misplaced:
                x, y, theta = self.physics.robot_pose(agent.index)
                if math.hypot(x - wx, y - wy) <= tolerance and abs(normalize_rad(theta - wth)) <= math.pi / 4:
                    continue
            self.place_robot(agent, wx, wy, wth)

    # -------------------------------------------------------------------------- agent hooks

    def pose_snapshot(self) -> Snapshot:
        """Every robot's pose and the ball's position now, read from physics once per step (reused in place)."""
        snap = self._snapshot
        if self._snapshot_steps != self._steps:
            self._snapshot_steps = self._steps
            snap.ball_x, snap.ball_y = self.physics.read_poses(snap.x, snap.y, snap.theta)
        return snap

    def _sense(self, agent: SoccerAgent, now_ms: int) -> None:
        snap = self.pose_snapshot()
        team = agent.team_index
        if self._delivered_ms[team] != now_ms:
            # Once per team and tick: deliver team messages, read what the referee says.
            self._delivered_ms[team] = now_ms
            self.channels[team].deliver(now_ms, self._team_models[team])
            game = self.game
            self._game_info[team] = (
                int(game.state),
                game.half,
                game.kickoff_team == team,
                game.score[team],
                game.score[1 - team],
                game.half_time_left_ms,
                game.side[team],
            )
        state, half, own_kickoff, own_score, opponent_score, time_left, side = self._game_info[team]
        wm = agent.perception
        perceive(wm, snap, agent.index, side, self._opponents[team], self.sensor, self.noise, now_ms)
        wm.game_state = state
        wm.half = half
        wm.own_kickoff = own_kickoff
        wm.own_score = own_score
        wm.opponent_score = opponent_score
        wm.half_time_left_ms = time_left
        wm.kickoff_x, wm.kickoff_y = self._kickoff_mm[agent.index][own_kickoff]
        wm.kick_ready = agent.robot.kick_ready(now_ms)

    def _act(self, agent: SoccerAgent, now_ms: int) -> None:
        game = self.game
        index = agent.index
        # Sensing and acting see the same physics state (no step in between), so the pose read
        # for perception serves the legs too.
        snap = self.pose_snapshot()
        pose = (snap.x[index], snap.y[index], snap.theta[index])
        # ``game.may_move`` / ``game.may_kick``, without two property calls per robot and tick.
        state = game.state
        may_kick = state == _PLAYING
        agent.robot.act(agent.motion, now_ms, pose, game.side[agent.team_index], may_kick or state == _READY, may_kick)
        if now_ms - self._last_sent_ms[index] >= self.sensor.message_interval_ms:
            self._last_sent_ms[index] = now_ms
            self.channels[agent.team_index].send(now_ms, agent.number, agent.perception.outgoing)


def build_world(
    seed: int,
    players_per_team: int = 5,
    half_duration_s: float = 600.0,
    **options: Any,
) -> SoccerWorld:
    """Build a match ready to run: robots on their kick-off poses, ball on the centre spot.

    Args:
        seed: the only source of randomness.
        players_per_team: robots per team (1..7).
        half_duration_s: seconds of play per half (SPL: 600).
        **options: further ``SoccerWorld`` arguments (``rules`` overrides ``half_duration_s``;
            ``sensor``, ``dims``, ``limits``, ``ball``, ``robot_body``).

    Returns:
        The world, in game state INITIAL, with no controllers plugged in.

    Example::

        world = build_world(seed=7, players_per_team=3, half_duration_s=60)
        for agent in world.agents:
            agent.controller = make_engine(agent)   # reads agent.perception, writes agent.motion
        run_headless(world, duration_s=200)
    """
    options.setdefault("rules", GameRules(half_duration_s=half_duration_s))
    return SoccerWorld(seed, players_per_team, **options)


__all__ = ["TEAM_NAMES", "GameState", "SoccerAgent", "SoccerWorld", "build_world"]
