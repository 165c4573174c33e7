"""Recording a running world: :class:`Recorder` samples the engines each tick and feeds the encoder.

Feed it after every behavior tick (``run_headless(..., on_tick=recorder.on_tick)`` or, in a loop
of your own, ``loop.tick(); recorder.tick(now_ms)``). Per tick it samples every XABSL agent
(:class:`~xabsl_studio.engine.record.sampler.AgentSampler`) and the world's dynamic scene (its status on key
frames), and hands them to a :class:`~xabsl_studio.engine.record.encoder.RecordingEncoder`, which writes the
MCAP file: in the same thread, or with ``background=True`` in a writer process of its own, so
that encoding, indexing and compressing leave the simulation's thread (operations are sent in
batches over a pipe). Once, at the start: the header (agents, rates, seed, value tables), each
program's behavior description and the static scene.

For the studio (later): :meth:`Recorder.event` writes debugging and session events,
:meth:`Recorder.reload` starts a new program generation (new description, changed files, fresh
samplers, a key frame next), :meth:`Recorder.rebind` follows a world that was rebuilt (a reset).
Message layouts: :mod:`xabsl_studio.engine.record.schema` and docs/recordings.md.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from multiprocessing.connection import Connection
from pathlib import Path
from types import TracebackType
from typing import Any

from xabsl_studio.engine.emit.ic import emit_ic
from xabsl_studio.engine.emit.json import program_to_json
from xabsl_studio.engine.errors import RecordError
from xabsl_studio.engine.host import Agent, World
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.record import schema as S
from xabsl_studio.engine.record.encoder import (
    CHUNK_SIZE,
    DECIMALS,
    FOXGLOVE_EVERY,
    NO_CHANGE,
    RecordingEncoder,
    TickSample,
)
from xabsl_studio.engine.record.sampler import AgentSampler, ProgramTables
from xabsl_studio.engine.runtime import Engine, Fault, Root
from xabsl_studio.engine.types import Ms

__all__ = ["Recorder", "RecorderStats", "RecordingFailed", "engines_of"]

#: Operations per pipe message in background mode: one send per batch keeps the per-tick cost
#: of the pipe to one list append.
BATCH = 64


class RecordingFailed(RecordError):
    """The writer (in the background process) failed; the message says why."""


@dataclass(slots=True)
class RecorderStats:
    """What a recorder wrote."""

    path: str
    ticks: int
    messages: int
    bytes: int


def engines_of(world: World) -> list[Engine | None]:
    """Per agent of ``world`` the XABSL engine its controller is or runs (``controller.engine``), or None."""
    engines: list[Engine | None] = []
    for agent in world.agents:
        controller = agent.controller
        engine = controller if isinstance(controller, Engine) else getattr(controller, "engine", None)
        engines.append(engine if isinstance(engine, Engine) else None)
    return engines


class _Background:
    """The encoder in a writer process: operations are batched and sent over a pipe."""

    def __init__(self, **encoder: Any) -> None:
        context = multiprocessing.get_context("spawn")  # no fork of a process that may run threads
        self._conn, child = context.Pipe()
        self._process = context.Process(target=_serve, args=(child, encoder), name="xabsl-recorder", daemon=True)
        self._process.start()
        child.close()
        self._batch: list[tuple[Any, ...]] = []

    def handle(self, op: tuple[Any, ...]) -> None:
        batch = self._batch
        batch.append(op)
        if len(batch) >= BATCH:
            self._send()

    def _send(self) -> None:
        batch, self._batch = self._batch, []
        try:
            self._conn.send(batch)
        except (BrokenPipeError, EOFError, OSError) as error:
            raise RecordingFailed(f"the recording process stopped: {self._reply()}") from error

    def _reply(self) -> str:
        try:
            if self._conn.poll(5.0):
                reply = self._conn.recv()
                return str(reply[1]) if reply[0] == "error" else "no error reported"
        except (EOFError, OSError):
            pass
        return "it exited without a word"

    def close(self) -> tuple[str, int, int, int]:
        self._batch.append(("close",))
        self._send()
        try:
            reply = self._conn.recv()
        except EOFError:
            reply = ("error", "the recording process exited before closing the file")
        self._process.join(10.0)
        self._conn.close()
        if reply[0] == "error":
            raise RecordingFailed(str(reply[1]))
        return reply[1]  # type: ignore[no-any-return]

    def abort(self) -> None:
        try:
            self._batch.append(("abort",))
            self._send()
        except RecordingFailed:
            pass
        self._process.join(10.0)
        if self._process.is_alive():
            self._process.terminate()
        self._conn.close()


def _serve(conn: Connection, options: dict[str, Any]) -> None:
    """The writer process: run operations until ``close`` (reply with the stats) or ``abort``."""
    encoder: RecordingEncoder | None = None
    try:
        encoder = RecordingEncoder(**options)
        while True:
            for op in conn.recv():
                if op[0] == "close":
                    conn.send(("ok", encoder.close()))
                    return
                if op[0] == "abort":
                    encoder.abort()
                    return
                encoder.handle(op)
    except Exception as error:  # report it to the simulation side, which raises RecordingFailed
        if encoder is not None:
            encoder.abort()
        with contextlib.suppress(OSError):
            conn.send(("error", f"{type(error).__name__}: {error}"))
    finally:
        conn.close()


class _Capture:
    """Per-agent capture state: the sampler and what was last sent (roots and fault by identity)."""

    __slots__ = ("fault", "key", "roots", "sampler")

    def __init__(self, key: str, sampler: AgentSampler) -> None:
        self.key = key
        self.sampler = sampler
        self.roots: tuple[Root, ...] | None = None
        self.fault: Fault | int | None = NO_CHANGE


class Recorder:
    """Records a running world into an MCAP file (see the module docstring).

    Args:
        path: the ``.mcap`` file to write (created or replaced when the recorder closes).
        world: the world being run; its agents' controllers expose ``engine`` (XABSL) or not.
        programs: program key -> the program (each engine's key is the key of the program it runs).
        example: the example's name (``soccer``), for the header.
        behavior_hz, physics_hz: the loop's rates.
        engines: per agent the engine to record (default: :func:`engines_of`).
        key_every: a symbols key frame every this many ticks.
        foxglove_scene: also write the Foxglove 2D scene channels (for planar worlds).
        foxglove_every: write ``/foxglove/scene`` every this many ticks (and right after a reset).
        deterministic: whether the run is a pure function of seed and programs (for fork).
        decimals: decimal symbol values are rounded to this many fractional digits (the studio's
            display precision; None: exact). Activation paths and assignment values are always exact.
        chunk_size: uncompressed bytes per MCAP chunk.
        background: encode and write in a writer process (the simulation thread only samples).
        sources: per program key its source files (:func:`xabsl_studio.engine.record.sources.program_sources`),
            so that a fork can re-simulate with the recorded behavior.
        world_options: how the world was built (the world plug-in's options, e.g. ``robots``).
        first_seq: the seq of the first tick (a fork continues its original's numbering).
        forked_from: ``{"file", "seq"}`` of the recording this run was forked from.

    Raises:
        ValueError: an engine runs a program that is not in ``programs``.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        world: World,
        programs: Mapping[str, Program],
        *,
        example: str,
        behavior_hz: int,
        physics_hz: int,
        engines: Sequence[Engine | None] | None = None,
        key_every: int = S.KEY_EVERY,
        foxglove_scene: bool = True,
        foxglove_every: int = FOXGLOVE_EVERY,
        deterministic: bool = True,
        decimals: int | None = DECIMALS,
        chunk_size: int = CHUNK_SIZE,
        background: bool = False,
        sources: Mapping[str, Mapping[str, Any]] | None = None,
        world_options: Mapping[str, Any] | None = None,
        first_seq: int = 0,
        forked_from: Mapping[str, Any] | None = None,
    ) -> None:
        if key_every < 1:
            raise ValueError(f"key_every must be at least 1, got {key_every}")
        if foxglove_every < 1:
            raise ValueError(f"foxglove_every must be at least 1, got {foxglove_every}")
        self.path = Path(path)
        self.world = world
        self.programs = dict(programs)
        self.behavior_hz = behavior_hz
        self.key_every = key_every
        self.seq = first_seq
        self.generation = 0
        self._sources = dict(sources or {})
        self._closed = False
        self._tables: dict[str, ProgramTables] = {}
        engines = list(engines) if engines is not None else engines_of(world)
        captures: list[_Capture | None] = []
        keys: list[str | None] = []
        for engine in engines:
            if engine is None:
                captures.append(None)
                keys.append(None)
                continue
            key = self._key_of(engine.program)
            keys.append(key)
            captures.append(_Capture(key, AgentSampler(engine, self._tables_for(key, engine))))
        self._captures = captures
        options: dict[str, Any] = {
            "path": str(self.path),
            "behavior_hz": behavior_hz,
            "key_every": key_every,
            "decimals": decimals,
            "chunk_size": chunk_size,
            "foxglove_scene": foxglove_scene,
            "foxglove_every": foxglove_every,
        }
        self._sink: RecordingEncoder | _Background = (
            _Background(**options) if background else RecordingEncoder(**options)
        )
        static = world.static_scene()
        self._message(
            S.RECORDING,
            "xabsl.Recording",
            {
                "format": S.FORMAT,
                "version": S.VERSION,
                "example": example,
                "world": str(static.get("kind", "")),
                "seed": int(world.seed),
                "behavior_hz": behavior_hz,
                "physics_hz": physics_hz,
                "key_every": key_every,
                "decimals": decimals,
                "deterministic": deterministic,
                "agents": [
                    {"id": i, "name": a.name, "team": a.team, "number": a.number, "program": keys[i]}
                    for i, a in enumerate(world.agents)
                ],
                "tables": {key: tables.to_json() for key, tables in self._tables.items()},
                **({"world_options": dict(world_options)} if world_options is not None else {}),
                **({"first_seq": first_seq} if first_seq else {}),
                **({"forked_from": dict(forked_from)} if forked_from is not None else {}),
            },
        )
        for key in self._tables:
            self._write_program(key, self.programs[key], "start", ())
        self._bind_all()
        self._sink.handle(("static", self.seq, static, world.dynamic_scene()))

    @classmethod
    def for_world(
        cls,
        path: str | os.PathLike[str],
        world: World,
        program_key: Callable[[Agent], str | None],
        **options: Any,
    ) -> Recorder:
        """A recorder for ``world`` whose agent ``a`` runs the program named ``program_key(a)``.

        The programs are those the agents' engines run (:func:`engines_of`); ``options`` are the
        constructor's keyword arguments (``example``, ``behavior_hz``, ``physics_hz``, ...).

        Raises:
            ValueError: two different programs under one key.
        """
        engines: list[Engine | None] = []
        programs: dict[str, Program] = {}
        for agent, engine in zip(world.agents, engines_of(world), strict=True):
            key = program_key(agent) if engine is not None else None
            if engine is None or key is None:
                engines.append(None)  # no engine, or one the caller does not want recorded
                continue
            engines.append(engine)
            known = programs.setdefault(key, engine.program)
            if known is not engine.program:
                raise ValueError(f"two different programs are both named {key!r}")
        return cls(path, world, programs, engines=engines, **options)

    # -- setup helpers ------------------------------------------------------------------------------

    def _key_of(self, program: Program) -> str:
        for key, candidate in self.programs.items():
            if candidate is program:
                return key
        raise ValueError("an engine runs a program that is not among the recorder's programs")

    def _tables_for(self, key: str, engine: Engine) -> ProgramTables:
        tables = self._tables.get(key)
        if tables is None:
            tables = self._tables[key] = ProgramTables.of(engine)
        return tables

    def _bind_all(self) -> None:
        for index, (agent, capture) in enumerate(zip(self.world.agents, self._captures, strict=True)):
            if capture is not None:
                self._sink.handle(("agent", index, agent.name, capture.sampler.tables, self.generation))
                capture.roots = None
                capture.fault = NO_CHANGE

    def _message(self, topic: str, schema_name: str, message: dict[str, Any]) -> None:
        self._sink.handle(("msg", topic, schema_name, self.seq, message))

    def _write_program(self, key: str, program: Program, reason: str, changed_files: Sequence[str]) -> None:
        self._message(
            S.PROGRAM,
            "xabsl.Program",
            {
                "seq": self.seq,
                "gen": self.generation,
                "key": key,
                "reason": reason,
                "program": program_to_json(program),
                "changed_files": list(changed_files),
                "ic": emit_ic(program),
                **({"sources": self._sources[key]} if reason == "start" and key in self._sources else {}),
            },
        )

    # -- per tick -----------------------------------------------------------------------------------

    def on_tick(self, now_ms: Ms) -> None:
        """``run_headless``'s ``on_tick`` hook: record the tick just run (never stops the run)."""
        self.tick(now_ms)

    def tick(self, now_ms: Ms) -> None:
        """Record the tick that just ran at engine time ``now_ms``."""
        samples: list[TickSample | None] = []
        append = samples.append
        for capture in self._captures:
            if capture is None:
                append(None)
                continue
            s = capture.sampler.sample()
            roots: Any = NO_CHANGE
            if s.roots is not capture.roots:  # the engine keeps its roots tuple until they change
                capture.roots = s.roots
                roots = [[r.kind, r.name] for r in s.roots]
            fault: Any = NO_CHANGE
            if s.fault is not capture.fault:
                capture.fault = s.fault
                fault = _fault(s.fault)
            append((s.tick, s.path, s.assignments, s.inputs, s.outputs, roots, fault, s.unread, s.reads))
        seq = self.seq
        world = self.world
        status = world.status() if seq % self.key_every == 0 else None
        self._sink.handle(("tick", seq, now_ms, samples, world.dynamic_scene(), status))
        self.seq = seq + 1

    # -- events and generations (the studio) --------------------------------------------------------

    def event(self, kind: str, now_ms: Ms, agent: str | None = None, **data: Any) -> None:
        """Write an event of ``kind`` (one of :data:`~xabsl_studio.engine.record.schema.EVENT_KINDS`) before a tick.

        Raises:
            ValueError: an unknown kind.
        """
        if kind not in S.EVENT_KINDS:
            raise ValueError(f"unknown event kind {kind!r} (known: {', '.join(S.EVENT_KINDS)})")
        self._message(
            S.EVENTS, "xabsl.Event", {"seq": self.seq, "t": now_ms, "kind": kind, "agent": agent, "data": data}
        )

    def reload(
        self,
        key: str,
        program: Program,
        engines: Sequence[Engine | None],
        now_ms: Ms,
        changed_files: Sequence[str] = (),
    ) -> None:
        """A hot reload of program ``key``: a new generation from the next tick on.

        ``engines`` are the world's engines after the reload (agent order); the agents that run
        ``program`` get fresh samplers, a ``/xabsl/program`` message carries the new description,
        an event marks the reload and the next tick is a key frame.
        """
        self.generation += 1
        self.programs[key] = program
        self._tables.pop(key, None)
        for capture, engine in zip(self._captures, engines, strict=True):
            if capture is not None and engine is not None and engine.program is program:
                capture.sampler = AgentSampler(engine, self._tables_for(key, engine))
        tables = self._tables.get(key)
        self._write_program(key, program, "reload", changed_files)
        self.event(
            "reload",
            now_ms,
            None,
            key=key,
            gen=self.generation,
            changed_files=list(changed_files),
            tables=tables.to_json() if tables is not None else None,
        )
        self._bind_all()

    def rebind(self, world: World, engines: Sequence[Engine | None], now_ms: Ms, reason: str = "reset") -> None:
        """Follow a world that was rebuilt (a reset): new engines, the static scene again, a key frame next.

        The agents must be the same (names, order, which run engines) as when recording started.

        Raises:
            ValueError: the new world has other agents.
        """
        old = [a.name for a, c in zip(self.world.agents, self._captures, strict=True) if c is not None]
        new = [a.name for a, e in zip(world.agents, engines, strict=True) if e is not None]
        if old != new or len(world.agents) != len(self._captures):
            raise ValueError(f"the rebuilt world has other agents: {new} instead of {old}")
        self.world = world
        self.generation += 1
        for capture, engine in zip(self._captures, engines, strict=True):
            if capture is not None and engine is not None:
                capture.sampler = AgentSampler(engine, self._tables_for(capture.key, engine))
        self.event("reset", now_ms, None, reason=reason, gen=self.generation, seed=int(world.seed))
        self._bind_all()
        self._sink.handle(("static", self.seq, world.static_scene(), world.dynamic_scene()))

    # -- closing --------------------------------------------------------------------------------

    def close(self) -> RecorderStats:
        """Finish the file (summary, indexes) and move it to its final name.

        Raises:
            RecordingFailed: the writer process failed.
        """
        if self._closed:
            return RecorderStats(str(self.path), self.seq, -1, self.path.stat().st_size)
        self._closed = True
        path, ticks, messages, size = self._sink.close()
        return RecorderStats(path, ticks, messages, size)

    def abort(self) -> None:
        """Stop without a file (an error in the run): the partial file is removed."""
        if not self._closed:
            self._closed = True
            self._sink.abort()

    def __enter__(self) -> Recorder:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, traceback: TracebackType | None
    ) -> None:
        if kind is None:
            self.close()
        else:
            self.abort()


def _fault(fault: Fault | None) -> dict[str, Any] | None:
    if fault is None:
        return None
    span = fault.span
    return {
        "message": fault.message,
        "option": fault.option,
        "state": fault.state,
        "error": fault.error,
        "span": [span.file, span.line, span.col] if span is not None else None,
    }
