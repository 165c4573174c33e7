"""The bench world: a small kinematic world for behaviors that come without a world of their own.

Robots (points with a heading) and a ball on a 6 m x 4 m field, no physics engine: a tick moves
robots by their commanded walk and the ball by its velocity with friction. It exists so that the
studio can run any behavior (a behavior folder such as ``examples/demo``, or an agents file
anywhere on disk) and so that the server tests run fast without pymunk. It is a world plug-in
like any other (:func:`example`, the default of ``server.examples.load_example``).

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
import re
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from engine.host import (
    DEFAULT_BEHAVIOR_HZ,
    DEFAULT_PHYSICS_HZ,
    Agent,
    AgentController,
    BehaviorSource,
    ExampleError,
    Scene,
    World,
    behavior_source,
    common_root,
)
from engine.ir.model import Program, short_name
from engine.runtime import BasicBehavior, Engine
from engine.trace.conformance import conformance_bindings
from engine.types import Value

FIELD_X, FIELD_Y = 3000.0, 2000.0  # half lengths, mm
VIEW_ANGLE, VIEW_DISTANCE = 30.0, 4000.0  # deg either side, mm
BALL_FRICTION = 0.6  # velocity kept per second
READY_MS = 500


class BenchAgent:
    """One robot of the bench world: pose, commanded walk, the values its plain input symbols read."""

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

    def __init__(self, world: BenchWorld, index: int) -> None:
        self.world = world
        self.index = index
        self.number = index + 1
        self.team = "bench"
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
        """Update the inputs the world knows (ball, game state) and clear last tick's commands."""
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
        """Nothing to do: the basic behaviors set speed and turn, ``BenchWorld.step`` moves."""


class BenchWorld:
    """The bench world, an ``engine.host.World`` (see the module docstring)."""

    def __init__(self, seed: int, n_agents: int = 2) -> None:
        self.seed = seed
        self.rng = random.Random(seed)
        self._agents = [BenchAgent(self, i) for i in range(n_agents)]
        self.ball = [self.rng.uniform(-1500, 1500), self.rng.uniform(-1000, 1000)]
        self.ball_velocity = [0.0, 0.0]
        self.time_s = 0.0
        self.kicks = 0
        self._playing = 3  # conformance value of game.state.playing; set by the adapter
        self._ready = 1

    @property
    def agents(self) -> Sequence[BenchAgent]:
        """The robots, in loop order."""
        return self._agents

    @property
    def finished(self) -> bool:
        """Never: the bench runs until stopped."""
        return False

    def game_state_value(self, now_ms: int) -> int:
        """The host value of ``game.state`` at ``now_ms``: ready first, then playing."""
        return self._ready if now_ms < READY_MS else self._playing

    def step(self, dt: float) -> None:
        """Move robots by their commands and the ball by its velocity."""
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
        """The field rectangle, the robots and body sizes (mm)."""
        return {
            "kind": "bench",
            "units": {"length": "mm", "angle": "deg", "time": "ms"},
            "field": {"x": [-FIELD_X, FIELD_X], "y": [-FIELD_Y, FIELD_Y]},
            "agents": [{"name": a.name, "team": a.team, "number": a.number} for a in self._agents],
            "robot_radius": 150,
            "ball_radius": 50,
        }

    def dynamic_scene(self) -> Scene:
        """Ball and robot poses (mm, degrees)."""
        return {
            "t": round(self.time_s * 1000),
            "ball": [round(self.ball[0]), round(self.ball[1])],
            "robots": [[round(a.x), round(a.y), round(a.heading, 1)] for a in self._agents],
        }

    def status(self) -> Scene:
        """Time and the number of kicks."""
        return {"time_ms": round(self.time_s * 1000), "finished": False, "kicks": self.kicks}


class _Skill(BasicBehavior):
    """A basic behavior of the bench world: ``run(agent, params)`` after the engine set them."""

    run: Callable[[BenchAgent, dict[str, Value]], None] = staticmethod(lambda agent, params: None)

    def __init__(self, agent: BenchAgent) -> None:
        super().__init__()
        self.agent = agent

    def execute(self) -> None:
        """Run the skill with the parameters by their declared names (the behavior's prefix stripped)."""
        params = {short_name(name, self.name): value for name, value in self.params.items()}
        type(self).run(self.agent, params)


def _walk(agent: BenchAgent, p: dict[str, Value]) -> None:
    agent.speed = float(p.get("speed", 0.0))
    agent.turn_to = float(p.get("direction", 0.0))


def _turn(agent: BenchAgent, p: dict[str, Value]) -> None:
    agent.rate = float(p.get("rate", 0.0))


def _kick(agent: BenchAgent, p: dict[str, Value]) -> None:
    agent.kick = float(p.get("strength", 1.0)) or 1.0


_SKILLS: dict[str, Callable[[BenchAgent, dict[str, Value]], None]] = {"walk": _walk, "turn": _turn, "kick": _kick}


class BenchController:
    """``AgentController`` of a bench robot: an engine on the kit's bindings plus the world's."""

    def __init__(self, agent: BenchAgent, program: Program) -> None:
        bindings, values = conformance_bindings(program)
        agent.values = values
        for behavior in program.behaviors.values():
            run = _SKILLS.get(behavior.name)
            if run is None:
                continue
            cls: Any = type(
                f"Bench_{behavior.name}",
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
        """One engine tick."""
        self.engine.execute(now_ms)


def _normalize(angle: float) -> float:
    return (angle + 180.0) % 360.0 - 180.0


class BenchExample:
    """The bench world as a world plug-in: every robot runs the one behavior set of ``path``.

    Args:
        path: a behavior folder (see :func:`find_agents_file`) or an agents file anywhere on disk.
        robots: how many robots.

    Raises:
        ExampleError: no agents file at ``path``, or a number of robots out of 1..20.
    """

    preload: tuple[str, ...] = ("server.bench_world",)
    behavior_hz = DEFAULT_BEHAVIOR_HZ
    physics_hz = DEFAULT_PHYSICS_HZ

    def __init__(self, path: Path, robots: int = 2) -> None:
        path = path.resolve()
        agents_file = find_agents_file(path) if path.is_dir() else path
        if isinstance(robots, bool) or not isinstance(robots, int) or not 1 <= robots <= 20:
            raise ExampleError(f"robots must be an integer in 1..20, got {robots!r}")
        self.n_agents = robots
        self.sources: tuple[BehaviorSource, ...] = (behavior_source(agents_file),)
        self.root = common_root(self.sources)
        self.name = self.sources[0].key

    def build_world(self, seed: int) -> World:
        """A bench world with ``robots`` robots."""
        return BenchWorld(seed, self.n_agents)

    def program_key(self, agent: Agent) -> str | None:
        """Every robot runs the one behavior set."""
        return self.sources[0].key

    def make_controller(self, agent: Agent, program: Program) -> tuple[AgentController, Engine]:
        """A :class:`BenchController` for a bench robot."""
        if not isinstance(agent, BenchAgent):
            raise TypeError("the bench world runs BenchWorld robots")
        controller = BenchController(agent, program)
        return controller, controller.engine


#: An agent declaration at the start of a line: what makes a file an agents file.
_AGENT_DECLARATION = re.compile(rb"^[ \t]*agent[ \t]+[A-Za-z_]", re.MULTILINE)


def find_agents_file(folder: Path) -> Path:
    """The agents file of a behavior folder: ``agents.xabsl``, else its one file declaring agents.

    Raises:
        ExampleError: no such file, or several files declare agents (the user must pick one).
    """
    conventional = folder / "agents.xabsl"
    if conventional.is_file():
        return conventional
    found = []
    for candidate in sorted(folder.glob("*.xabsl")):
        try:
            if _AGENT_DECLARATION.search(candidate.read_bytes()):
                found.append(candidate)
        except OSError:
            continue
    if len(found) == 1:
        return found[0]
    if found:
        names = ", ".join(f.name for f in found)
        raise ExampleError(f"{folder}: several files declare agents ({names}); give the agents file itself")
    raise ExampleError(
        f"{folder}: no agents.xabsl here, no file declaring agents and no studio.py saying how to run this folder"
    )


def example(path: Path, robots: int = 2) -> BenchExample:
    """The world plug-in factory of the bench world (``xabsl serve PATH --world bench``)."""
    return BenchExample(path, robots)
