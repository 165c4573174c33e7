"""A small kinematic world for behaviors that come without a world of their own (``examples/demo``).

Robots (points with a heading) and a ball on a 6 m x 4 m field, no physics engine: a tick moves
robots by their commanded walk and the ball by its velocity with friction. It exists so that the
studio can run any behavior folder (and so that the server tests run fast without pymunk).

Symbols are bound by name, on top of the conformance kit's bindings (``engine.trace.conformance``)
so that *any* program links: the inputs the world knows (``ball.seen``, ``ball.distance``,
``ball.angle``, ``ball.time_since_seen``, ``game.state``) follow the world, every other plain
input keeps the kit's constant value, and the basic behaviors ``stand``, ``walk(speed,
direction)``, ``turn(rate)`` and ``kick(strength)`` move the robot; others only count calls.

``game.state`` is ``ready`` for the first half second, then ``playing`` (the demo's root option
waits while the game does not run, so the activation path changes visibly at the start).
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable, Sequence
from typing import Any

from engine.host import AgentController, Scene
from engine.ir.model import Program, short_name
from engine.runtime import BasicBehavior, Engine
from engine.trace.conformance import conformance_bindings
from engine.types import Value

FIELD_X, FIELD_Y = 3000.0, 2000.0  # half lengths, mm
VIEW_ANGLE, VIEW_DISTANCE = 30.0, 4000.0  # deg either side, mm
BALL_FRICTION = 0.6  # velocity kept per second
READY_MS = 500


class DemoAgent:
    """One robot: pose, commanded walk, the value table its plain input symbols read."""

    __slots__ = (
        "controller",
        "heading",
        "index",
        "kick",
        "last_seen_ms",
        "name",
        "number",
        "rate",
        "speed",
        "team",
        "turn_to",
        "values",
        "world",
        "x",
        "y",
    )

    def __init__(self, world: DemoWorld, index: int) -> None:
        self.world = world
        self.index = index
        self.number = index + 1
        self.team = "demo"
        self.name = f"robot{self.number}"
        self.controller: AgentController | None = None
        self.values: dict[str, Value] = {}
        self.x = -1000.0 + 600.0 * index
        self.y = -800.0 + 500.0 * index
        self.heading = 90.0 * index
        self.last_seen_ms = -(10**9)
        self.speed = 0.0  # mm/s forward
        self.turn_to: float | None = None  # relative direction to turn towards, deg
        self.rate = 0.0  # deg/s
        self.kick = 0.0

    def sense(self, now_ms: int) -> None:
        world, values = self.world, self.values
        dx, dy = world.ball[0] - self.x, world.ball[1] - self.y
        distance = math.hypot(dx, dy)
        angle = _normalize(math.degrees(math.atan2(dy, dx)) - self.heading)
        seen = distance < VIEW_DISTANCE and abs(angle) < VIEW_ANGLE
        if seen:
            self.last_seen_ms = now_ms
        known = {
            "ball.seen": seen,
            "ball.distance": distance,
            "ball.angle": angle,
            "ball.time_since_seen": float(min(now_ms - self.last_seen_ms, 10**6)),
            "game.state": world.game_state_value(now_ms),
        }
        for name, value in known.items():
            if name in values:
                values[name] = value
        self.speed, self.turn_to, self.rate, self.kick = 0.0, None, 0.0, 0.0

    def act(self, now_ms: int) -> None:
        """Nothing to do: the basic behaviors set speed and turn, ``DemoWorld.step`` moves."""


class DemoWorld:
    """Implements ``engine.host.World`` for the demo (see the module docstring)."""

    def __init__(self, seed: int, n_agents: int = 2) -> None:
        self.seed = seed
        self.rng = random.Random(seed)
        self._agents = [DemoAgent(self, i) for i in range(n_agents)]
        self.ball = [self.rng.uniform(-1500, 1500), self.rng.uniform(-1000, 1000)]
        self.ball_velocity = [0.0, 0.0]
        self.time_s = 0.0
        self.kicks = 0
        self._playing = 3  # conformance value of game.state.playing; set by the adapter
        self._ready = 1

    @property
    def agents(self) -> Sequence[DemoAgent]:
        return self._agents

    @property
    def finished(self) -> bool:
        return False

    def game_state_value(self, now_ms: int) -> int:
        return self._ready if now_ms < READY_MS else self._playing

    def step(self, dt: float) -> None:
        self.time_s += dt
        for a in self._agents:
            if a.turn_to is not None:
                turn = max(-180.0 * dt, min(180.0 * dt, a.turn_to))
                a.heading = _normalize(a.heading + turn)
                a.turn_to -= turn
            a.heading = _normalize(a.heading + a.rate * dt)
            rad = math.radians(a.heading)
            a.x = max(-FIELD_X, min(FIELD_X, a.x + math.cos(rad) * a.speed * dt))
            a.y = max(-FIELD_Y, min(FIELD_Y, a.y + math.sin(rad) * a.speed * dt))
            if a.kick > 0.0 and math.hypot(self.ball[0] - a.x, self.ball[1] - a.y) < 350.0:
                self.ball_velocity = [math.cos(rad) * 2000.0 * a.kick, math.sin(rad) * 2000.0 * a.kick]
                self.kicks += 1
                a.kick = 0.0
        keep = BALL_FRICTION**dt
        for axis, limit in ((0, FIELD_X), (1, FIELD_Y)):
            self.ball[axis] += self.ball_velocity[axis] * dt
            self.ball_velocity[axis] *= keep
            if abs(self.ball[axis]) > limit:
                self.ball[axis] = math.copysign(limit, self.ball[axis])
                self.ball_velocity[axis] = -self.ball_velocity[axis]

    def static_scene(self) -> Scene:
        return {
            "kind": "demo",
            "units": {"length": "mm", "angle": "deg", "time": "ms"},
            "field": {"x": [-FIELD_X, FIELD_X], "y": [-FIELD_Y, FIELD_Y]},
            "agents": [{"name": a.name, "team": a.team, "number": a.number} for a in self._agents],
            "robot_radius": 150,
            "ball_radius": 50,
        }

    def dynamic_scene(self) -> Scene:
        return {
            "t": round(self.time_s * 1000),
            "ball": [round(self.ball[0]), round(self.ball[1])],
            "robots": [[round(a.x), round(a.y), round(a.heading, 1)] for a in self._agents],
        }

    def status(self) -> Scene:
        return {"time_ms": round(self.time_s * 1000), "finished": False, "kicks": self.kicks}


class _Skill(BasicBehavior):
    """A basic behavior of the demo world: ``run(agent, params)`` after the engine set them."""

    run: Callable[[DemoAgent, dict[str, Value]], None] = staticmethod(lambda agent, params: None)

    def __init__(self, agent: DemoAgent) -> None:
        super().__init__()
        self.agent = agent

    def execute(self) -> None:
        params = {short_name(name, self.name): value for name, value in self.params.items()}
        type(self).run(self.agent, params)


def _walk(agent: DemoAgent, p: dict[str, Value]) -> None:
    agent.speed = float(p.get("speed", 0.0))
    agent.turn_to = float(p.get("direction", 0.0))


def _turn(agent: DemoAgent, p: dict[str, Value]) -> None:
    agent.rate = float(p.get("rate", 0.0))


def _kick(agent: DemoAgent, p: dict[str, Value]) -> None:
    agent.kick = float(p.get("strength", 1.0)) or 1.0


_SKILLS: dict[str, Callable[[DemoAgent, dict[str, Value]], None]] = {"walk": _walk, "turn": _turn, "kick": _kick}


class DemoController:
    """``AgentController`` of a demo robot: an engine on the kit's bindings plus the world's."""

    def __init__(self, agent: DemoAgent, program: Program) -> None:
        bindings, values = conformance_bindings(program)
        agent.values = values
        for behavior in program.behaviors.values():
            run = _SKILLS.get(behavior.name)
            if run is None:
                continue
            cls: Any = type(
                f"Demo_{behavior.name}",
                (_Skill,),
                {"name": behavior.name, "parameters": behavior.params, "run": staticmethod(run)},
            )
            bindings.behavior(cls(agent))
        enum = program.enums.get("game.state")
        if enum is not None and not enum.internal:
            elements = list(enum.elements)
            world = agent.world
            world._ready = elements.index("game.state.ready") if "game.state.ready" in elements else 0
            world._playing = elements.index("game.state.playing") if "game.state.playing" in elements else 0
        self.engine = Engine(bindings, program, agent_name=agent.name)

    def execute(self, now_ms: int) -> None:
        self.engine.execute(now_ms)


def _normalize(angle: float) -> float:
    return (angle + 180.0) % 360.0 - 180.0
