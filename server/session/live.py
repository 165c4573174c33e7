"""The live session as the server process sees it: a simulation process, its frames, its commands.

The world and the engines live in a separate process (``xabsl_studio.server.simulation.worker``, started with the
forkserver or spawn method, never a fork of the running server) so that websocket clients cannot
slow the simulation through the GIL (docs/server.md). This module is that process's other end:

* **frames**: the worker sends one sample per tick over a non-blocking socket
  (``xabsl_studio.server.protocol.channel``); the asyncio loop reads it with ``add_reader`` (no extra thread), turns it
  into a ring :class:`~xabsl_studio.server.session.frames.Entry` (masks, delta and key frames) and calls ``notify``
  (the :class:`~xabsl_studio.server.api.clients.Hub`). Generation messages (start, reload, reset) come before the
  first sample of their generation and become :attr:`Session.generation`;
* **commands**: :meth:`Session.request` sends a validated command (a dataclass of
  ``xabsl_studio.server.protocol``) in a
  :class:`~xabsl_studio.server.protocol.host.WorkerRequest` and resolves when the worker
  answers (the samples a command produced, e.g. by ``step``, arrive before the answer);
* **compiling** stays here (:meth:`Session.compile`, run in a worker thread by the app); a clean
  program is pickled to the simulation, which hot-swaps it between two ticks (:meth:`Session.apply`);
* **crashes**: when the simulation process ends unasked (an exception in the world, a kill), the
  session keeps serving: status and clients learn why (``on_crash``), the ring stays readable,
  and ``reset`` starts a new process (same seed unless given) that continues seq and generation.

Mirrored state (``paused``, ``speed``, ``seed``) follows the samples and answers, so reading it
never waits for the worker; :meth:`Session.status` asks the worker for its counters.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import itertools
import logging
import multiprocessing
import socket
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar

import orjson

from xabsl_studio.engine.emit.json import program_to_json
from xabsl_studio.engine.host import DEFAULT_BEHAVIOR_HZ, DEFAULT_PHYSICS_HZ, BehaviorSource, Example
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.lang import Compilation, compile_file
from xabsl_studio.engine.lang.condition import check_condition
from xabsl_studio.engine.runtime.breakpoints import Breakpoint, BreakpointError
from xabsl_studio.server.protocol.channel import Channel, ChannelClosed
from xabsl_studio.server.protocol.commands import (
    AttachHost,
    BreakpointCommand,
    CheckCondition,
    EnableBreakpoint,
    Explain,
    Fork,
    ListBreakpoints,
    Pause,
    Query,
    RemoveBreakpoint,
    Reset,
    Resume,
    SetBreakpoint,
    Status,
)
from xabsl_studio.server.protocol.host import (
    Apply,
    Crash,
    ExplainRecorded,
    ForkAt,
    FromWorker,
    Hit,
    NewGeneration,
    ReleaseOwner,
    Sample,
    SetBreakpoints,
    Stop,
    ToWorker,
    WorkerCommand,
    WorkerReply,
    WorkerRequest,
)
from xabsl_studio.server.protocol.replies import ForkOrigin
from xabsl_studio.server.protocol.rest import ProgramStatus
from xabsl_studio.server.protocol.types import HelloReason
from xabsl_studio.server.session import frames
from xabsl_studio.server.session.breakpoints import BreakpointStore, validate
from xabsl_studio.server.session.frames import Entry, FrameRecorder, Generation, Ring
from xabsl_studio.server.session.generations import Generations
from xabsl_studio.server.session.query import answer_history
from xabsl_studio.server.session.recording import LiveRecorder
from xabsl_studio.server.simulation import worker
from xabsl_studio.server.simulation.forkstart import ForkStart
from xabsl_studio.server.simulation.worker import CommandError, WorkerConfig, check_speed

if TYPE_CHECKING:
    from xabsl_studio.engine.record import Recording

__all__ = ["RING_SECONDS", "CommandError", "ProgramState", "Session", "fork_request"]

log = logging.getLogger("xabsl.server")

#: Seconds of ticks the ring buffer keeps.
RING_SECONDS = 120.0
#: Seconds the simulation process may take to come up (first start of the forkserver included).
START_TIMEOUT = 60.0
#: Seconds a stopping simulation process gets before it is terminated, then killed.
STOP_TIMEOUT = 5.0


@dataclass(slots=True)
class ProgramState:
    """The last compile of one behavior source, and the program running (last clean compile)."""

    source: BehaviorSource
    compilation: Compilation | None = None
    running: Program | None = None
    running_json: dict[str, Any] | None = None
    error: str | None = None
    #: while nothing compiled clean yet: what parsed (``Compilation.partial``) and its program JSON,
    #: shown by the studio (graph, option views, symbols) until the behavior compiles
    partial: Program | None = None
    partial_json: dict[str, Any] | None = None
    #: the source texts (display name -> text) the running program was compiled from
    running_sources: dict[str, str] | None = None

    @property
    def shown(self) -> Program | None:
        """The program the studio shows: the running one, else what parsed of a broken one."""
        return self.running if self.running is not None else self.partial

    def as_dict(self) -> ProgramStatus:
        """The behavior set as ``GET /api/status`` shows it."""
        comp = self.compilation
        return {
            "folder": self.source.folder.name,
            "agents_file": self.source.agents_file.name,
            "ok": comp is not None and comp.ok and self.error is None,
            "running": self.running is not None,
            "partial": self.running is None and self.partial is not None,
            "error": self.error,
            "diagnostics": [d.as_dict() for d in comp.diagnostics] if comp is not None else [],
            "files": list(comp.files) if comp is not None else [],
        }


def _context(example: Example) -> Any:
    """The start method: forkserver where there is one (cheap starts, preloaded modules), else spawn."""
    if "forkserver" in multiprocessing.get_all_start_methods():
        context = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(["xabsl_studio.server.simulation.worker", *getattr(example, "preload", ())])
        return context
    return multiprocessing.get_context("spawn")


class Session:
    """A running example: compiles here, simulates in its own process, records frames here.

    Args:
        example: the adapter of the example folder.
        seed: the world's seed.
        speed: real time x speed (0.1..20).
        behavior_hz, physics_hz: the loop's rates (``xabsl_studio.engine.host``).
        ring_seconds: how much history the ring buffer keeps.
        state_dir: where breakpoints are stored (default: ``xabsl_studio.server.session.breakpoints.state_folder()``).

    The studio's edge (``xabsl_studio.server.api``) serves every kind of session (live, a replay,
    a fork, attached robots) through this class's interface; what differs between kinds, it asks
    the session (:attr:`keeps_sources`, :attr:`played`, :meth:`history_span`), never its class.
    """

    #: Whether the session keeps its generations' behavior sources (hot reload, generation
    #: diffs, version compare): a replay has only the recording's intermediate code.
    keeps_sources: ClassVar[bool] = True

    @property
    def played(self) -> Recording | None:
        """The recording this session plays back, or None: it runs (and records) its own ticks."""
        return None

    def history_span(self, x0: int, x1: int, every: int) -> tuple[list[frames.Generation], int, Iterator[bytes]]:
        """The ``history`` of timeline times ``x0 .. x1``: generations whose ticks follow, a count, the frames."""
        return frames.span_history(self.ring, x0, x1, every)

    def __init__(
        self,
        example: Example,
        seed: int = 1,
        speed: float = 1.0,
        behavior_hz: int = DEFAULT_BEHAVIOR_HZ,
        physics_hz: int = DEFAULT_PHYSICS_HZ,
        ring_seconds: float = RING_SECONDS,
        state_dir: Path | None = None,
    ) -> None:
        self.example = example
        self.seed = seed
        self.speed = check_speed(speed)
        self.behavior_hz = behavior_hz
        self.physics_hz = physics_hz
        self.paused = False
        self.programs: dict[str, ProgramState] = {s.key: ProgramState(s) for s in example.sources}
        self.ring = Ring(ring_seconds, behavior_hz)
        self.recorder = FrameRecorder(self.ring)
        #: called on the asyncio loop after the samples that arrived together were recorded
        self.notify: Callable[[Entry], None] = lambda entry: None
        #: called on the asyncio loop when the simulation process ended unasked (with crash info)
        self.on_crash: Callable[[dict[str, Any]], None] = lambda crash: None
        self.generation: Generation | None = None
        #: the generations kept by number, with their sources (diffs of reloads)
        self.generations = Generations()
        self.crash: dict[str, Any] | None = None
        self.restarts = 0
        self.pid: int | None = None
        self._process: Any = None
        self._channel: Channel[ToWorker, FromWorker] | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._pending: dict[int, asyncio.Future[tuple[bool, Any, str | None]]] = {}
        self._ids = itertools.count(1)
        self._started: asyncio.Future[None] | None = None
        self._stopping = False
        self._worker_status: dict[str, Any] = {}
        self._restart_lock: asyncio.Lock | None = None
        #: records the session to a folder from the samples (``xabsl_studio.server.session.recording``); None: off
        self.live_recorder: LiveRecorder | None = None
        #: start the first simulation at a tick of a recording (``xabsl_studio.server.session.fork``); None: fresh
        self.fork_start: ForkStart | None = None
        self._incoming: dict[str, Program] = {}
        self._incoming_sources: dict[str, dict[str, str]] = {}
        for key in self.programs:
            self._store_compilation(key, self.compile(key))
        #: called on the asyncio loop when a breakpoint hit (after the sample of its tick)
        self.on_breakpoint: Callable[[Hit], None] = lambda hit: None
        self.breakpoint_store = BreakpointStore(state_dir)
        #: the fork the running world comes from (``fork``); None since the last start or reset
        self.fork: ForkOrigin | None = None
        #: per (robot, option id): where the last live ``explain`` scan of the ring stopped
        self._scans: dict[tuple[int, int], Scan] = {}
        #: per behavior key: its breakpoints by id (stored per agents file)
        self.breakpoints: dict[str, dict[int, Breakpoint]] = {
            key: {p.id: p for p in self.breakpoint_store.load(state.source.agents_file)}
            for key, state in self.programs.items()
        }

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
            state.running_sources = compilation.sources
        else:
            _store_partial(state, compilation)

    def shown_program(self, key: str) -> Program | None:
        """The program the studio draws for behavior ``key`` (graphs): the running or partial one."""
        state = self.programs.get(key)
        return state.shown if state is not None else None

    # -- the simulation process ----------------------------------------------------------------------

    @property
    def running(self) -> bool:
        """Whether the simulation process runs (started, not crashed, not stopped)."""
        return self._process is not None and self._channel is not None and self.crash is None

    async def start(self) -> None:
        """Start the simulation process; returns once its first frame is in the ring."""
        assert self._process is None, "the session runs already"
        self._loop = asyncio.get_running_loop()
        self._restart_lock = asyncio.Lock()
        self._stopping = False
        await self._spawn(self.seed, "connect")

    async def _spawn(self, seed: int, reason: HelloReason) -> None:
        loop = self._loop
        assert loop is not None
        latest = self.ring.latest
        fork = self.fork_start if reason == "connect" else None
        first = fork.at - 2 if fork is not None else 0  # its first sample: tick at - 1, as recorded
        config = WorkerConfig(
            example=self.example,
            seed=seed,
            speed=self.speed,
            paused=self.paused,
            behavior_hz=self.behavior_hz,
            physics_hz=self.physics_hz,
            programs={
                key: (state.running, state.running_json)
                if state.running is not None and state.running_json is not None
                else None
                for key, state in self.programs.items()
            },
            descriptions={
                key: state.partial_json
                for key, state in self.programs.items()
                if state.running is None and state.partial_json is not None
            },
            seq=max(latest.seq if latest else first, self.crash.get("seq", 0) if self.crash else 0),
            generation=self.generation.number if self.generation is not None else 0,
            reason=reason,
            breakpoints={key: tuple(points.values()) for key, points in self.breakpoints.items()},
            history_ticks=self.ring.capacity,
            fork=fork,
        )
        ours, theirs = socket.socketpair()
        process = _context(self.example).Process(
            target=worker.main, args=(theirs, config), daemon=True, name="xabsl-simulation"
        )
        try:
            await asyncio.to_thread(process.start)
        finally:
            theirs.close()
        channel: Channel[ToWorker, FromWorker] = Channel(ours)
        self._process, self._channel, self.pid = process, channel, process.pid
        self._started = loop.create_future()
        self.crash = None
        loop.add_reader(channel.fileno(), self._on_readable)
        try:
            await asyncio.wait_for(asyncio.shield(self._started), START_TIMEOUT)
        except TimeoutError:
            raise RuntimeError("the simulation process did not start") from None

    def _on_readable(self) -> None:
        channel = self._channel
        if channel is None:
            return
        try:
            messages = channel.receive()
        except ChannelClosed:
            self._ended()
            return
        self.receive(messages)

    def receive(self, messages: list[FromWorker]) -> None:
        """Record what the host sent (samples, generations, replies, hits, a crash), then notify.

        The simulation process's messages come through here, and so do an attached session's
        (``xabsl_studio.server.session.attached``), whose hosts are programs elsewhere.
        """
        latest: Entry | None = None
        hits: list[Hit] = []
        for message in messages:
            if isinstance(message, Sample):
                if self.generation is None or message.gen != self.generation.number:
                    continue  # never expected: a sample always follows its generation
                message = self.generation.shown(message)
                latest = self.recorder.record(self.generation, message)
                self.paused, self.speed = message.paused, message.speed
                if self.live_recorder is not None:
                    self.live_recorder.sample(message)
            elif isinstance(message, WorkerReply):
                future = self._pending.pop(message.ident, None) if message.ident is not None else None
                if future is not None and not future.done():
                    future.set_result((message.ok, message.result, message.error))
            elif isinstance(message, NewGeneration):
                self.generation = Generation.from_message(message)
                sources = {k: self._incoming_sources.get(k) or s.running_sources for k, s in self.programs.items()}
                self.generations.add(self.generation, {k: v for k, v in sources.items() if v is not None}, self.ring)
                self.seed = message.seed
                if message.fork is not None:
                    self.fork = ForkOrigin(seq=message.fork[0], t=message.fork[1], start=message.fork[2])
                elif message.reason != "reload":  # a reload goes on in the same run (and fork)
                    self.fork = None
                for key, error in message.errors.items():
                    if key in self.programs:
                        self.programs[key].error = error
                if self.live_recorder is not None:
                    programs = {k: self._incoming.get(k) or s.running for k, s in self.programs.items()}
                    self.live_recorder.generation(self.generation, programs, message.seed, self.generation.changed)
            elif isinstance(message, Hit):
                hits.append(message)
            elif isinstance(message, Crash):
                self.crash = {
                    "message": message.message,
                    "traceback": message.traceback,
                    "seq": message.seq,
                    "t": message.t,
                }
                log.error("the simulation stopped: %s\n%s", message.message, message.traceback)
        if latest is not None:
            if self._started is not None and not self._started.done():
                self._started.set_result(None)
            self.notify(latest)
        for hit in hits:
            self.paused = True
            self.on_breakpoint(hit)

    def _ended(self) -> None:
        """The simulation process closed its end: asked to (stop) or not (a crash)."""
        loop, channel, process = self._loop, self._channel, self._process
        if channel is not None and loop is not None:
            with contextlib.suppress(Exception):
                loop.remove_reader(channel.fileno())
            with contextlib.suppress(Exception):
                loop.remove_writer(channel.fileno())
            channel.close()
        self._channel = None
        if process is not None:
            process.join(timeout=1.0)  # it closed the socket on its way out: this is quick
            code = process.exitcode
        else:
            code = None
        if not self._stopping and self.crash is None:
            self.crash = {
                "message": f"the simulation process ended (exit code {code})",
                "traceback": None,
                "seq": self.ring.latest.seq if self.ring.latest else 0,
                "t": None,
            }
        if self.crash is not None:
            self.crash["exit_code"] = code
        for future in self._pending.values():
            if not future.done():
                future.set_exception(CommandError(self._stopped_message()))
        self._pending.clear()
        if self._started is not None and not self._started.done():
            self._started.set_exception(RuntimeError(self._stopped_message()))
        if not self._stopping and self.crash is not None:
            self.on_crash(self.crash)

    def _stopped_message(self) -> str:
        if self.crash is None:
            return "the simulation is stopping"
        return f"the simulation stopped: {self.crash['message']}; reset starts it again"

    async def aclose(self) -> None:
        """Stop the simulation process (on the loop that started it); no zombie is left."""
        self._stopping = True
        channel, loop = self._channel, self._loop
        if channel is not None and loop is not None:
            with contextlib.suppress(Exception):
                loop.remove_reader(channel.fileno())
            with contextlib.suppress(Exception):
                loop.remove_writer(channel.fileno())
            with contextlib.suppress(ChannelClosed, OSError):
                channel.send(Stop())
                channel.flush()
        await asyncio.to_thread(self.stop)

    def stop(self) -> None:
        """Stop the simulation process from any thread (waits, then terminates, then kills)."""
        self._stopping = True
        process, channel = self._process, self._channel
        if channel is not None:
            with contextlib.suppress(ChannelClosed, OSError):
                channel.send(Stop())
                channel.flush()
        if process is not None:
            process.join(timeout=STOP_TIMEOUT)
            if process.is_alive():
                process.terminate()
                process.join(timeout=STOP_TIMEOUT)
            if process.is_alive():
                process.kill()
                process.join(timeout=STOP_TIMEOUT)
        if channel is not None:
            channel.close()
        self._channel = None
        self._process = None
        if self.live_recorder is not None:
            self.live_recorder.close()
        for future in list(self._pending.values()):
            if not future.done() and self._loop is not None and not self._loop.is_closed():
                with contextlib.suppress(RuntimeError):
                    self._loop.call_soon_threadsafe(_fail, future, CommandError("the session stopped"))
        self._pending.clear()

    # -- commands ----------------------------------------------------------------------------------

    async def request(
        self, command: WorkerCommand | BreakpointCommand | Fork | Query | AttachHost, owner: str | None = None
    ) -> Any:
        """Carry out a command in the simulation (docs/protocol.md); its result.

        Raises:
            CommandError: arguments that do not fit the world or program, or the simulation is
                not running (crashed) and the command needs it; a bad ``query`` condition.
        """
        if isinstance(command, Query):
            return await answer_history(self.ring, command)
        if isinstance(command, Reset) and self.crash is not None and not self._stopping:
            return await self._restart(command)
        if isinstance(command, Status):
            return await self.status()
        if isinstance(command, SetBreakpoint | RemoveBreakpoint | EnableBreakpoint | ListBreakpoints | CheckCondition):
            return await self.breakpoint_command(command)
        if isinstance(command, Explain):
            return await self.explain(command, owner)
        if isinstance(command, AttachHost):
            return await self.attach_host(command)
        if isinstance(command, Fork):
            command = fork_request(self.ring, command.seq)
        ok, result, error = await self._send(command, owner)
        if not ok:
            raise CommandError(error)
        if self.live_recorder is not None:
            self.live_recorder.command(command)
        if isinstance(command, Pause | Resume):
            # a paused simulation sends no sample that would carry the new state: mirror the answer
            self.paused = bool(result["paused"])
        return result

    async def attach_host(self, command: AttachHost) -> dict[str, Any]:
        """Connect… (``attach_host``): only a studio on hosts elsewhere attaches more of them.

        Raises:
            CommandError: always here (``xabsl_studio.server.session.attached`` answers it).
        """
        raise CommandError("this studio runs its own world: attach to hosts with xabsl attach HOST:PORT")

    async def _send(self, command: WorkerCommand, owner: str | None) -> tuple[bool, Any, str | None]:
        channel, loop = self._channel, self._loop
        if channel is None or loop is None or self.crash is not None:
            raise CommandError(self._stopped_message())
        ident = next(self._ids)
        future: asyncio.Future[tuple[bool, Any, str | None]] = loop.create_future()
        self._pending[ident] = future
        try:
            channel.send(WorkerRequest(ident, command, owner))
        except ChannelClosed:
            self._pending.pop(ident, None)
            raise CommandError(self._stopped_message()) from None
        self._watch_backlog()
        return await future

    def _watch_backlog(self) -> None:
        channel, loop = self._channel, self._loop
        if channel is None or loop is None or not channel.backlog:
            return

        def flush() -> None:
            try:
                done = channel.flush()
            except ChannelClosed:
                done = True
            if done:
                loop.remove_writer(channel.fileno())

        loop.add_writer(channel.fileno(), flush)

    async def _restart(self, command: Reset) -> Any:
        """``reset`` after a crash: a new simulation process (same seed unless given)."""
        seed = self.seed if command.seed is None else command.seed
        assert self._restart_lock is not None
        async with self._restart_lock:
            if self.crash is not None:
                if self._process is not None:
                    await asyncio.to_thread(self._process.join, STOP_TIMEOUT)
                self._process = None
                self.restarts += 1
                await self._spawn(seed, "reset")
        return {"seed": seed}

    def release_owner(self, owner: str) -> None:
        """Release what client ``owner`` forced and overrode (it disconnected); no answer awaited."""
        channel = self._channel
        if channel is None or self.crash is not None:
            return
        with contextlib.suppress(ChannelClosed):
            channel.send(WorkerRequest(None, ReleaseOwner(), owner))
            self._watch_backlog()

    # -- breakpoints ---------------------------------------------------------------------------------

    def _breakpoint_key(self, program: str | None, robot: int | None = None) -> str:
        if program is not None:
            if program not in self.programs:
                raise CommandError(f"unknown program {program!r} (programs: {', '.join(self.programs)})")
            return program
        if robot is not None and self.generation is not None:
            robots = self.generation.structure.get("robots", [])
            if not 0 <= robot < len(robots):
                raise CommandError(f"robot must be a robot id in 0..{len(robots) - 1}")
            key = robots[robot].get("program")
            if key is None:
                raise CommandError(f"robot {robot} runs no XABSL engine")
            return str(key)
        return next(iter(self.programs))

    def breakpoint_list(self, key: str | None = None) -> dict[str, Any]:
        """The ``list_breakpoints`` result (of behavior ``key``, or of all)."""
        listed = []
        for program, points in self.breakpoints.items():
            if key is not None and program != key:
                continue
            running = self.programs[program].running
            for point in sorted(points.values(), key=lambda p: p.id):
                try:
                    validate(running, point)
                    problem = None
                except BreakpointError as error:
                    problem = str(error)
                fields = point.as_dict()
                fields["breakpoint"] = fields.pop("id")
                listed.append({"program": program, **fields, "description": point.describe(), "problem": problem})
        return {"breakpoints": listed}

    async def breakpoint_command(self, command: BreakpointCommand) -> Any:
        """Set, remove, enable, list breakpoints or check a condition (stored, then sent to the simulation).

        Raises:
            CommandError: an unknown program or breakpoint, names the behavior lacks, a bad condition.
        """
        if isinstance(command, ListBreakpoints):
            return self.breakpoint_list(self._breakpoint_key(command.program) if command.program else None)
        if isinstance(command, CheckCondition):
            key = self._breakpoint_key(command.program)
            running = self.programs[key].running
            if running is None:
                raise CommandError(f"the behavior {key} has not compiled yet")
            checked = check_condition(running, command.condition)
            return {"ok": checked.ok, "diagnostics": [d.as_dict() for d in checked.diagnostics]}
        robot = command.robot if isinstance(command, SetBreakpoint) else None
        key = self._breakpoint_key(command.program, robot)
        points = self.breakpoints.setdefault(key, {})
        try:
            if isinstance(command, SetBreakpoint):
                ident = command.breakpoint or max(points, default=0) + 1
                point = Breakpoint(
                    ident,
                    command.kind,
                    command.option,
                    command.state,
                    command.leaf,
                    command.condition,
                    command.robot,
                    command.enabled,
                )
                validate(self.programs[key].running, point)
                points[ident] = point
            elif isinstance(command, RemoveBreakpoint):
                if points.pop(command.breakpoint, None) is None:
                    raise CommandError(f"no breakpoint {command.breakpoint} in {key}")
            else:
                point = points.get(command.breakpoint)  # type: ignore[assignment]
                if point is None:
                    raise CommandError(f"no breakpoint {command.breakpoint} in {key}")
                points[command.breakpoint] = replace(point, enabled=command.enabled)
        except BreakpointError as error:
            raise CommandError(str(error)) from None
        self.breakpoint_store.save(self.programs[key].source.agents_file, points.values())
        if self.running:
            ok, _, problem = await self._send(SetBreakpoints(key, tuple(points.values())), None)
            if not ok:
                raise CommandError(problem)
        return self.breakpoint_list(key)

    # -- explain ---------------------------------------------------------------------------------------

    async def explain(self, command: Explain, owner: str | None) -> Any:
        """``explain``: live (``seq`` null) or from the recorded values of tick ``seq``; with the last transition.

        Raises:
            CommandError: unknown robot or option, a tick no longer in the ring, or the option did
                not run in it.
        """
        live: dict[str, Any] | None = None
        if command.seq is None:
            ok, result, error = await self._send(command, owner)
            if not ok:
                raise CommandError(error)
            live = result
            latest = self.ring.latest
            if latest is None:
                return live
            seq = latest.seq
        else:
            seq = command.seq
        # A tick of an earlier generation (before a reload) names options with that generation's ids.
        recorded = self.ring.get(seq) if live is None else None
        gen = recorded.gen if recorded is not None else self.generation
        option_id = live["option"] if live is not None else self._option_id(command.robot, command.option, gen)
        if live is not None:
            # Live: continue the last scan of this robot and option (a full decode only the first time).
            cache_key = (command.robot, option_id)
            found = await asyncio.to_thread(
                _recorded, self.ring, seq, command.robot, option_id, self._scans.get(cache_key)
            )
            if found is not None:
                self._scans[cache_key] = found[3]
        else:
            found = await asyncio.to_thread(_recorded, self.ring, seq, command.robot, option_id)
        if found is None:
            if live is not None:
                return {**live, "last_transition": None}
            raise CommandError(f"tick {seq} is not in the ring buffer (or option {command.option} did not run in it)")
        generation, at, transition, _ = found
        if live is not None:
            if transition is None:
                return {**live, "last_transition": None}
            ticks: tuple[tuple[Any, ...], ...] = (transition,)
        else:
            ticks = (at,) if transition is None else (at, transition)
        name = (
            _option_name(self, command.option, command.robot, gen)
            if isinstance(command.option, int)
            else command.option
        )
        # live: the answer has its why-not already; this asks for the last transition only
        why_not = None if live is not None else command.why_not
        ok, results, error = await self._send(
            ExplainRecorded(command.robot, name, generation, ticks, why_not=why_not), owner
        )
        if not ok:
            raise CommandError(error)
        if live is not None:
            return {**live, "last_transition": _transition(results[0])}
        decision: dict[str, Any] = results[0]
        decision["last_transition"] = _transition(results[1]) if len(results) > 1 else None
        return decision

    def _option_id(self, robot: int, option: int | str, gen: Generation | None = None) -> int:
        if isinstance(option, int):
            return option
        gen = gen or self.generation
        key = self._breakpoint_key(None, robot)
        program = gen.structure["programs"].get(key) if gen is not None else None
        for item in program.get("options", []) if program else []:
            if item.get("name") == option:
                return int(item["id"])
        raise CommandError(f"unknown option {option!r}")

    # -- hot reload ----------------------------------------------------------------------------------

    async def apply(self, key: str, compilation: Compilation) -> str | None:
        """Store a compile of ``key``; when clean, hot-swap it into the simulation's engines.

        Returns:
            None when swapped (or stored for the next start), else why the running behavior was kept.
        """
        state = self.programs[key]
        state.compilation = compilation
        program = compilation.program
        if program is None:
            if state.running is None:
                # the partial shown stays the one of the hello (its ids), until it compiles clean
                return "the behavior has errors; its robots start when it compiles"
            return "the behavior has errors; the running version is kept"
        program_json = program_to_json(program, compilation.source_text)
        if self.running:
            self._incoming[key] = program  # the new generation arrives before the answer
            self._incoming_sources[key] = compilation.sources
            try:
                ok, problem, error = await self._send(Apply(key, program, program_json), None)
            finally:
                self._incoming.pop(key, None)
                self._incoming_sources.pop(key, None)
            if not ok:
                raise CommandError(error)
            if problem is not None:
                state.error = problem
                return str(problem)
        state.error = None
        state.running = program
        state.running_json = program_json
        state.running_sources = compilation.sources
        state.partial = state.partial_json = None
        return None

    # -- status ----------------------------------------------------------------------------------------

    async def status(self) -> dict[str, Any]:
        """The session status (``GET /api/status``): the simulation's counters and the server's."""
        if self.running:
            try:
                ok, answer, _ = await self._send(Status(op="status"), None)
                if ok:
                    self._worker_status = answer
            except CommandError:
                pass
        sim = dict(self._worker_status)
        latest = self.ring.latest
        ring_entries = len(self.ring)
        gen = self.generation
        return {
            "example": self.example.name,
            "paused": self.paused,
            "finished": sim.get("finished", False),
            "speed": self.speed,
            "seed": self.seed,
            "behavior_hz": self.behavior_hz,
            "seq": latest.seq if latest else 0,
            "t": latest.t if latest else 0,
            "generation": gen.number if gen is not None else 0,
            "fork": dataclasses.asdict(self.fork) if self.fork is not None else None,
            "real_time_factor": sim.get("real_time_factor", 0.0) if self.running else 0.0,
            "tick_ms": sim.get("tick_ms", 0.0),
            # raw counters of the simulation process, for windowed measurements (benchmarks/stream_load.py)
            "timing": sim.get("timing", {}),
            "ring": {
                "frames": ring_entries,
                "capacity": self.ring.capacity,
                "seconds": round(ring_entries / self.behavior_hz, 1),
                "bytes": self.ring.nbytes(),
                "record_seconds": self.recorder.record_seconds,
                "recorded": self.recorder.recorded,
            },
            "simulation": {
                "running": self.running,
                "pid": self.pid,
                "restarts": self.restarts,
                "crash": self.crash,
                "pipe": sim.get("pipe", {}),
            },
            "programs": {key: state.as_dict() for key, state in self.programs.items()},
            "world": sim.get("world") or _latest_world(latest),
            "recording": self.live_recorder.stats() if self.live_recorder is not None else None,
        }


def fork_request(ring: frames.Ring, seq: int) -> ForkAt:
    """``fork`` at ``seq`` for the simulation, with what ``ring`` recorded of ticks ``seq - 1`` and ``seq``.

    Raises:
        CommandError: tick ``seq`` is not in the ring.
    """
    if ring.get(seq) is None:
        entries, latest = ring.snapshot()[:1], ring.latest
        held = f"{entries[0].seq}..{latest.seq}" if entries and latest is not None else "none"
        raise CommandError(f"tick {seq} is not in the history (it holds ticks {held})")
    recorded: dict[int, tuple[tuple[Any, ...], Any]] = {}
    for at in (seq - 1, seq):
        entry = ring.get(at)
        if entry is not None:
            frame = orjson.loads(entry.delta)  # every frame holds every path and the scene
            recorded[at] = (tuple(r["path"] for r in frame["robots"]), frame["scene"])
    return ForkAt(seq, recorded)


def _store_partial(state: ProgramState, compilation: Compilation) -> None:
    """Keep what parsed of a broken behavior for the studio to show (nothing when it cannot be described)."""
    partial = compilation.partial
    try:
        state.partial_json = program_to_json(partial, compilation.source_text) if partial is not None else None
    except Exception:  # a half-built program the emitter cannot describe: show no graph, keep serving
        log.exception("the partial program of %s cannot be described", state.source.key)
        state.partial_json = None
    state.partial = partial if state.partial_json is not None else None


def _option_name(session: Session, option: int, robot: int, gen: Generation | None = None) -> str:
    gen = gen or session.generation
    key = session._breakpoint_key(None, robot)
    program = gen.structure["programs"].get(key) if gen is not None else None
    for item in program.get("options", []) if program else []:
        if item.get("id") == option:
            return str(item["name"])
    raise CommandError(f"unknown option id {option}")


#: path node fields (docs/protocol.md "path"): kind, depth, option id, active state, option_time,
#: state_time, decided-in state, leaf, params
_NODE = 9


#: Where a scan of the ring stopped: (seq, decoded frame, generation, last transition tick or None,
#: the option's tick at seq).
Scan = tuple[int, dict[str, Any], int, tuple[Any, ...] | None, tuple[Any, ...]]


def _recorded(
    ring: frames.Ring, seq: int, robot: int, option: int, resume: Scan | None = None
) -> tuple[int, tuple[Any, ...], Any, Scan] | None:
    """For tick ``seq``: generation, the option's decision, the last transition up to it, the scan's end.

    The scan's end continues a later scan (``resume``) from where this one stopped.
    """
    if resume is not None and resume[0] == seq:
        return resume[2], resume[4], resume[3], resume
    at: tuple[Any, ...] | None = None
    transition: tuple[Any, ...] | None = resume[3] if resume is not None else None
    generation = resume[2] if resume is not None else None
    frame: dict[str, Any] | None = None
    last_seq = -1
    resumed = (resume[0], resume[1]) if resume is not None else None
    for entry, robots in frames.recorded_ticks(ring, seq, resumed):
        if generation is not None and entry.gen.number != generation:
            transition = None
        generation = entry.gen.number
        frame, last_seq = frames.decoded_frame(robots), entry.seq
        if robot >= len(robots):
            return None
        state = robots[robot]
        node = next((n for n in state.get("path", []) if n[0] == 0 and n[2] == option and len(n) >= _NODE), None)
        if node is None:
            if entry.seq == seq:
                return None
            continue
        # What the decisions read in that tick, as the simulation sent it (b"": not recorded).
        reads = entry.reads[robot] if robot < len(entry.reads) else b""
        tick = (entry.seq, entry.t, node[6], node[7], node[3], reads)
        if node[6] != node[3]:  # the decision left its state: a transition
            transition = tick
        if entry.seq == seq:
            at = tick
    if at is None or generation is None or frame is None:
        return None
    return generation, at, transition, (last_seq, frame, generation, transition, at)


def _transition(result: dict[str, Any]) -> dict[str, Any]:
    """A ``LastTransition`` from an explanation of the tick it fired in."""
    return {
        "seq": result["seq"],
        "t": result["t"],
        "decided_in": result["decided_in"],
        "decided_in_name": result["decided_in_name"],
        "target": result["target"],
        "target_name": result["target_name"],
        "leaf": result["leaf"],
        "conditions": result["conditions"],
        "tree": result["tree"],
    }


def _latest_world(latest: Entry | None) -> dict[str, Any]:
    import orjson

    if latest is None or not latest.status:
        return {}
    world: dict[str, Any] = orjson.loads(latest.status)
    return world


def _fail(future: asyncio.Future[Any], error: BaseException) -> None:
    if not future.done():
        future.set_exception(error)
