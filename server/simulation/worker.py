"""The simulation process: one world and its XABSL engines, stepped at real time x speed (§2.2 one tick).

The studio server (``xabsl_studio.server.session.live``) starts :func:`main` in a process of its own (forkserver or
spawn, never a fork of the server) so that websocket clients can never slow the simulation
through the GIL. This process owns everything that touches the world and the engines:

* :class:`Simulation`: the world, the :class:`~xabsl_studio.engine.host.BehaviorLoop`, the engines, the
  hot swap of programs compiled by the server, the commands (``_op_*``) and who forced what;
* per tick, one compact :class:`~xabsl_studio.server.protocol.host.Sample`: seq, generation, clocks, and per robot
  the activation path (JSON bytes), the extras (fault, force, overrides), the input and output
  values as tuples; the dynamic scene and the world status (JSON bytes). Everything per client
  (masks, deltas, full frames, the ring buffer, history) happens in the server process;
* a :class:`~xabsl_studio.server.protocol.host.NewGeneration` (:meth:`Simulation.generation`) whenever the ids
  change (start, reload, reset): structure bytes, static scene bytes, the symbol id tables, sent
  before its first sample.

The loop (:func:`run`) ticks when a tick is due and otherwise waits on the channel for
:class:`~xabsl_studio.server.protocol.host.WorkerRequest` messages: a command the server validated already (a
dataclass of ``xabsl_studio.server.protocol``), answered with a
:class:`~xabsl_studio.server.protocol.host.WorkerReply` after the samples the command produced. Samples
are droppable (``xabsl_studio.server.protocol.channel``): a server that falls behind never blocks a tick
(except a generation's first second: :meth:`Simulation.sample_droppable`). An
exception escaping the world ends the process after a :class:`~xabsl_studio.server.protocol.host.Crash`
message; the server reports it and starts a fresh process on ``reset``.

Timing: ticks are due every ``1 / (behavior_hz x speed)`` wall seconds; more than a quarter of a
second behind (a slow machine at 20x), the backlog is dropped instead of burst through.
"""

from __future__ import annotations

import os
import select
import signal
import socket
import sys
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import orjson

from xabsl_studio.engine.host import (
    DEFAULT_BEHAVIOR_HZ,
    DEFAULT_PHYSICS_HZ,
    BehaviorLoop,
    CommandableWorld,
    Example,
    World,
    WorldCommandError,
)
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.runtime import DebugError, Debugger, Engine, EngineError
from xabsl_studio.engine.runtime.breakpoints import Breakpoint
from xabsl_studio.engine.runtime.debug import ReadValues, decision_reads, explain_decision
from xabsl_studio.server.protocol.channel import Channel, ChannelClosed
from xabsl_studio.server.protocol.commands import (
    Explain,
    Pause,
    Reset,
    Resume,
    Seek,
    Speed,
    Status,
    Step,
    WorldCommand,
)
from xabsl_studio.server.protocol.display import display_path, program_display
from xabsl_studio.server.protocol.host import (
    Apply,
    Crash,
    ExplainRecorded,
    ForkAt,
    FromWorker,
    NewGeneration,
    Sample,
    ToWorker,
    WorkerCommand,
    WorkerReply,
    WorkerRequest,
)
from xabsl_studio.server.protocol.limits import MAX_SPEED, MIN_SPEED
from xabsl_studio.server.protocol.types import HelloReason
from xabsl_studio.server.simulation.engines import CommandError as CommandError
from xabsl_studio.server.simulation.engines import EngineSet
from xabsl_studio.server.simulation.explain import explanation_result, mark_values, tree_result, why_not_result
from xabsl_studio.server.simulation.forkstart import ForkStart
from xabsl_studio.server.simulation.runlog import LOGGED_OPS, Programs, RunLog, Switch

#: Simulated seconds a ``fork`` re-simulates at most (from the last reset: about 0.2 ms a tick for
#: 10 robots, so 30 minutes take some 15 s in which the simulation answers nothing).
FORK_MAX_SECONDS = 1800.0

#: The channel as the simulation process sees it.
WorkerChannel = Channel[FromWorker, ToWorker]


@dataclass(slots=True)
class WorkerConfig:
    """What a simulation process starts from (pickled to it)."""

    example: Example
    seed: int = 1
    speed: float = 1.0
    paused: bool = False
    behavior_hz: int = DEFAULT_BEHAVIOR_HZ
    physics_hz: int = DEFAULT_PHYSICS_HZ
    #: per behavior key: the running program and its program JSON (None: not compiled clean)
    programs: dict[str, tuple[Program, dict[str, Any]] | None] = field(default_factory=dict)
    #: per behavior key that did not compile clean: the program JSON of what parsed (shown, not run)
    descriptions: dict[str, dict[str, Any]] = field(default_factory=dict)
    #: the last seq and generation number sent (a restarted worker continues the numbering)
    seq: int = 0
    generation: int = 0
    #: the ``hello`` reason of the first generation (``reset`` when restarted after a crash)
    reason: HelloReason = "connect"
    #: per behavior key: its breakpoints (the server keeps and stores them)
    breakpoints: dict[str, tuple[Breakpoint, ...]] = field(default_factory=dict)
    #: samples the server's ring holds: run logs older than that are dropped (``fork``)
    history_ticks: int = 4800
    #: start at a tick of a recording instead of a fresh world ("run from here", ``simulation/forkstart.py``)
    fork: ForkStart | None = None


@dataclass(slots=True)
class _Timing:
    """Wall and simulated time of the recent ticks, for the real-time factor and tick cost."""

    window: list[tuple[float, float]] = field(default_factory=list)
    busy: float = 0.0
    cpu: float = 0.0
    sample: float = 0.0
    #: CPU seconds of this thread spent sampling the ticks (wall time also counts other processes)
    sample_cpu: float = 0.0
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


class Simulation(EngineSet):
    """A running example without any client: world, engines, samples, commands.

    Args:
        config: example, seed, speed, rates, the programs to run and where numbering continues.
    """

    def __init__(self, config: WorkerConfig) -> None:
        super().__init__()
        self.example = config.example
        self.seed = config.seed
        self.speed = config.speed
        self.paused = config.paused
        self.behavior_hz = config.behavior_hz
        self.physics_hz = config.physics_hz
        self.programs = dict(config.programs)
        self.descriptions = dict(config.descriptions)
        self.errors: dict[str, str | None] = dict.fromkeys(self.programs)
        self.seq = config.seq
        self.generation_number = config.generation
        self.timing = _Timing()
        self.world: World
        self.loop: BehaviorLoop
        self.reason: HelloReason = config.reason
        #: the channel to the server (its counters show in the status), None in tests
        self.channel: WorkerChannel | None = None
        #: where generation messages and samples produced by commands go: ``emit(message,
        #: droppable) -> sent``; the process loop sends them, tests may collect them
        self.emit: Callable[[FromWorker, bool], bool] = _collect
        for key, points in config.breakpoints.items():
            self.breakpoints.replace(key, points)
        #: the run logs whose samples the server's ring may still hold, oldest first (``fork``)
        self.logs: list[RunLog] = []
        self.history_ticks = config.history_ticks
        #: whether commands are logged (not while re-simulating a run for a fork)
        self.logging = True
        #: samples still sent behind a backlog instead of dropped (:meth:`sample_droppable`)
        self.kept_samples = 0
        if config.fork is not None:
            self._fork_world(config.fork)
        else:
            self._build_world(self.seed)

    # -- world and generations ---------------------------------------------------------------------

    def _build_world(self, seed: int) -> None:
        world = self.example.build_world(seed)
        engines: list[Engine | None] = []
        keys: list[str | None] = []
        for agent in world.agents:
            key = self.example.program_key(agent)
            engine = None
            running = self.programs.get(key) if key is not None else None
            if running is not None:
                try:
                    controller, engine = self.example.make_controller(agent, running[0])
                    agent.controller = controller
                except EngineError as error:  # the program does not link with this host
                    self.errors[key] = str(error)  # type: ignore[index]
                    engine = None
            engines.append(engine)
            keys.append(key)
        self.world = world
        self.engines = engines
        self.keys = keys
        self.seed = seed
        self.loop = BehaviorLoop(world, self.physics_hz, self.behavior_hz)
        self._owners.clear()
        # The next sample is the build's: a new run starts there.
        self._start_log(RunLog(seed, self.programs, self.seq + 1))

    def _start_log(self, log: RunLog) -> None:
        if self.logs:
            self.logs[-1].end = log.start
        self.logs.append(log)
        self._prune_logs()

    def _prune_logs(self) -> None:
        """Drop the logs of runs whose samples have all left the server's ring."""
        oldest = self.seq - self.history_ticks
        self.logs = [log for log in self.logs if log.end is None or log.end > oldest]

    def _fork_world(self, fork: ForkStart) -> None:
        """The recorded world at the fork tick, with the behaviors on disk (``simulation/forkstart.py``)."""
        from xabsl_studio.server.simulation.forkstart import resimulated

        start = resimulated(self.example, self.programs, fork, self.physics_hz, self.behavior_hz)
        self.world, self.loop, self.engines, self.keys = start.world, start.loop, start.engines, start.keys
        self._owners.clear()
        # The run log replays a run from its seed; this one started from a recording's tick.
        log = RunLog(self.seed, self.programs, self.seq + 1)
        log.problem = "this run started from a tick of a recording: fork the recording in its replay instead"
        self._start_log(log)

    def generation(self, reason: HelloReason, fork: tuple[int, int, int] | None = None) -> NewGeneration:
        """Start a new generation of ids; returns its message for the server (``fork``: its origin)."""
        self.generation_number += 1
        self.reason = reason
        self.kept_samples = self.behavior_hz
        robots, input_ids, output_ids = self.sampling_tables(
            self.generation_number, ((r.name, r.team, r.number) for r in self.world.agents)
        )
        programs = {key: running[1] for key, running in self.programs.items() if running is not None}
        for key, description in self.descriptions.items():
            programs.setdefault(key, description)
        structure = {"programs": programs, "robots": robots}
        return NewGeneration(
            self.generation_number,
            self.reason,
            orjson.dumps(structure),
            orjson.dumps(self.world.static_scene()),
            input_ids,
            output_ids,
            self.seed,
            dict(self.errors),
            fork,
            {key: codec.tables.enums for key, codec in self.codecs[self.generation_number].items()},
            raw_values=True,
        )

    def sample_droppable(self) -> bool:
        """Whether the next tick's sample may be dropped when the server falls behind.

        Not in the first second of a generation: a fork's first divergence from its original and
        what a reload or reset changed are looked for in exactly those ticks, and the server is
        busiest then (a new structure for every client). One second of samples is a bounded queue.
        """
        if self.kept_samples > 0:
            self.kept_samples -= 1
            return False
        return True

    def _tick_time(self) -> int:
        # The clock of the tick just run (the loop's now_ms is already the next tick's).
        loop = self.loop
        return loop.start_ms + round(max(loop.ticks - 1, 0) * 1000 / self.behavior_hz)

    def sample(self) -> Sample:
        """The sample of the tick just run (without running one: after a reload or reset too)."""
        started = time.perf_counter()
        self.seq += 1
        paths, extras, inputs, outputs, reads = self.robot_samples()
        dumps = orjson.dumps
        world = self.world
        sample = Sample(
            self.seq,
            self.generation_number,
            self._tick_time(),
            time.time() * 1000.0,
            self.paused,
            self.speed,
            paths,
            extras,
            inputs,
            outputs,
            dumps(world.dynamic_scene()),
            dumps(world.status()),
            tuple(reads),
        )
        self.timing.sample += time.perf_counter() - started
        return sample

    def tick(self) -> Sample:
        """Run one behavior tick (engines + physics) and sample it."""
        started = time.perf_counter()
        cpu = time.thread_time()
        self.loop.tick()
        found = self.check_breakpoints() if self.breakpoints.armed else None
        sampling = time.thread_time()
        sample = self.sample()
        if found:
            self.record_hits(found, sample.seq, sample.t)
        done = time.perf_counter()
        timing = self.timing
        timing.busy += done - started
        end = time.thread_time()
        timing.cpu += end - cpu
        timing.sample_cpu += end - sampling
        timing.ticks += 1
        timing.add(done, self.loop.sim_seconds)
        return sample

    # -- commands ---------------------------------------------------------------------------------

    def execute(self, command: WorkerCommand | WorkerRequest, owner: str | None = None) -> Any:
        """Carry out one command (docs/protocol.md); generations and samples it makes go to :attr:`emit`.

        ``command`` is a command dataclass of ``xabsl_studio.server.protocol.commands`` (validated at the server's edge,
        so its arguments have their types and static ranges) or a :class:`WorkerRequest`.

        Raises:
            CommandError: arguments that do not fit this world or program; the simulation is unchanged.
        """
        body = command.body if isinstance(command, WorkerRequest) else command
        if isinstance(command, WorkerRequest):
            owner = command.owner
        handler = getattr(self, f"_op_{body.op}", None)
        if handler is None:
            raise CommandError(f"unknown op {body.op!r}")
        seq, ticks = self.seq, self.loop.ticks
        try:
            result = handler(body, owner)
        except (DebugError, EngineError) as error:
            raise CommandError(str(error)) from None
        if self.logging and body.op in LOGGED_OPS and _changed_run(body, result):
            self.logs[-1].record(seq, ticks, body, owner, self.seq - seq)
        return result

    def _op_pause(self, command: Pause, owner: str | None) -> Any:
        self.paused = True
        return {"paused": True}

    def _op_resume(self, command: Resume, owner: str | None) -> Any:
        self.paused = False
        return {"paused": False}

    def _op_step(self, command: Step, owner: str | None) -> Any:
        ticks = command.ticks
        if not self.paused:
            raise CommandError("step works while the session is paused")
        sample = None
        sent = True
        for _ in range(ticks):
            if self.world.finished:
                break
            sample = self.tick()
            if self.hits:  # a breakpoint stops the steps too
                break
            sent = self.emit(sample, self.sample_droppable())
        if sample is not None and (not sent or self.hits):  # the state a paused client looks at must arrive
            self.emit(sample, False)
        for hit in self.take_hits():
            self.emit(hit, False)
        if sample is None:
            return {"seq": self.seq, "t": self._tick_time() if self.loop.ticks else 0}
        return {"seq": sample.seq, "t": sample.t}

    def _op_speed(self, command: Speed, owner: str | None) -> Any:
        self.speed = command.speed
        return {"speed": self.speed}

    def _op_reset(self, command: Reset, owner: str | None) -> Any:
        seed = self.seed if command.seed is None else command.seed
        self._build_world(seed)
        self.emit(self.generation("reset"), False)
        self.emit(self.sample(), False)
        return {"seed": seed}

    def _op_seek(self, command: Seek, owner: str | None) -> Any:
        raise CommandError("seek needs a replay (xabsl serve --replay FILE.mcap)")

    def _op_explain(self, command: Explain, owner: str | None) -> Any:
        if command.seq is not None:
            raise CommandError("explain at a past tick needs a replay (xabsl serve --replay FILE.mcap)")
        _, engine, codec = self._robot(command.robot)
        option = self._named(command.option, codec.option_ids, "option")
        debugger = Debugger(engine)
        explanation = debugger.explain(option)
        ir_option = codec.program.options[option]
        result = explanation_result(ir_option, explanation)
        result["tree"] = tree_result(ir_option, explanation.decided_in, explanation.leaf, None)
        mark_values(result["tree"], explanation)
        result.update(seq=None, t=None, recorded=False)
        if command.why_not is not None:
            # from the same reads as the explanation: the last decision's
            _, state, leaf, values = debugger.last_decision(option)
            result["why_not"] = why_not_result(ir_option, state, leaf, command.why_not, values)
        return result

    def _op_explain_recorded(self, command: ExplainRecorded, owner: str | None) -> Any:
        """Internal: explain decisions of past ticks from what they read (``explain`` with ``seq``)."""
        index, _, _ = self._robot(command.robot)
        key = self.keys[index] or ""
        codec = self.codecs.get(command.generation, {}).get(key)
        if codec is None:
            raise CommandError("that tick ran a version of the behavior this simulation no longer has")
        option = self._named(command.option, codec.option_ids, "option")
        ir_option = codec.program.options[option]
        results: list[dict[str, Any]] = []
        for seq, t, decided, leaf, _, reads in command.ticks:
            if not 0 <= decided < len(ir_option.states):
                raise CommandError(f"option {option} has no state {decided}")
            state = ir_option.states[decided]
            # The values the decision read in that tick, as the ring kept them: nothing is asked of the world now.
            read = decision_reads(orjson.loads(reads), ir_option.index) if reads else None
            values = ReadValues(codec.program, ir_option, read, codec.tables.enums)
            try:
                explanation = explain_decision(ir_option, state, leaf, values)
            except KeyError:
                raise CommandError(f"state {option}.{state.name} has no leaf {leaf}") from None
            result = explanation_result(ir_option, explanation)
            result.update(seq=seq, t=t, recorded=True, tree=tree_result(ir_option, state.name, leaf, values))
            if command.why_not is not None and not results:  # the explained tick, not the last transition's
                result["why_not"] = why_not_result(ir_option, state, leaf, command.why_not, values)
            results.append(result)
        return results

    def _op_status(self, command: Status, owner: str | None) -> Any:
        return self.status()

    def _op_world_command(self, command: WorldCommand, owner: str | None) -> Any:
        """A command of the world itself (``xabsl_studio.engine.host.CommandableWorld``); without ``name``: the list."""
        world = self.world
        if not isinstance(world, CommandableWorld):
            raise CommandError("this world has no commands")
        if command.name is None:
            return {"commands": world.commands()}
        try:
            result = world.command(command.name, dict(command.args))
        except WorldCommandError as error:
            raise CommandError(str(error)) from None
        if self.paused:  # a paused client must see what the command changed
            self.emit(self.sample(), False)
        return result

    def _op_apply(self, command: Apply, owner: str | None) -> Any:
        """Internal: hot-swap a program the server compiled clean."""
        return self.apply(command.key, command.program, command.program_json)

    # -- fork ----------------------------------------------------------------------------------------

    def _op_fork(self, command: ForkAt, owner: str | None) -> Any:
        """``fork``: rebuild the run of tick ``seq`` to just before it, check it, go on with the programs in force.

        Tick ``seq`` (a tick sample) runs again live; a sample that no tick made (a build, a
        reload, a fork) is restored as it was. The re-simulated state must equal what the ring
        recorded of the sample before (or of ``seq`` itself when no tick made it); otherwise the
        command fails and the running world is left as it was.
        """
        started = time.perf_counter()
        seq = command.seq
        if seq > self.seq:
            raise CommandError(f"tick {seq} has not run yet (the newest is {self.seq})")
        self._prune_logs()
        log = next((run for run in reversed(self.logs) if run.covers(seq)), None)
        if log is None:
            raise CommandError(f"tick {seq} is older than the session log: a fork starts from a tick of the history")
        if log.problem is not None:
            raise CommandError(f"tick {seq} cannot be forked: {log.problem}")
        v = seq - log.offset
        if log.full_at is not None and v > log.full_at:
            raise CommandError(
                f"the session log stopped at tick {log.full_at + log.offset} (more than {len(log.events)} commands "
                "since the world was built): reset the world to fork later ticks"
            )
        anchor = log.is_anchor(v)
        ticks = log.ticks_at(v) - (0 if anchor else 1)
        if ticks > FORK_MAX_SECONDS * self.behavior_hz:
            raise CommandError(
                f"forking tick {seq} re-simulates {ticks / self.behavior_hz:.0f} s since the world was built "
                f"(at most {FORK_MAX_SECONDS:.0f} s): reset the world to fork later ticks"
            )
        check = seq if anchor else seq - 1
        recorded = command.recorded.get(check)
        if recorded is None:
            raise CommandError(f"tick {check} is not in the history any more: the fork cannot be checked")
        replay = self._replay(log, v, check, recorded, ticks)
        # Adopt the re-simulated world, then run the programs in force now.
        current = dict(self.programs)
        self.world, self.loop, self.engines, self.keys = replay.world, replay.loop, replay.engines, replay.keys
        self._owners = replay._owners
        self.errors = dict(replay.errors)
        self.programs = dict(replay.programs)
        self.seed = log.seed
        self._switch(current)
        self.timing.window.clear()  # the simulated clock went back
        start = self.seq + 1
        self._start_log(log.child(v, ticks, Switch(dict(self.programs)), start))
        t = self.loop.start_ms + round(max(log.ticks_at(v) - 1, 0) * 1000 / self.behavior_hz)
        self.emit(self.generation("fork", (seq, t, start)), False)
        self.emit(self.sample(), False)
        ms = round(1000 * (time.perf_counter() - started), 1)
        return {"seq": seq, "t": t, "start": start, "ticks": ticks, "ms": ms}

    def _replay(self, log: RunLog, v: int, check: int, recorded: tuple[tuple[Any, ...], Any], ticks: int) -> Simulation:
        """Run ``log`` again from its seed up to run-local sample ``v`` (``ticks`` ticks), checking sample ``check``."""
        replay = Simulation(
            WorkerConfig(
                self.example,
                seed=log.seed,
                paused=True,
                behavior_hz=self.behavior_hz,
                physics_hz=self.physics_hz,
                programs=dict(log.programs),
                descriptions=dict(self.descriptions),
            )
        )
        replay.logging = False
        replay.generation("connect")  # the samplers: commands name options and symbols by id
        check_v = check - log.offset
        checked = False
        for event in log.events:
            if event.at >= v:
                break
            if not checked and event.at >= check_v:
                replay._advance(log.ticks_at(check_v))
                replay._verify(check, recorded)
                checked = True
            replay._advance(event.ticks)
            if isinstance(event.command, Switch):
                replay._switch(event.command.programs)
                replay.generation("fork")
                continue
            try:
                replay.execute(event.command, event.owner)
            except CommandError as error:
                raise CommandError(f"the session log does not replay at tick {replay.loop.ticks}: {error}") from None
        if not checked:
            replay._advance(log.ticks_at(check_v))
            replay._verify(check, recorded)
        replay._advance(ticks)
        return replay

    def _advance(self, ticks: int) -> None:
        """Run ticks (without sampling them) until ``ticks`` have run."""
        loop = self.loop
        if loop.ticks > ticks:
            raise CommandError(f"the session log is out of order at tick {ticks}")
        while loop.ticks < ticks:
            loop.tick()

    def _shown_path(self, index: int) -> bytes:
        """Robot ``index``'s path now as the history shows it: parameters as the server shows them."""
        sampler = self.samplers[index]
        key = self.keys[index]
        assert sampler is not None and key is not None
        running = self.programs.get(key)
        description = running[1] if running is not None else self.descriptions.get(key, {})
        params = program_display(description, sampler.codec.tables.enums).params
        return display_path(params, orjson.dumps(sampler.path()))

    def _verify(self, seq: int, recorded: tuple[tuple[Any, ...], Any]) -> None:
        """The state now must be what sample ``seq`` recorded: every robot's path, the world's scene."""
        paths, scene = recorded
        for index, sampler in enumerate(self.samplers):
            try:
                path = orjson.loads(self._shown_path(index)) if sampler is not None else []
            except Exception:  # as ``sample``: a broken tree reads as an empty path
                path = []
            if index >= len(paths) or path != paths[index]:
                name = self.world.agents[index].name
                raise CommandError(
                    f"the re-simulated run differs from the history at tick {seq} ({name}'s activation path): "
                    "the world is not deterministic or something changed it outside the session log; "
                    "the run goes on unchanged"
                )
        if orjson.loads(orjson.dumps(self.world.dynamic_scene())) != scene:
            raise CommandError(
                f"the re-simulated run differs from the history at tick {seq} (the world's scene): "
                "the world is not deterministic or something changed it outside the session log; "
                "the run goes on unchanged"
            )

    # -- hot reload ----------------------------------------------------------------------------------

    def apply(self, key: str, program: Program, program_json: dict[str, Any]) -> str | None:
        """Hot-swap a clean program into the engines of behavior ``key``.

        Returns:
            None when swapped, else why the running behavior was kept.
        """
        problem = self._swap(key, program, program_json)
        if problem is not None:
            return problem
        self.emit(self.generation("reload"), False)
        self.emit(self.sample(), False)
        return None

    def _swap(self, key: str, program: Program, program_json: dict[str, Any]) -> str | None:
        """The engines of ``key`` run ``program`` (states kept where they still exist); None, or why not."""
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
        except EngineError as error:
            # Engines are reloaded one by one; with one host they fail alike, so the first fails.
            self.errors[key] = str(error)
            return f"the behavior does not run on this host: {error}"
        self.errors[key] = None
        self.programs[key] = (program, program_json)
        self.descriptions.pop(key, None)
        return None

    def _switch(self, programs: Programs) -> None:
        """Run ``programs`` where another version runs (``fork``; a program that does not link is not run)."""
        for key, running in programs.items():
            have = self.programs.get(key)
            if running is not None and (have is None or have[0] is not running[0]):
                self._swap(key, *running)

    # -- status ----------------------------------------------------------------------------------------

    def status(self) -> dict[str, Any]:
        """The simulation's part of the session status (the server adds ring, clients, programs)."""
        timing = self.timing
        return {
            "paused": self.paused,
            "finished": self.world.finished,
            "speed": self.speed,
            "seed": self.seed,
            "seq": self.seq,
            "real_time_factor": round(timing.real_time_factor(), 3),
            "tick_ms": round(1000 * timing.busy / timing.ticks, 3) if timing.ticks else 0.0,
            # raw counters, for windowed measurements (benchmarks/stream_load.py)
            "timing": {
                "ticks": timing.ticks,
                "busy_seconds": timing.busy,
                "cpu_seconds": timing.cpu,
                "sim_seconds": self.loop.sim_seconds,
                "frame_seconds": timing.sample,
                "frame_cpu_seconds": timing.sample_cpu,
            },
            "errors": dict(self.errors),
            "pipe": {
                "sent": self.channel.sent,
                "dropped": self.channel.dropped,
                "bytes": self.channel.bytes_sent,
                "backlog": self.channel.backlog,
            }
            if self.channel is not None
            else {},
            "world": self.world.status(),
        }


#: ``explain`` and ``explain_recorded`` as the simulation answers them, for every other owner of
#: engines (the attach host, ``xabsl_studio.server.simulation.host``): they read only what an
#: :class:`~xabsl_studio.server.simulation.engines.EngineSet` has (``_robot``, ``_named``, ``keys``,
#: ``codecs``), so a host answers "why" exactly as the studio's own simulation does.
EXPLAIN_OPS: dict[str, Callable[[Any, Any, str | None], Any]] = {
    "explain": Simulation._op_explain,
    "explain_recorded": Simulation._op_explain_recorded,
}


def check_speed(speed: Any) -> float:
    """``speed`` as a float when it is a number in the allowed range (the server's start option)."""
    if isinstance(speed, bool) or not isinstance(speed, int | float) or not MIN_SPEED <= speed <= MAX_SPEED:
        raise ValueError(f"speed must be a number in {MIN_SPEED:g}..{MAX_SPEED:g}")
    return float(speed)


def _collect(message: FromWorker, droppable: bool) -> bool:
    return True


def _changed_run(command: Any, result: Any) -> bool:
    """Whether a logged op that succeeded changed the run (a list of world commands, a refused swap did not)."""
    if command.op == "world_command":
        return command.name is not None
    if command.op == "apply":
        return result is None
    return True


# -- the process ------------------------------------------------------------------------------------


def main(sock: socket.socket, config: WorkerConfig) -> None:
    """Entry point of the simulation process: run until told to stop or the server goes away."""
    # Ctrl+C reaches the whole process group; the server decides when this process ends.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    channel: WorkerChannel = Channel(sock)
    try:
        try:
            sim = Simulation(config)
        except Exception as error:  # say why (a fork that cannot re-simulate), then end
            channel.send(Crash(f"{type(error).__name__}: {error}", traceback.format_exc(), config.seq, 0))
            _drain(channel)
            raise SystemExit(1) from None
        run(channel, sim)
    except ChannelClosed:
        pass
    finally:
        channel.close()


def run(channel: WorkerChannel, sim: Simulation) -> None:
    """The tick loop (see the module docstring); returns on a ``stop`` message.

    Raises:
        ChannelClosed: the server went away.
    """
    sim.emit = channel.send
    sim.channel = channel
    channel.send(sim.generation(sim.reason))
    channel.send(sim.sample())
    fd = channel.fileno()
    next_due = time.perf_counter()
    while True:
        if sim.paused or sim.world.finished:
            wait: float = 0.05
            next_due = time.perf_counter()
        else:
            wait = next_due - time.perf_counter()
        if wait > 0:
            writers = [fd] if channel.backlog else []
            readable, _, _ = select.select([fd], writers, [], wait)
            if not readable:
                channel.flush()
                continue
        for message in channel.receive():
            if not isinstance(message, WorkerRequest):  # Stop
                channel.flush()
                return
            _command(channel, sim, message)
        if sim.paused or sim.world.finished or time.perf_counter() < next_due:
            continue
        try:
            sample = sim.tick()
        except Exception as error:  # the world broke: report, end this process (reset starts a new one)
            channel.send(Crash(f"{type(error).__name__}: {error}", traceback.format_exc(), sim.seq, sim._tick_time()))
            _drain(channel)
            raise SystemExit(1) from None
        if sim.hits:  # a breakpoint paused the simulation: its tick must arrive, then the hits
            channel.send(sample)
            for hit in sim.take_hits():
                channel.send(hit)
            continue
        channel.send(sample, droppable=sim.sample_droppable())
        next_due += 1.0 / (sim.behavior_hz * sim.speed)
        if time.perf_counter() - next_due > 0.25:
            next_due = time.perf_counter()


def _command(channel: WorkerChannel, sim: Simulation, request: WorkerRequest) -> None:
    try:
        result = sim.execute(request.body, request.owner)
        ok, error = True, None
    except CommandError as problem:
        result, ok, error = None, False, str(problem)
    except Exception as problem:  # a bug in a command must not end the simulation: answer it
        traceback.print_exc()
        result, ok, error = None, False, f"internal error: {type(problem).__name__}: {problem}"
    channel.send(WorkerReply(request.ident, ok, result, error))


def _drain(channel: WorkerChannel, timeout: float = 2.0) -> None:
    deadline = time.monotonic() + timeout
    fd = channel.fileno()
    while channel.backlog and time.monotonic() < deadline:
        select.select([], [fd], [], 0.05)
        channel.flush()


if __name__ == "__main__":  # pragma: no cover - started through multiprocessing
    print("xabsl_studio.server.simulation.worker runs inside `xabsl serve`", file=sys.stderr)
    sys.exit(os.EX_USAGE)
