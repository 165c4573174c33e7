"""The bench world: a small kinematic world for behaviors that come without a world of their own.

Robots (points with a heading) and a ball on a 6 m x 4 m field, no physics engine: a tick moves
robots by their commanded walk and the ball by its velocity with friction. It exists so that a
team can run its own behavior (a behavior folder, or an agents file anywhere on disk) and test
single options by hand, and so that the server tests run fast without pymunk. It is a world
plug-in like any other (:func:`example`, the default of ``xabsl_studio.engine.worlds.loader.load_example``).

Every name of the program is bound (:class:`BenchController`), so *any* behavior set links:

* plain input symbols read a value per robot: the inputs the world knows (``ball.seen``,
  ``ball.distance``, ``ball.angle``, ``ball.time_since_seen``, ``game.state``) follow the world;
  every other one keeps the value last set by hand (world command ``set_input``) or by the input
  trace (``--inputs FILE.jsonl``, the ``xabsl trace`` format, played on the behavior clock so it
  pauses and scrubs with the session); a world input set so leaves the world's control;
* input functions (input symbols with parameters) with a common mathematical meaning
  (``abs(value)``, ``atan2(y, x)``, ``vector.abs(x, y)``…, matched by name and parameters in
  ``xabsl_studio.engine.worlds.benchmath``) are computed; the others return the value set by hand
  for that symbol (``set_function``; 0, false or the first element until then), never a made-up
  function of the arguments; a computed one set by hand returns the value set until released
  (``follow_world``); each tick's calls and their arguments are in the dynamic scene (``calls``);
* a bench file (``bench.toml`` beside the agents file, ``xabsl_studio.engine.worlds.benchfile``)
  computes further input functions and plain inputs by expression and drives the robot's pose
  from output symbols;
* basic behaviors ``walk(speed, direction)``, ``turn(rate)`` and ``kick(strength)`` move the
  robot, others run without effect;
* a bindings module (``--bindings FILE.py``, docs/own-behaviors.md) replaces any of these with
  Python of the team's own through ``xabsl_studio.engine.runtime.Bindings``.

``game.state`` is ``ready`` for the first half second, then ``playing`` (the demo's root option
waits while the game does not run, so the activation path changes visibly at the start).
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import math
import random
import re
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from xabsl_studio.engine.errors import EngineError, ValueConversionError
from xabsl_studio.engine.host import (
    DEFAULT_BEHAVIOR_HZ,
    DEFAULT_PHYSICS_HZ,
    Agent,
    AgentController,
    BehaviorSource,
    ExampleError,
    Scene,
    World,
    WorldCommandError,
    behavior_source,
    common_root,
)
from xabsl_studio.engine.ir.model import InputSymbol, Program, short_name
from xabsl_studio.engine.runtime import BasicBehavior, Bindings, Engine
from xabsl_studio.engine.runtime.values import EnumValues, coerce
from xabsl_studio.engine.types import Kind, Value
from xabsl_studio.engine.worlds import benchmath
from xabsl_studio.engine.worlds.benchfile import BenchFile, BenchFileError, Entry, Getter, Resolver, find_bench_file

FIELD_X, FIELD_Y = 3000.0, 2000.0  # half lengths, mm
VIEW_ANGLE, VIEW_DISTANCE = 30.0, 4000.0  # deg either side, mm
BALL_FRICTION = 0.6  # velocity kept per second
READY_MS = 500


class BenchAgent:
    """One robot of the bench world: pose, commanded walk, the values its input symbols read.

    What a bindings module may use: ``name``, ``number``, ``x``, ``y`` (mm), ``heading`` (deg),
    ``now_ms``, ``world`` (``world.ball``: [x, y] mm), ``values`` (plain inputs by name) and the
    commands ``speed`` (mm/s), ``side`` (mm/s, to the left), ``rate`` (deg/s), ``turn_to`` (deg,
    relative), ``kick`` (0..1),
    which the world applies after the tick.
    """

    __slots__ = (
        "calls",
        "controller",
        "functions",
        "hand",
        "heading",
        "index",
        "kick",
        "last_seen_ms",
        "name",
        "now_ms",
        "number",
        "rate",
        "side",
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
        #: plain input symbols by name (host values)
        self.values: dict[str, Value] = {}
        #: plain inputs set by hand or by the input trace: the world no longer moves them
        self.hand: set[str] = set()
        #: the value set by hand per input function without a binding (host values)
        self.functions: dict[str, Value] = {}
        #: this tick's calls per input function: ``[(arguments, value), ...]``
        self.calls: dict[str, list[tuple[tuple[Value, ...], Value]]] = {}
        self.now_ms = 0
        self.x = -1000.0 + 600.0 * index
        self.y = -800.0 + 500.0 * index
        self.heading = 90.0 * index
        self.last_seen_ms = -(10**9)
        self.speed = 0.0  # mm/s forward
        self.side = 0.0  # mm/s to the left
        self.turn_to: float | None = None  # relative direction to turn towards, deg
        self.rate = 0.0  # deg/s
        self.kick = 0.0

    def sense(self, now_ms: int) -> None:
        """Update the inputs the world knows (ball, game state) and clear last tick's commands."""
        world, values, hand = self.world, self.values, self.hand
        self.now_ms = now_ms
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
            if name in values and name not in hand:
                values[name] = value
        if self.calls:
            self.calls = {}
        self.speed, self.side, self.turn_to, self.rate, self.kick = 0.0, 0.0, None, 0.0, 0.0

    def act(self, now_ms: int) -> None:
        """Nothing to do: the basic behaviors set speed and turn, ``BenchWorld.step`` moves."""


#: The inputs the bench world computes itself.
WORLD_INPUTS = ("ball.seen", "ball.distance", "ball.angle", "ball.time_since_seen", "game.state")


class BenchWorld:
    """The bench world, an ``xabsl_studio.engine.host.World`` and ``CommandableWorld`` (see the module docstring)."""

    def __init__(self, seed: int, n_agents: int = 2) -> None:
        self.seed = seed
        self.rng = random.Random(seed)
        self._agents = [BenchAgent(self, i) for i in range(n_agents)]
        self.ball = [self.rng.uniform(-1500, 1500), self.rng.uniform(-1000, 1000)]
        self.ball_velocity = [0.0, 0.0]
        self.time_s = 0.0
        self.kicks = 0
        #: host values of game.state.playing and .ready (set by the controller from the bindings)
        self.playing_value = 3
        self.ready_value = 1
        #: the input trace playing, the user's bindings module (for the scene)
        self.trace: InputTrace | None = None
        self.bindings_file: Path | None = None

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
        return self.ready_value if now_ms < READY_MS else self.playing_value

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
            cos, sin = math.cos(rad), math.sin(rad)
            a.x = max(-FIELD_X, min(FIELD_X, a.x + (cos * a.speed - sin * a.side) * dt))
            a.y = max(-FIELD_Y, min(FIELD_Y, a.y + (sin * a.speed + cos * a.side) * dt))
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

    def _controllers(self) -> list[BenchController]:
        return [a.controller for a in self._agents if isinstance(a.controller, BenchController)]

    def static_scene(self) -> Scene:
        """The field rectangle, the robots and body sizes (mm); what can be set by hand (``bench``)."""
        scene: Scene = {
            "kind": "bench",
            "units": {"length": "mm", "angle": "deg", "time": "ms"},
            "field": {"x": [-FIELD_X, FIELD_X], "y": [-FIELD_Y, FIELD_Y]},
            "agents": [{"name": a.name, "team": a.team, "number": a.number} for a in self._agents],
            "robot_radius": 150,
            "ball_radius": 50,
            "commands": self.commands(),
        }
        controllers = self._controllers()
        if controllers:
            controller = controllers[0]  # every robot runs the same behavior set on the same bindings
            inputs = controller.program.inputs.values()
            scene["bench"] = {
                "world_inputs": [s.name for s in inputs if s.name in controller.followed and not s.params],
                "bound": controller.bound,
                "functions": [s.name for s in inputs if s.params and s.name not in controller.bound],
                # what the bench computes itself, by input function: "abs(value)", "bench.toml: x - robot.x"
                "computed": dict(controller.computed),
                "bindings": str(self.bindings_file) if self.bindings_file is not None else None,
                "bench_file": str(controller.bench_file.path) if controller.bench_file is not None else None,
                "trace": {
                    "file": str(self.trace.path),
                    "lines": len(self.trace.lines),
                    "end_ms": self.trace.lines[-1].t if self.trace.lines else 0,
                }
                if self.trace is not None
                else None,
            }
        return scene

    def dynamic_scene(self) -> Scene:
        """Ball and robot poses (mm, degrees); per robot the input functions' calls and the hand-set names."""
        scene: Scene = {
            "t": round(self.time_s * 1000),
            "ball": [round(self.ball[0]), round(self.ball[1])],
            "robots": [[round(a.x), round(a.y), round(a.heading, 1)] for a in self._agents],
        }
        bench: list[dict[str, Any]] = []
        for a in self._agents:
            controller = a.controller
            if not isinstance(controller, BenchController):
                bench.append({})
                continue
            show = controller.index_of
            bench.append(
                {
                    "calls": {
                        name: [[list(args), show(name, value)] for args, value in calls]
                        for name, calls in a.calls.items()
                    },
                    "functions": {name: show(name, value) for name, value in a.functions.items()},
                    "hand": sorted(a.hand),
                }
            )
        scene["bench"] = bench
        return scene

    def status(self) -> Scene:
        """Time and the number of kicks."""
        return {"time_ms": round(self.time_s * 1000), "finished": False, "kicks": self.kicks}

    # -- world commands: values by hand ----------------------------------------------------------

    def commands(self) -> list[dict[str, Any]]:
        """``set_input``, ``set_function`` and ``follow_world`` (docs/protocol.md, the bench world)."""
        robot = {"name": "robot", "type": "number", "choices": None, "default": 0}
        symbol = {"name": "symbol", "type": "string", "choices": None, "default": None}
        value = {"name": "value", "type": "number", "choices": None, "default": None}
        return [
            {
                "name": "set_input",
                "label": "Set input",
                "group": "bench",
                "doc": "a plain input symbol reads this value until set again (enum: element index or name)",
                "args": [robot, symbol, value],
            },
            {
                "name": "set_function",
                "label": "Set input function",
                "group": "bench",
                "doc": "an input function without a binding returns this value, whatever its arguments",
                "args": [robot, symbol, value],
            },
            {
                "name": "follow_world",
                "label": "Follow the world",
                "group": "bench",
                "doc": "an input the world computes (ball.*, game.state, the bench file's) follows the world "
                "again; a computed input function is computed again",
                "args": [robot, symbol],
            },
        ]

    def command(self, name: str, args: dict[str, Any]) -> Any:
        """Carry out a bench command (see :meth:`commands`)."""
        if name not in ("set_input", "set_function", "follow_world"):
            raise WorldCommandError(f"unknown command {name!r} (set_input, set_function, follow_world)")
        allowed = {"robot", "symbol"} if name == "follow_world" else {"robot", "symbol", "value"}
        extra = set(args) - allowed
        if extra:
            raise WorldCommandError(f"{name}: unknown argument {sorted(extra)[0]!r}")
        index = args.get("robot")
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < len(self._agents):
            raise WorldCommandError(f"{name}: robot must be a robot id in 0..{len(self._agents) - 1}")
        agent = self._agents[index]
        controller = agent.controller
        if not isinstance(controller, BenchController):
            raise WorldCommandError(f"{name}: robot {index} runs no XABSL engine")
        symbol = args.get("symbol")
        if not isinstance(symbol, str):
            raise WorldCommandError(f"{name}: symbol must be an input symbol name")
        if name == "follow_world":
            if symbol in controller.computed:
                agent.functions.pop(symbol, None)
                return None
            if symbol not in controller.followed:
                known = sorted(controller.followed) + sorted(controller.computed)
                raise WorldCommandError(f"follow_world: the bench does not compute {symbol!r} ({', '.join(known)})")
            agent.hand.discard(symbol)
            return None
        if "value" not in args:
            raise WorldCommandError(f"{name}: value is missing")
        try:
            value = controller.convert(symbol, args["value"], plain=name == "set_input", by_index=True)
        except BenchInputError as error:
            raise WorldCommandError(f"{name}: {error}") from None
        if name == "set_input":
            agent.values[symbol] = value
            agent.hand.add(symbol)
        else:
            agent.functions[symbol] = value
        return None


class _Skill(BasicBehavior):
    """A basic behavior of the bench world: ``run(agent, params)`` after the engine set them."""

    run: Callable[[BenchAgent, dict[str, Value]], None] = staticmethod(lambda agent, params: None)

    def __init__(self, agent: BenchAgent) -> None:
        super().__init__()
        self.agent = agent
        self.calls = 0

    def execute(self) -> None:
        """Run the skill with the parameters by their declared names (the behavior's prefix stripped)."""
        self.calls += 1
        params = {short_name(name, self.name): value for name, value in self.params.items()}
        type(self).run(self.agent, params)


def _walk(agent: BenchAgent, p: dict[str, Value]) -> None:
    agent.speed = float(p.get("speed", 0.0))
    agent.turn_to = float(p.get("direction", 0.0))


def _turn(agent: BenchAgent, p: dict[str, Value]) -> None:
    agent.rate = float(p.get("rate", 0.0))


def _kick(agent: BenchAgent, p: dict[str, Value]) -> None:
    agent.kick = float(p.get("strength", 1.0)) or 1.0


def _nothing(agent: BenchAgent, p: dict[str, Value]) -> None:
    """A basic behavior the bench does not know: its calls show in the activation path, nothing moves."""


_SKILLS: dict[str, Callable[[BenchAgent, dict[str, Value]], None]] = {"walk": _walk, "turn": _turn, "kick": _kick}

#: At most this many distinct calls of one input function are kept per tick (the scene shows them).
MAX_CALLS = 8


def _initial(kind: Kind) -> Value:
    return 0.0 if kind is Kind.DECIMAL else (False if kind is Kind.BOOLEAN else 0)


class BenchController:
    """``AgentController`` of a bench robot: an engine on the bench's bindings and the user's.

    The bench binds every name of the program: external enumerations (element *i* has value
    *i*), plain inputs (read from :attr:`BenchAgent.values`: set by the world, by the bench file,
    by hand or by the input trace), input functions (computed by the bench file's expression or
    by their common mathematical meaning, else a value set by hand per symbol, initially 0 /
    false / the first element; every call is recorded with its arguments), outputs (engine
    storage) and basic behaviors (``walk``, ``turn``, ``kick`` move the robot, others only run).
    A bindings module (``--bindings``) then replaces any of these through the same
    ``xabsl_studio.engine.runtime.Bindings`` API. The bench file's ``[pose]`` drives the robot
    after each tick.
    """

    def __init__(
        self,
        agent: BenchAgent,
        program: Program,
        user: BindingsModule | None = None,
        trace: InputTrace | None = None,
        bench_file: BenchFile | None = None,
    ) -> None:
        self.agent = agent
        self.program = program
        self.bindings = bindings = Bindings()
        self.bench_file = bench_file
        #: what the bench computes, by input function name: the studio's "computed: …"
        self.computed: dict[str, str] = {}
        #: plain inputs the bench file computes: getters of the robot, applied before each tick
        self.followers: dict[str, Getter] = {}
        #: the inputs that follow the world (or the bench file) until set by hand
        self.followed: set[str] = set(WORLD_INPUTS)
        agent.values = {}
        agent.functions = {}
        ours = self._bind_missing(program)
        if user is not None:
            user.bind(bindings, agent)
        #: names of the input symbols the bindings module supplies (not settable by hand)
        self.bound = sorted(name for name, binding in ours.items() if bindings.inputs.get(name) is not binding)
        for name in self.bound:  # the bindings module's own: not ours to compute
            self.computed.pop(name, None)
            if self.followers.pop(name, None) is not None and name not in WORLD_INPUTS:
                self.followed.discard(name)
        for name in self.bound:  # record the calls of the user's functions too
            binding = bindings.inputs[name]
            if binding.params:
                bindings.input(
                    name, binding.kind, _recorded(agent, name, binding.read), params=binding.params, enum=binding.enum
                )
        try:  # the bench file's [pose] against this program
            #: the bench file's [pose], compiled against the program at the start
            self.pose: dict[str, Getter] = self._pose(program)
        except BenchFileError as error:  # the robot stands; the banner says why
            raise BenchInputError(str(error)) from None
        self.adopt(program)
        self.trace = trace
        self.trace_position = 0
        self.engine = _BenchEngine(self, bindings, program, agent_name=agent.name)
        if trace is not None:
            self.trace_lines = [self._checked(line) for line in trace.lines]

    def _bind_missing(self, program: Program) -> dict[str, object]:
        """Bind what ``program`` names and nobody bound yet (at start, and before a hot reload).

        Returns:
            the input bindings made, by name.
        """
        bindings = self.bindings
        for enum in program.enums.values():
            if not enum.internal and enum.name not in bindings.enums:
                bindings.enum(enum.name, list(enum.elements))
        ours: dict[str, object] = {}
        try:
            own = self._bench_entries(program)
            return self._bind_inputs(program, own, ours)
        except BenchFileError as error:  # the robot stands (or keeps its version); the banner says why
            raise BenchInputError(str(error)) from None

    def _bind_inputs(self, program: Program, own: dict[str, Entry], ours: dict[str, object]) -> dict[str, object]:
        """Bind ``program``'s input symbols nobody bound yet (bench file, computed, by hand)."""
        agent, bindings, values = self.agent, self.bindings, self.agent.values
        for symbol in program.inputs.values():
            if symbol.name in bindings.inputs:
                continue
            entry = own.get(symbol.name)
            if symbol.params:
                read: Callable[..., Value]
                computed = benchmath.match(symbol) if entry is None else None
                if entry is not None:
                    assert self.bench_file is not None
                    function = self._function(symbol, self.bench_file.compiled(entry, self._resolver(program, symbol)))
                    read = _computed_function(agent, symbol.name, function)
                    self.computed[symbol.name] = f"{self.bench_file.path.name}: {entry.text.strip()}"
                elif computed is not None:
                    read = _computed_function(agent, symbol.name, computed.function)
                    self.computed[symbol.name] = computed.description
                else:
                    read = _hand_function(agent, symbol.name, _initial(symbol.kind))
                bindings.input(symbol.name, symbol.kind, read, params=symbol.params, enum=symbol.enum)
            else:
                values[symbol.name] = _initial(symbol.kind)
                if entry is not None:
                    assert self.bench_file is not None
                    self.followers[symbol.name] = self.bench_file.compiled(entry, self._resolver(program, None))
                    self.followed.add(symbol.name)
                # Subscripted by the generated code and read in C by samplers (a getter per input and
                # tick showed in team-sized sets: hundreds of inputs per robot).
                bindings.input_item(symbol.name, symbol.kind, values, symbol.name, enum=symbol.enum)
            ours[symbol.name] = bindings.inputs[symbol.name]
        for out in program.outputs.values():
            if not out.internal and out.name not in bindings.outputs:
                bindings.output(out.name, out.kind, enum=out.enum)
        for behavior in program.behaviors.values():
            if behavior.name in bindings.behaviors:
                continue
            cls: Any = type(
                f"Bench_{behavior.name}",
                (_Skill,),
                {
                    "name": behavior.name,
                    "parameters": behavior.params,
                    "run": staticmethod(_SKILLS.get(behavior.name, _nothing)),
                },
            )
            bindings.behavior(cls(agent))
        return ours

    def _bench_entries(self, program: Program) -> dict[str, Entry]:
        """The bench file's ``[functions]`` and ``[inputs]`` by symbol, checked against ``program``.

        Raises:
            BenchFileError: an entry for a symbol the program does not declare, or of the other sort.
        """
        found: dict[str, Entry] = {}
        bench = self.bench_file
        if bench is None:
            return found
        for entry in bench.functions:
            symbol = program.inputs.get(entry.key)
            if symbol is None or not symbol.params:
                what = "declares no input symbol" if symbol is None else "declares it without parameters (see [inputs])"
                raise bench.error(entry, f"the behavior {what}")
            found[entry.key] = entry
        for entry in bench.inputs:
            symbol = program.inputs.get(entry.key)
            if symbol is None or symbol.params:
                what = "declares no input symbol" if symbol is None else "declares it with parameters (see [functions])"
                raise bench.error(entry, f"the behavior {what}")
            found[entry.key] = entry
        return found

    def _resolver(self, program: Program, function: InputSymbol | None) -> Resolver:
        """The names of a bench-file expression.

        A function's parameters (by declared name), the robot, the ball, ``now`` (ms), plain
        inputs; in ``[pose]`` also outputs and enum elements (:meth:`_pose_resolver`).
        """
        params = {p.short_name: i for i, p in enumerate(function.params)} if function is not None else {}
        agent = self.agent

        def resolve(name: str) -> Getter | None:
            if name in params:
                index = params[name]
                return lambda c: c[index]
            robot = _ROBOT_NAMES.get(name)
            if robot is not None:
                return lambda c: robot(agent)
            symbol = program.inputs.get(name)
            if symbol is not None and not symbol.params:
                values = agent.values
                return lambda c: values.get(name, 0.0)
            return None

        return resolve

    def _pose_resolver(self, program: Program) -> Resolver:
        inner = self._resolver(program, None)
        # external enumerations: element i is host value i unless the bindings module says otherwise
        element_values = {
            e: self.bindings.enums.get(enum.name, {}).get(e, i)
            for enum in program.enums.values()
            if not enum.internal
            for i, e in enumerate(enum.elements)
        }

        def resolve(name: str) -> Getter | None:
            out = program.outputs.get(name)
            if out is not None:
                return lambda engine: _output(engine, name)
            if name in element_values:
                value = element_values[name]
                return lambda c: value
            return inner(name)

        return resolve

    def _pose(self, program: Program) -> dict[str, Getter]:
        """The bench file's ``[pose]`` compiled against ``program`` (evaluated with the engine)."""
        if self.bench_file is None:
            return {}
        resolve = self._pose_resolver(program)
        return {entry.key: self.bench_file.compiled(entry, resolve) for entry in self.bench_file.pose}

    def _function(self, symbol: InputSymbol, getter: Getter) -> Callable[..., Value]:
        """A bench-file expression as the host function of ``symbol`` (its result as the symbol's kind)."""
        kind = symbol.kind

        def function(*args: Value) -> Value:
            return _scalar(getter(args), kind)

        return function

    def adopt(self, program: Program) -> None:
        """``program`` is the one running: its enumerations' host values, the world's game states."""
        self.program = program
        bindings = self.bindings
        #: per external enumeration: its host values in declaration order (for the scene and commands)
        self.enums = {
            name: EnumValues(name, {e: bindings.enums.get(name, {}).get(e, i) for i, e in enumerate(enum.elements)})
            for name, enum in program.enums.items()
            if not enum.internal
        }
        game = self.enums.get("game.state")
        if game is not None:
            world = self.agent.world
            world.ready_value = game.elements.get("game.state.ready", 0)
            world.playing_value = game.elements.get("game.state.playing", 0)

    def before_reload(self, program: Program) -> None:
        """A hot reload is coming: bind the names the new version adds (the bench binds any)."""
        self._bind_missing(program)

    def _checked(self, line: TraceLine) -> tuple[int, str | None, dict[str, Value]]:
        """A trace line with its values converted for this program (raises EngineError naming the line)."""
        where = f"{self.trace.path if self.trace else '?'}:{line.number}"
        if line.agent is not None and line.agent not in {a.name for a in self.program.agents}:
            raise BenchInputError(f"{where}: unknown agent {line.agent!r}")
        settings: dict[str, Value] = {}
        for name, raw in line.settings.items():
            try:
                settings[name] = self.convert(name, raw, plain=True)
            except BenchInputError as error:
                raise BenchInputError(f"{where}: {error}") from None
        return line.t, line.agent, settings

    def convert(self, name: str, raw: object, *, plain: bool, by_index: bool = False) -> Value:
        """``raw`` as the host value of input symbol ``name`` (plain, or an input function).

        Raises:
            BenchInputError: no such symbol, one of the other sort, one the bindings module
                supplies, or a value that does not fit.
        """
        symbol = self.program.inputs.get(name)
        if symbol is None:
            raise BenchInputError(f"unknown input symbol {name!r}")
        if plain and symbol.params:
            raise BenchInputError(f"input symbol {name!r} has parameters: set its value with set_function")
        if not plain and not symbol.params:
            raise BenchInputError(f"input symbol {name!r} has no parameters: set it with set_input")
        if name in self.bound:
            raise BenchInputError(f"input symbol {name!r} comes from the bindings module; override it instead")
        enum = self.enums.get(symbol.enum) if symbol.enum else None
        try:
            return coerce(symbol.kind, enum, raw, name=f"input symbol {name!r}", by_index=by_index)
        except ValueConversionError as error:
            raise BenchInputError(str(error)) from None

    def execute(self, now_ms: int) -> None:
        """Apply the bench file's inputs and the input trace up to ``now_ms``, one engine tick, the pose."""
        agent = self.agent
        for name, follow in self.followers.items():
            if name not in agent.hand:
                agent.values[name] = _scalar(follow(()), self.program.inputs[name].kind)
        if self.trace is not None:
            lines, agent = self.trace_lines, self.agent
            while self.trace_position < len(lines) and lines[self.trace_position][0] <= now_ms:
                _, selected, settings = lines[self.trace_position]
                if selected is not None:
                    self.engine.root_actions.select_agent(selected)
                for name, value in settings.items():
                    agent.values[name] = value
                    agent.hand.add(name)
                self.trace_position += 1
        self.engine.execute(now_ms)
        if self.pose:
            self._drive()

    def _drive(self) -> None:
        """Move the robot by the bench file's ``[pose]`` (over what the basic behaviors commanded)."""
        pose, agent, engine = self.pose, self.agent, self.engine
        when = pose.get("when")
        if when is not None and not _finite_true(when(engine)):
            return
        for key, limit, attribute in _POSE_AXES:
            getter = pose.get(key)
            if getter is None:
                continue
            value = float(getter(engine))
            setattr(agent, attribute, max(-limit, min(limit, value)) if math.isfinite(value) else 0.0)

    def index_of(self, symbol: str, value: Value) -> Value:
        """A host value as the studio shows it: enum values as element indexes (-1: no element)."""
        enum_name = self.program.inputs[symbol].enum
        if enum_name is None or enum_name not in self.enums:
            return value
        for i, host in enumerate(self.enums[enum_name].elements.values()):
            if host == value:
                return i
        return -1


class _BenchEngine(Engine):
    """The engine of a bench robot: on a hot reload the bench first binds what the new version adds."""

    def __init__(self, controller: BenchController, bindings: Bindings, program: Program, agent_name: str) -> None:
        self.controller = controller
        super().__init__(bindings, program, agent_name=agent_name)

    def reload(self, program: Program) -> None:
        """Bind the new names, then reload (``Engine.reload``)."""
        self.controller.before_reload(program)
        super().reload(program)
        self.controller.adopt(program)


#: The fastest a bench file's pose moves a robot: mm/s along either axis, deg/s turning.
MAX_SPEED, MAX_RATE = 1000.0, 360.0

#: ``[pose]`` keys: their limit and the robot's command they set.
_POSE_AXES = (("forward", MAX_SPEED, "speed"), ("sideways", MAX_SPEED, "side"), ("turn", MAX_RATE, "rate"))

#: Names of the bench robot and the ball in a bench-file expression.
_ROBOT_NAMES: dict[str, Callable[[BenchAgent], float]] = {
    "robot.x": lambda a: a.x,
    "robot.y": lambda a: a.y,
    "robot.heading": lambda a: a.heading,
    "robot.number": lambda a: float(a.number),
    "ball.x": lambda a: a.world.ball[0],
    "ball.y": lambda a: a.world.ball[1],
    "now": lambda a: float(a.now_ms),
}


def _output(engine: Engine, name: str) -> Value:
    try:
        return engine.output(name)
    except EngineError:  # gone after a hot reload: no motion from it
        return math.nan


def _finite_true(value: object) -> bool:
    return bool(value) and not (isinstance(value, float) and math.isnan(value))


def _scalar(value: float | bool | int, kind: Kind) -> Value:
    if kind is Kind.BOOLEAN:
        return bool(value)
    if kind is Kind.ENUM:
        return int(value)
    return float(value)


def _computed_function(agent: BenchAgent, name: str, function: Callable[..., Value]) -> Callable[..., Value]:
    """An input function the bench computes: the value set by hand while there is one, else computed."""
    functions = agent.functions

    def read(*args: Value) -> Value:
        value = functions[name] if name in functions else function(*args)
        _note(agent, name, args, value)
        return value

    return read


def _note(agent: BenchAgent, name: str, args: tuple[Value, ...], value: Value) -> None:
    calls = agent.calls.setdefault(name, [])
    if len(calls) < MAX_CALLS and all(c[0] != args for c in calls):
        calls.append((args, value))


def _hand_function(agent: BenchAgent, name: str, initial: Value) -> Callable[..., Value]:
    """An input function without a binding: the value set by hand, whatever the arguments."""

    def read(*args: Value) -> Value:
        value = agent.functions.get(name, initial)
        _note(agent, name, args, value)
        return value

    return read


def _recorded(agent: BenchAgent, name: str, function: Callable[..., Value]) -> Callable[..., Value]:
    """A function of the bindings module whose calls are recorded for the studio."""

    def read(*args: Value) -> Value:
        value = function(*args)
        _note(agent, name, args, value)
        return value

    return read


def _normalize(angle: float) -> float:
    return (angle + 180.0) % 360.0 - 180.0


class BenchInputError(EngineError, ValueError):
    """An input trace line or a hand-set value that does not fit the program (names file:line)."""


@dataclass(frozen=True, slots=True)
class TraceLine:
    """One line of an input trace (the ``xabsl trace`` format, engine/trace/conformance.py)."""

    number: int
    t: int
    agent: str | None
    settings: dict[str, object]


@dataclass(frozen=True, slots=True)
class InputTrace:
    """An input trace file (``--inputs FILE.jsonl``): lines in time order."""

    path: Path
    lines: tuple[TraceLine, ...]

    @classmethod
    def read(cls, path: Path) -> InputTrace:
        """Read and check the form of every line (names and values are checked against the program later).

        Raises:
            ExampleError: no such file, a line that is not JSON or not a trace line, times going back.
        """
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as error:
            raise ExampleError(f"--inputs {path}: {error}") from None
        lines: list[TraceLine] = []
        last = -1
        for number, raw in enumerate(text.splitlines(), start=1):
            if not raw.strip():
                continue
            where = f"{path}:{number}"
            try:
                record = json.loads(raw)
            except json.JSONDecodeError as error:
                raise ExampleError(f"{where}: not JSON ({error.msg})") from None
            if not isinstance(record, dict):
                raise ExampleError(f"{where}: a trace line is a JSON object")
            unknown = set(record) - {"t", "set", "agent"}
            if unknown:
                raise ExampleError(f"{where}: unknown key {sorted(unknown)[0]!r} (a line has t, set, agent)")
            t = record.get("t")
            if isinstance(t, bool) or not isinstance(t, int) or t < 0:
                raise ExampleError(f"{where}: t must be a non-negative integer (ms), got {t!r}")
            if t < last:
                raise ExampleError(f"{where}: t {t} is before the previous line's {last}")
            last = t
            settings = record.get("set", {})
            if not isinstance(settings, dict):
                raise ExampleError(f"{where}: set must be an object of input symbol values")
            agent = record.get("agent")
            if agent is not None and not isinstance(agent, str):
                raise ExampleError(f"{where}: agent must be an agent name")
            lines.append(TraceLine(number, t, agent, settings))
        return cls(path, tuple(lines))


class BindingsModule:
    """A user's bindings module (``--bindings FILE.py``): its ``bind(bindings, robot)`` function.

    ``bind`` gets the robot's :class:`xabsl_studio.engine.runtime.Bindings` with the bench's own bindings in
    it and the :class:`BenchAgent`; what it registers (``input``, ``input`` with ``params``,
    ``behavior``, ``enum``, ``output``) replaces the bench's binding of that name.
    """

    def __init__(self, path: Path) -> None:
        self.path = path
        self.function = _load_bind(path)

    def bind(self, bindings: Bindings, robot: BenchAgent) -> None:
        """Call the module's ``bind``; its exceptions name the module.

        Raises:
            EngineError: ``bind`` raised.
        """
        try:
            self.function(bindings, robot)
        except Exception as error:
            raise BenchInputError(f"{self.path}: bind() raised {type(error).__name__}: {error}") from error


def _load_bind(path: Path) -> Callable[[Bindings, BenchAgent], None]:
    if not path.is_file():
        raise ExampleError(f"--bindings {path}: no such file")
    digest = hashlib.sha256(str(path).encode()).hexdigest()[:10]
    name = f"_xabsl_bench_bindings_{digest}"
    module = sys.modules.get(name)
    if module is None:
        spec = importlib.util.spec_from_file_location(name, path)
        if spec is None or spec.loader is None:
            raise ExampleError(f"--bindings {path}: not a Python module")
        module = importlib.util.module_from_spec(spec)
        try:
            spec.loader.exec_module(module)
        except Exception as error:  # the user's module: say where and why
            raise ExampleError(f"--bindings {path}: {type(error).__name__}: {error}") from error
        sys.modules[name] = module
    bind = getattr(module, "bind", None)
    if not callable(bind):
        raise ExampleError(f"--bindings {path}: defines no function bind(bindings, robot)")
    result: Callable[[Bindings, BenchAgent], None] = bind
    return result


class BenchExample:
    """The bench world as a world plug-in: every robot runs the one behavior set of ``path``.

    Args:
        path: a behavior folder (see :func:`find_agents_file`) or an agents file anywhere on disk.
        robots: how many robots.
        bindings: a Python file whose ``bind(bindings, robot)`` supplies symbols and basic behaviors.
        inputs: an input trace (``xabsl trace`` format) that plays on every robot.
        bench: a bench file (default: ``bench.toml`` beside the agents file, if there is one).

    Raises:
        ExampleError: no agents file at ``path``, a number of robots out of 1..20, a bindings
            module that does not load, an input trace or a bench file that does not read.
    """

    preload: tuple[str, ...] = ("xabsl_studio.engine.worlds.bench",)
    behavior_hz = DEFAULT_BEHAVIOR_HZ
    physics_hz = DEFAULT_PHYSICS_HZ

    def __init__(
        self,
        path: Path,
        robots: int = 2,
        bindings: str | Path | None = None,
        inputs: str | Path | None = None,
        bench: str | Path | None = None,
    ) -> None:
        path = path.resolve()
        agents_file = find_agents_file(path) if path.is_dir() else path
        if isinstance(robots, bool) or not isinstance(robots, int) or not 1 <= robots <= 20:
            raise ExampleError(f"robots must be an integer in 1..20, got {robots!r}")
        self.n_agents = robots
        self.sources: tuple[BehaviorSource, ...] = (behavior_source(agents_file),)
        self.root = common_root(self.sources)
        self.name = self.sources[0].key
        self.bindings = BindingsModule(Path(bindings).expanduser().resolve()) if bindings is not None else None
        self.inputs = InputTrace.read(Path(inputs).expanduser().resolve()) if inputs is not None else None
        bench_path = Path(bench).expanduser().resolve() if bench is not None else find_bench_file(agents_file)
        self.bench_file = BenchFile.read(bench_path) if bench_path is not None else None

    def build_world(self, seed: int) -> World:
        """A bench world with ``robots`` robots."""
        world = BenchWorld(seed, self.n_agents)
        world.trace = self.inputs
        world.bindings_file = self.bindings.path if self.bindings is not None else None
        return world

    def program_key(self, agent: Agent) -> str | None:
        """Every robot runs the one behavior set."""
        return self.sources[0].key

    def make_controller(self, agent: Agent, program: Program) -> tuple[AgentController, Engine]:
        """A :class:`BenchController` for a bench robot."""
        if not isinstance(agent, BenchAgent):
            raise TypeError("the bench world runs BenchWorld robots")
        controller = BenchController(agent, program, self.bindings, self.inputs, self.bench_file)
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


def example(
    path: Path, robots: int = 2, bindings: str | None = None, inputs: str | None = None, bench: str | None = None
) -> BenchExample:
    """The world plug-in factory of the bench world (``xabsl serve PATH --world bench``)."""
    return BenchExample(path, robots, bindings, inputs, bench)
