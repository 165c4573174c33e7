"""The live session: one world stepped by its own thread at real time x speed, steered between ticks.

The simulation thread is the only one that touches the world and the engines. Everything else
(websocket commands, REST writes, hot reloads) hands it a function through a queue and waits on
a ``concurrent.futures.Future``; the thread runs queued functions between two ticks, so a command
never sees half a tick. The thread never waits for a client: after each tick it records a frame
(``frames.FrameRecorder``) and calls ``notify`` (set by the app), which only schedules work on the
asyncio loop.

Timing: ticks are due every ``1 / (behavior_hz x speed)`` wall seconds. A thread that falls more
than a quarter of a second behind (a slow machine at 20x) drops the backlog instead of bursting,
so the real-time factor then simply tops out.

Compiling is not the thread's business: :meth:`Session.compile` runs anywhere (the app uses a
worker thread) and :meth:`Session.apply` hot-swaps a clean program into the engines between
ticks. Forces and input overrides remember which client made them (``owner``) so they can be
released when that client disconnects.
"""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable, Mapping
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Any, TypeVar

import orjson

from engine.emit.json import program_to_json
from engine.host import DEFAULT_BEHAVIOR_HZ, DEFAULT_PHYSICS_HZ, BehaviorLoop, World
from engine.ir.model import Program, leaf_path
from engine.lang import Compilation, compile_file
from engine.runtime import DebugError, Engine, EngineError
from engine.types import Kind, Value
from server.examples import BehaviorSource, Example
from server.frames import AgentSampler, Entry, FrameRecorder, Generation, ProgramCodec, Ring
from server.protocol import MAX_SPEED, MAX_STEP_TICKS, MIN_SPEED, HelloReason

T = TypeVar("T")

#: Seconds of ticks the ring buffer keeps.
RING_SECONDS = 120.0


class CommandError(ValueError):
    """A command that cannot be carried out (bad agent, unknown option, wrong value...)."""


@dataclass(slots=True)
class ProgramState:
    """The last compile of one behavior source, and the program running (last clean compile)."""

    source: BehaviorSource
    compilation: Compilation | None = None
    running: Program | None = None
    running_json: dict[str, Any] | None = None
    error: str | None = None

    def as_dict(self) -> dict[str, Any]:
        comp = self.compilation
        return {
            "folder": self.source.folder.name,
            "agents_file": self.source.agents_file.name,
            "ok": comp is not None and comp.ok and self.error is None,
            "running": self.running is not None,
            "error": self.error,
            "diagnostics": [d.as_dict() for d in comp.diagnostics] if comp is not None else [],
            "files": list(comp.files) if comp is not None else [],
        }


@dataclass(slots=True)
class _Timing:
    """Wall and simulated time of the recent ticks, for the real-time factor and tick cost."""

    window: list[tuple[float, float]] = field(default_factory=list)
    busy: float = 0.0
    ticks: int = 0

    def add(self, wall: float, sim: float) -> None:
        self.window.append((wall, sim))
        if len(self.window) > 400:
            del self.window[:200]

    def real_time_factor(self) -> float:
        if len(self.window) < 2:
            return 0.0
        (w0, s0), (w1, s1) = self.window[0], self.window[-1]
        return (s1 - s0) / (w1 - w0) if w1 > w0 else 0.0


class Session:
    """A running example: world, engines, ring buffer, simulation thread (see the module docstring).

    Args:
        example: the adapter of the example folder.
        seed: the world's seed.
        speed: real time x speed (0.1..20).
        behavior_hz, physics_hz: the loop's rates (``engine.host``).
        ring_seconds: how much history the ring buffer keeps.
    """

    def __init__(
        self,
        example: Example,
        seed: int = 1,
        speed: float = 1.0,
        behavior_hz: int = DEFAULT_BEHAVIOR_HZ,
        physics_hz: int = DEFAULT_PHYSICS_HZ,
        ring_seconds: float = RING_SECONDS,
    ) -> None:
        self.example = example
        self.seed = seed
        self.speed = _check_speed(speed)
        self.behavior_hz = behavior_hz
        self.physics_hz = physics_hz
        self.paused = False
        self.programs: dict[str, ProgramState] = {s.key: ProgramState(s) for s in example.sources}
        self.ring = Ring(ring_seconds, behavior_hz)
        self.recorder = FrameRecorder(self.ring)
        #: called from the simulation thread after every recorded frame (the app schedules work)
        self.notify: Callable[[Entry], None] = lambda entry: None
        self.timing = _Timing()
        self._commands: queue.SimpleQueue[tuple[Callable[[], Any], Future[Any]]] = queue.SimpleQueue()
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._generation_number = 0
        self._owners: dict[tuple[int, str], str] = {}  # (agent, "root" | input name) -> client
        self.world: World
        self.loop: BehaviorLoop
        self.engines: list[Engine | None] = []
        self.keys: list[str | None] = []
        self.generation: Generation
        for key in self.programs:
            self._store_compilation(key, self.compile(key))
        self._build_world(seed)
        self._new_generation(HelloReason.CONNECT)

    # -- compiling -------------------------------------------------------------------------------

    def compile(self, key: str, overrides: Mapping[str, str] | None = None) -> Compilation:
        """Compile behavior ``key`` from disk (``overrides``: unsaved texts by absolute path)."""
        source = self.programs[key].source
        return compile_file(str(source.agents_file), base=str(self.example.root), overrides=overrides)

    def _store_compilation(self, key: str, compilation: Compilation) -> None:
        state = self.programs[key]
        state.compilation = compilation
        state.error = None
        if compilation.program is not None:
            state.running = compilation.program
            state.running_json = program_to_json(compilation.program, compilation.source_text)

    # -- world and generations (simulation thread, or before it starts) ---------------------------

    def _build_world(self, seed: int) -> None:
        world = self.example.build_world(seed)
        engines: list[Engine | None] = []
        keys: list[str | None] = []
        for agent in world.agents:
            key = self.example.program_key(agent)
            engine = None
            if key is not None and key in self.programs:
                state = self.programs[key]
                if state.running is not None:
                    try:
                        controller, engine = self.example.make_controller(agent, state.running)
                        agent.controller = controller
                    except EngineError as error:  # the program does not link with this host
                        state.error = str(error)
                        engine = None
            engines.append(engine)
            keys.append(key)
        self.world = world
        self.engines = engines
        self.keys = keys
        self.seed = seed
        self.loop = BehaviorLoop(world, self.physics_hz, self.behavior_hz)
        self._owners.clear()

    def _new_generation(self, reason: str) -> Generation:
        self._generation_number += 1
        codecs: dict[str, ProgramCodec] = {}
        samplers: list[AgentSampler | None] = []
        input_ids: list[tuple[int, ...]] = []
        output_ids: list[tuple[int, ...]] = []
        agents = []
        for index, (agent, engine, key) in enumerate(zip(self.world.agents, self.engines, self.keys, strict=True)):
            program_key = key if engine is not None else None
            agents.append({"id": index, "name": agent.name, "team": agent.team, "number": agent.number,
                           "program": program_key})
            if engine is None or key is None:
                samplers.append(None)
                input_ids.append(())
                output_ids.append(())
                continue
            codec = codecs.get(key)
            if codec is None or codec.program is not engine.program:
                codec = codecs[key] = ProgramCodec.build(key, engine.program, engine)
            samplers.append(AgentSampler(index, engine, codec))
            input_ids.append(tuple(i for i, *_ in codec.inputs))
            output_ids.append(tuple(i for i, *_ in codec.outputs))
        programs = {key: state.running_json for key, state in self.programs.items() if state.running_json is not None}
        structure = {"programs": programs, "agents": agents}
        self.generation = Generation(
            number=self._generation_number,
            reason=str(reason),
            structure=structure,
            structure_bytes=orjson.dumps(structure),
            scene_bytes=orjson.dumps(self.world.static_scene()),
            codecs=codecs,
            samplers=samplers,
            input_ids=input_ids,
            output_ids=output_ids,
        )
        return self.generation

    def _record(self) -> Entry:
        world = self.world
        entry = self.recorder.record(self.generation, self._tick_time(), world.dynamic_scene(), world.status())
        self.notify(entry)
        return entry

    def _tick_time(self) -> int:
        # The clock of the tick just run (the loop's now_ms is already the next tick's).
        loop = self.loop
        return loop.start_ms + round(max(loop.ticks - 1, 0) * 1000 / self.behavior_hz)

    def _tick(self) -> Entry:
        started = time.perf_counter()
        self.loop.tick()
        entry = self._record()
        done = time.perf_counter()
        self.timing.busy += done - started
        self.timing.ticks += 1
        self.timing.add(done, self.loop.sim_seconds)
        return entry

    # -- the thread --------------------------------------------------------------------------------

    def start(self) -> None:
        """Record the first frame and start the simulation thread."""
        assert self._thread is None, "the session runs already"
        self._record()
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name="xabsl-simulation", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop the simulation thread (waits for the tick in progress)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def _run(self) -> None:
        next_due = time.perf_counter()
        while not self._stop.is_set():
            if self.paused or self.world.finished:
                self._drain(0.05)
                next_due = time.perf_counter()
                continue
            now = time.perf_counter()
            if now < next_due:
                self._drain(next_due - now)
                continue
            self._tick()
            next_due += 1.0 / (self.behavior_hz * self.speed)
            if time.perf_counter() - next_due > 0.25:
                next_due = time.perf_counter()
            self._drain(0.0)

    def _drain(self, timeout: float) -> None:
        try:
            item = self._commands.get(timeout=timeout) if timeout > 0 else self._commands.get_nowait()
        except queue.Empty:
            return
        while True:
            fn, future = item
            if future.set_running_or_notify_cancel():
                try:
                    future.set_result(fn())
                except BaseException as error:  # handed to the waiting caller, never kills the thread
                    future.set_exception(error)
            try:
                item = self._commands.get_nowait()
            except queue.Empty:
                return

    def submit(self, fn: Callable[[], T]) -> Future[T]:
        """Run ``fn`` in the simulation thread between two ticks; its result or error in the future.

        Before :meth:`start` (and after :meth:`stop`) ``fn`` runs at once in the caller's thread.
        """
        future: Future[T] = Future()
        if not self.running:
            future.set_running_or_notify_cancel()
            try:
                future.set_result(fn())
            except BaseException as error:
                future.set_exception(error)
            return future
        self._commands.put((fn, future))
        return future

    # -- commands (run by the simulation thread through submit) ---------------------------------------

    def execute(self, op: str, args: Mapping[str, Any], owner: str | None = None) -> Any:
        """Carry out one command (docs/protocol.md); must run in the simulation thread.

        Raises:
            CommandError: bad arguments; the session is unchanged.
        """
        handler = getattr(self, f"_op_{op}", None)
        if handler is None:
            raise CommandError(f"unknown op {op!r}")
        try:
            return handler(args, owner)
        except (DebugError, EngineError) as error:
            raise CommandError(str(error)) from None

    def _op_pause(self, args: Mapping[str, Any], owner: str | None) -> Any:
        self.paused = True
        return {"paused": True}

    def _op_resume(self, args: Mapping[str, Any], owner: str | None) -> Any:
        self.paused = False
        return {"paused": False}

    def _op_step(self, args: Mapping[str, Any], owner: str | None) -> Any:
        ticks = args.get("ticks", 1)
        if isinstance(ticks, bool) or not isinstance(ticks, int) or not 1 <= ticks <= MAX_STEP_TICKS:
            raise CommandError(f"ticks must be an integer in 1..{MAX_STEP_TICKS}")
        if not self.paused:
            raise CommandError("step works while the session is paused")
        entry = None
        for _ in range(ticks):
            if self.world.finished:
                break
            entry = self._tick()
        latest = entry or self.ring.latest
        return {"seq": latest.seq if latest else 0, "t": latest.t if latest else 0}

    def _op_speed(self, args: Mapping[str, Any], owner: str | None) -> Any:
        try:
            self.speed = _check_speed(args.get("speed"))
        except ValueError as error:
            raise CommandError(str(error)) from None
        return {"speed": self.speed}

    def _op_reset(self, args: Mapping[str, Any], owner: str | None) -> Any:
        seed = args.get("seed", self.seed)
        if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 2**32:
            raise CommandError("seed must be an integer in 0..2**32-1")
        self._build_world(seed)
        self._new_generation(HelloReason.RESET)
        self._record()
        return {"seed": seed}

    def _op_select_agent(self, args: Mapping[str, Any], owner: str | None) -> Any:
        _, engine, _ = self._agent(args)
        name = args.get("name")
        if not isinstance(name, str):
            raise CommandError("name (an XABSL agent of the program) is required")
        engine.select_agent(name)
        return None

    def _op_force_option(self, args: Mapping[str, Any], owner: str | None) -> Any:
        index, engine, codec = self._agent(args)
        option = self._named(args.get("option"), codec.option_ids, "option")
        params = self._params(args.get("params"), codec.program.options[option].params, codec)
        engine.debug.force_option(option, params)
        self._own(index, "root", owner)
        return None

    def _op_force_behavior(self, args: Mapping[str, Any], owner: str | None) -> Any:
        index, engine, codec = self._agent(args)
        behavior = self._named(args.get("behavior"), codec.behavior_ids, "basic behavior")
        params = self._params(args.get("params"), codec.program.behaviors[behavior].params, codec)
        engine.debug.force_behavior(behavior, params)
        self._own(index, "root", owner)
        return None

    def _op_release(self, args: Mapping[str, Any], owner: str | None) -> Any:
        index, engine, _ = self._agent(args)
        engine.debug.release()
        self._owners.pop((index, "root"), None)
        return None

    def _op_override_input(self, args: Mapping[str, Any], owner: str | None) -> Any:
        index, engine, codec = self._agent(args)
        ids = {s.name: s.index for s in codec.program.inputs.values()}
        name = self._named(args.get("symbol"), ids, "input symbol")
        symbol = codec.program.inputs[name]
        if "value" not in args:
            raise CommandError("value is required")
        engine.debug.override_input(name, self._value(args["value"], symbol.kind, symbol.enum, codec, name))
        self._own(index, "input:" + name, owner)
        return None

    def _op_release_input(self, args: Mapping[str, Any], owner: str | None) -> Any:
        index, engine, codec = self._agent(args)
        if args.get("symbol") is None:
            engine.debug.release_inputs()
            for key in [k for k in self._owners if k[0] == index and k[1].startswith("input:")]:
                del self._owners[key]
            return None
        ids = {s.name: s.index for s in codec.program.inputs.values()}
        name = self._named(args.get("symbol"), ids, "input symbol")
        engine.debug.release_input(name)
        self._owners.pop((index, "input:" + name), None)
        return None

    def _op_reset_agent(self, args: Mapping[str, Any], owner: str | None) -> Any:
        _, engine, _ = self._agent(args)
        engine.debug.reset()
        return None

    def _op_explain(self, args: Mapping[str, Any], owner: str | None) -> Any:
        _, engine, codec = self._agent(args)
        option = self._named(args.get("option"), codec.option_ids, "option")
        explanation = engine.debug.explain(option)
        states = codec.state_ids[option]
        ir_option = codec.program.options[option]
        decided = ir_option.state(explanation.decided_in)
        # The leaf's own span, so the editor can point at the transition that fired.
        leaf_span = None
        try:
            path = leaf_path(decided.decision, explanation.leaf)
            node: Any = decided.decision
            for _, branch in path:
                node = node.then if branch else node.otherwise
            leaf_span = node.span.as_dict() if node.span else None
        except KeyError:
            pass
        return {
            "option": codec.option_ids[option],
            "option_name": option,
            "decided_in": states[explanation.decided_in],
            "decided_in_name": explanation.decided_in,
            "leaf": explanation.leaf,
            "target": states.get(explanation.target, -1),
            "target_name": explanation.target,
            "stay": explanation.stay,
            "leaf_span": leaf_span,
            "conditions": [
                {"text": c.text, "source": c.source, "value": _plain(c.value), "branch": c.branch,
                 "span": c.span.as_dict() if c.span else None}
                for c in explanation.conditions
            ],
        }

    def _op_status(self, args: Mapping[str, Any], owner: str | None) -> Any:
        return self.status()

    # -- helpers for commands -----------------------------------------------------------------------

    def _agent(self, args: Mapping[str, Any]) -> tuple[int, Engine, ProgramCodec]:
        index = args.get("agent")
        if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < len(self.engines):
            raise CommandError(f"agent must be an agent id in 0..{len(self.engines) - 1}")
        engine = self.engines[index]
        sampler = self.generation.samplers[index]
        if engine is None or sampler is None:
            raise CommandError(f"agent {index} runs no XABSL engine")
        return index, engine, sampler.codec

    @staticmethod
    def _named(value: Any, ids: Mapping[str, int], what: str) -> str:
        if isinstance(value, str):
            if value not in ids:
                raise CommandError(f"unknown {what} {value!r}")
            return value
        if isinstance(value, int) and not isinstance(value, bool):
            for name, i in ids.items():
                if i == value:
                    return name
            raise CommandError(f"unknown {what} id {value}")
        raise CommandError(f"{what} must be a name or an id")

    def _params(self, given: Any, declared: Any, codec: ProgramCodec) -> dict[str, Value | str]:
        if given is None:
            return {}
        if not isinstance(given, dict):
            raise CommandError("params must be an object of parameter values")
        by_name = {p.name: p for p in declared}
        by_short = {p.name.rsplit(".", 1)[-1]: p for p in declared}
        result: dict[str, Value | str] = {}
        for key, value in given.items():
            param = by_name.get(key) or by_short.get(key)
            if param is None:
                raise CommandError(f"no parameter {key!r}")
            result[param.name] = self._value(value, param.kind, param.enum, codec, param.name)
        return result

    @staticmethod
    def _value(value: Any, kind: Kind, enum: str | None, codec: ProgramCodec, name: str) -> Value | str:
        if kind is Kind.ENUM and isinstance(value, int) and not isinstance(value, bool):
            element = codec.element(enum, value)
            if element is None:
                raise CommandError(f"{name}: no element {value} in enum {enum}")
            return element
        if kind is Kind.DECIMAL and isinstance(value, int | float) and not isinstance(value, bool):
            return float(value)
        return value

    def _own(self, agent: int, what: str, owner: str | None) -> None:
        if owner is None:
            self._owners.pop((agent, what), None)
        else:
            self._owners[(agent, what)] = owner

    def release_owner(self, owner: str) -> int:
        """Release every force and override ``owner`` made and nobody changed since (sim thread)."""
        released = 0
        for (agent, what), who in list(self._owners.items()):
            if who != owner:
                continue
            del self._owners[(agent, what)]
            engine = self.engines[agent]
            if engine is None:
                continue
            try:
                if what == "root":
                    engine.debug.release()
                else:
                    engine.debug.release_input(what.removeprefix("input:"))
                released += 1
            except (DebugError, EngineError):
                continue
        return released

    # -- hot reload ----------------------------------------------------------------------------------

    def apply(self, key: str, compilation: Compilation) -> str | None:
        """Store a compile of ``key``; when clean, hot-swap it into the engines (simulation thread).

        Returns:
            None when swapped (or nothing to swap), else why the running behavior was kept.
        """
        program = compilation.program
        state = self.programs[key]
        state.compilation = compilation
        if program is None:
            return "the behavior has errors; the running version is kept"
        reloaded: list[Engine] = []
        try:
            for index, engine in enumerate(self.engines):
                if self.keys[index] != key:
                    continue
                if engine is None:
                    agent = self.world.agents[index]
                    controller, engine = self.example.make_controller(agent, program)
                    agent.controller = controller
                    self.engines[index] = engine
                else:
                    engine.reload(program)
                reloaded.append(engine)
        except EngineError as error:
            # Engines are reloaded one by one; with one host they fail alike, so the first fails.
            state.error = str(error)
            return f"the behavior does not run on this host: {error}"
        state.error = None
        state.running = program
        state.running_json = program_to_json(program, compilation.source_text)
        self._new_generation(HelloReason.RELOAD)
        self._record()
        return None

    # -- status ----------------------------------------------------------------------------------------

    def status(self) -> dict[str, Any]:
        latest = self.ring.latest
        ring_entries = len(self.ring)
        return {
            "example": self.example.name,
            "paused": self.paused,
            "finished": self.world.finished,
            "speed": self.speed,
            "seed": self.seed,
            "behavior_hz": self.behavior_hz,
            "seq": latest.seq if latest else 0,
            "t": latest.t if latest else 0,
            "generation": self.generation.number,
            "real_time_factor": round(self.timing.real_time_factor(), 3),
            "tick_ms": round(1000 * self.timing.busy / self.timing.ticks, 3) if self.timing.ticks else 0.0,
            # raw counters, for windowed measurements (benchmarks/stream_load.py)
            "timing": {"ticks": self.timing.ticks, "busy_seconds": self.timing.busy,
                       "sim_seconds": self.loop.sim_seconds, "frame_seconds": self.recorder.sample_seconds},
            "ring": {"frames": ring_entries, "capacity": self.ring.capacity,
                     "seconds": round(ring_entries / self.behavior_hz, 1), "bytes": self.ring.nbytes()},
            "programs": {key: state.as_dict() for key, state in self.programs.items()},
            "world": self.world.status(),
        }


def _check_speed(speed: Any) -> float:
    if isinstance(speed, bool) or not isinstance(speed, int | float) or not MIN_SPEED <= speed <= MAX_SPEED:
        raise ValueError(f"speed must be a number in {MIN_SPEED:g}..{MAX_SPEED:g}")
    return float(speed)


def _plain(value: Any) -> Any:
    return value if isinstance(value, bool | int | float | str) or value is None else str(value)
