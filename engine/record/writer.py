"""Writing a recording: :class:`Recorder` turns a running world's ticks into an MCAP file.

Feed it after every behavior tick (``run_headless(..., on_tick=recorder.on_tick)`` or, in a loop
of your own, ``loop.tick(); recorder.tick(now_ms)``). Per tick it samples every XABSL agent
(:class:`~engine.record.sampler.AgentSampler`), writes one activation message per agent, one
symbols message per agent (all values on key frames every ``key_every`` ticks, the changed
values in between), a fault message when an agent's fault changes, the world's dynamic scene
and, for planar worlds, a Foxglove scene. Once, at the start: the header (agents, rates, seed,
value tables), each program's behavior description and the static scene.

For the studio (later): :meth:`Recorder.event` writes debugging and session events,
:meth:`Recorder.reload` starts a new program generation (new description, changed files, fresh
samplers, a key frame next), :meth:`Recorder.rebind` follows a world that was rebuilt (reset).

The file is written to ``FILE.part`` and renamed to ``FILE`` by :meth:`Recorder.close`, so a
crashed run never leaves a truncated file under the final name. Message layouts: see
:mod:`engine.record.schema` and docs/recordings.md.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any, BinaryIO

import orjson
from mcap.writer import CompressionType, Writer

from engine.emit.json import program_to_json
from engine.host import Agent, World
from engine.ir.model import Program
from engine.record import foxglove
from engine.record import schema as S
from engine.record.sampler import AgentSampler, ProgramTables
from engine.runtime import Engine, Fault
from engine.types import Ms, Value

__all__ = ["Recorder", "RecorderStats", "engines_of"]

#: Uncompressed bytes per MCAP chunk: small enough that a seek decompresses little (a chunk is
#: about 2 s of a 10-agent match), large enough for zstd to find the repetition between ticks.
CHUNK_SIZE = 512 * 1024
#: Decimal symbol values are kept to this many fractional digits by default: the studio's display
#: precision (mm, degrees and ms to a thousandth), and a third of the bytes of exact values.
DECIMALS = 3


@dataclass(slots=True)
class RecorderStats:
    """What a recorder wrote."""

    path: str
    ticks: int
    messages: int
    bytes: int


def engines_of(world: World) -> list[Engine | None]:
    """Per agent of ``world`` the XABSL engine its controller runs (``controller.engine``), or None."""
    engines: list[Engine | None] = []
    for agent in world.agents:
        engine = getattr(agent.controller, "engine", None)
        engines.append(engine if isinstance(engine, Engine) else None)
    return engines


class _Agent:
    """Per-agent writer state: channels, sampler, what the last messages said."""

    __slots__ = (
        "channel",
        "fault_channel",
        "gen",
        "key",
        "last_assignments",
        "last_fault",
        "last_inputs",
        "last_outputs",
        "last_roots",
        "name",
        "nest_inputs",
        "nest_outputs",
        "sampler",
    )

    def __init__(
        self, name: str, key: str, sampler: AgentSampler, gen: int, channels: tuple[int, int], decimals: int | None
    ) -> None:
        self.name = name
        self.key = key
        self.gen = gen
        self.channel, self.fault_channel = channels
        self.bind(sampler, gen, decimals)
        self.last_fault: Fault | None = None

    def bind(self, sampler: AgentSampler, gen: int, decimals: int | None) -> None:
        self.sampler = sampler
        self.gen = gen
        tables = sampler.tables
        self.nest_inputs = _Nesting(tables.inputs, tables.input_enums, tables.input_decimals, tables.enums, decimals)
        self.nest_outputs = _Nesting(
            tables.outputs, tables.output_enums, tables.output_decimals, tables.enums, decimals
        )
        self.last_inputs: tuple[Value | None, ...] = ()
        self.last_outputs: tuple[Value | None, ...] = ()
        self.last_assignments: tuple[Value | None, ...] | None = None
        self.last_roots: tuple[Any, ...] | None = None


class _Nesting:
    """Symbol values -> the nested JSON object of a symbols message (``ball.x`` -> ``{"ball": {"x": ..}}``).

    Foxglove's message paths address nested fields with dots (``.inputs.ball.x``) and cannot
    quote a key that contains one, hence the nesting. A name that is also a namespace of other
    names (``a`` beside ``a.b``) is stored under the key ``"="`` of that namespace. Enum values
    are written as element names, decimals rounded to ``decimals`` fractional digits (None: exact).
    """

    __slots__ = ("_decimal", "_enum", "_keys", "_paths", "_scale")

    def __init__(
        self,
        names: tuple[str, ...],
        enums: tuple[str | None, ...],
        is_decimal: tuple[bool, ...],
        tables: dict[str, dict[int, str]],
        decimals: int | None,
    ) -> None:
        namespaces = {name.rsplit(".", k)[0] for name in names for k in range(1, name.count(".") + 1)}
        paths: list[tuple[str, ...]] = []
        for name in names:
            parts = tuple(name.split("."))
            paths.append((*parts, "=") if name in namespaces else parts)
        self._paths = tuple(paths)
        self._keys = names
        self._enum = tuple(tables.get(e) if e is not None else None for e in enums)
        self._decimal = is_decimal if decimals is not None else (False,) * len(names)
        self._scale = 10.0 ** (decimals or 0)

    def encode(self, values: tuple[Value | None, ...], previous: tuple[Value | None, ...]) -> dict[str, Any]:
        """The nested object of ``values``: every value if ``previous`` is empty, else the changed ones."""
        out: dict[str, Any] = {}
        paths, enum, decimal, scale = self._paths, self._enum, self._decimal, self._scale
        if len(previous) != len(values):
            changed: Any = range(len(values))
        elif values == previous:
            return out
        else:
            changed = [
                i for i, (a, b) in enumerate(zip(values, previous, strict=True)) if a != b or type(a) is not type(b)
            ]
        for i in changed:
            value = values[i]
            table = enum[i]
            if table is not None and value is not None:
                value = table.get(int(value), int(value))
            elif decimal[i] and value is not None:
                # ``round(v * s) / s``: exact decimal rounding with round(v, n) costs 3-4x more;
                # a try beats contextlib.suppress in this loop. NaN and infinities stay (JSON null).
                try:  # noqa: SIM105
                    value = round(value * scale) / scale
                except (ValueError, OverflowError):
                    pass
            path = paths[i]
            depth = len(path)
            if depth == 2:  # the common case (``ball.x``), without the loop below
                node = out.get(path[0])
                if node is None:
                    node = out[path[0]] = {}
                node[path[1]] = value
                continue
            if depth == 1:
                out[path[0]] = value
                continue
            node = out
            for part in path[:-1]:
                child = node.get(part)
                if child is None:
                    child = node[part] = {}
                node = child
            node[path[-1]] = value
        return out


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
        deterministic: whether the run is a pure function of seed and programs (for fork).
        decimals: decimal symbol values are rounded to this many fractional digits (the studio's
            display precision; None: exact). Activation paths and assignment values are always exact.

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
        deterministic: bool = True,
        chunk_size: int = CHUNK_SIZE,
        decimals: int | None = DECIMALS,
    ) -> None:
        if key_every < 1:
            raise ValueError(f"key_every must be at least 1, got {key_every}")
        self.path = Path(path)
        self.world = world
        self.programs = dict(programs)
        self.behavior_hz = behavior_hz
        self.key_every = key_every
        self.decimals = decimals
        self.seq = 0
        self.generation = 0
        self.messages = 0
        self._closed = False
        self._force_key = True
        self._part = self.path.with_name(self.path.name + ".part")
        self._stream: BinaryIO = open(self._part, "wb")  # noqa: SIM115 -- closed in close()
        self._writer = Writer(self._stream, chunk_size=chunk_size, compression=CompressionType.ZSTD)
        self._writer.start(profile=S.PROFILE, library="xabsl-studio")
        self._schemas = {
            name: self._writer.register_schema(name, "jsonschema", orjson.dumps(s)) for name, s in S.SCHEMAS.items()
        }
        self._schemas[foxglove.SCENE_UPDATE_SCHEMA["title"]] = self._writer.register_schema(
            foxglove.SCENE_UPDATE_SCHEMA["title"], "jsonschema", orjson.dumps(foxglove.SCENE_UPDATE_SCHEMA)
        )
        self._foxglove = foxglove_scene
        self._channels: dict[str, int] = {}
        self._tables: dict[str, ProgramTables] = {}

        engines = list(engines) if engines is not None else engines_of(world)
        self._agents: list[_Agent | None] = []
        keys: list[str | None] = []
        for agent, engine in zip(world.agents, engines, strict=True):
            if engine is None:
                self._agents.append(None)
                keys.append(None)
                continue
            key = self._key_of(engine.program)
            keys.append(key)
            sampler = AgentSampler(engine, self._tables_for(key, engine))
            channels = (
                self._channel(S.agent_topic(agent.name), "xabsl.AgentTick"),
                self._channel(S.fault_topic(agent.name), "xabsl.Fault"),
            )
            self._agents.append(_Agent(agent.name, key, sampler, self.generation, channels, decimals))

        static = world.static_scene()
        self._write(
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
            },
        )
        for key in self._tables:
            self._write_program(key, self.programs[key], "start", ())
        self._write_static(static)

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

    def _channel(self, topic: str, schema_name: str) -> int:
        channel = self._channels.get(topic)
        if channel is None:
            channel = self._channels[topic] = self._writer.register_channel(topic, "json", self._schemas[schema_name])
        return channel

    def _write(self, topic: str, schema_name: str, message: dict[str, Any]) -> None:
        self._add(self._channel(topic, schema_name), orjson.dumps(message))

    def _add(self, channel: int, data: bytes) -> None:
        time_ns = S.tick_time_ns(self.seq, self.behavior_hz)
        self._writer.add_message(channel, time_ns, data, time_ns, self.seq)
        self.messages += 1

    def _write_program(self, key: str, program: Program, reason: str, changed_files: Sequence[str]) -> None:
        self._write(
            S.PROGRAM,
            "xabsl.Program",
            {
                "seq": self.seq,
                "gen": self.generation,
                "key": key,
                "reason": reason,
                "program": program_to_json(program),
                "changed_files": list(changed_files),
            },
        )

    def _write_static(self, static: dict[str, Any]) -> None:
        self._write(S.WORLD_STATIC, "xabsl.StaticScene", {"seq": self.seq, "scene": static})
        self._scene_builder: foxglove.SceneBuilder | None = None
        if self._foxglove and foxglove.supports(static, self.world.dynamic_scene()):
            time_ns = S.tick_time_ns(self.seq, self.behavior_hz)
            self._write(S.FOXGLOVE_FIELD, "foxglove.SceneUpdate", foxglove.static_update(static, time_ns))
            self._scene_builder = foxglove.SceneBuilder(static)

    # -- per tick -----------------------------------------------------------------------------------

    def on_tick(self, now_ms: Ms) -> None:
        """``run_headless``'s ``on_tick`` hook: record the tick just run (never stops the run)."""
        self.tick(now_ms)

    def tick(self, now_ms: Ms) -> None:
        """Record the tick that just ran at engine time ``now_ms``."""
        seq = self.seq
        key = self._force_key or seq % self.key_every == 0
        self._force_key = False
        dumps = orjson.dumps
        add = self._add
        gen = self.generation
        for agent in self._agents:
            if agent is None:
                continue
            sample = agent.sampler.sample()
            message: dict[str, Any] = {"seq": seq, "t": now_ms, "gen": gen, "tick": sample.tick, "path": sample.path}
            if key or sample.roots != agent.last_roots:
                agent.last_roots = sample.roots
                message["roots"] = [[r.kind, r.name] for r in sample.roots]
            if key or sample.assignments != agent.last_assignments:
                agent.last_assignments = sample.assignments
                message["assignments"] = sample.assignments
            message["key"] = key
            message["inputs"] = agent.nest_inputs.encode(sample.inputs, () if key else agent.last_inputs)
            message["outputs"] = agent.nest_outputs.encode(sample.outputs, () if key else agent.last_outputs)
            if sample.unread:
                message["unread"] = list(sample.unread)
            agent.last_inputs, agent.last_outputs = sample.inputs, sample.outputs
            add(agent.channel, dumps(message))
            # On change, and repeated on key frames while faulted, so a seek from a key frame sees it.
            if sample.fault != agent.last_fault or (key and sample.fault is not None):
                agent.last_fault = sample.fault
                add(agent.fault_channel, dumps({"seq": seq, "t": now_ms, "fault": _fault(sample.fault)}))
        world = self.world
        scene = world.dynamic_scene()
        self._write(S.WORLD_SCENE, "xabsl.DynamicScene", {"seq": seq, "t": now_ms, "scene": scene})
        builder = self._scene_builder
        if builder is not None:
            self._write(
                S.FOXGLOVE_SCENE, "foxglove.SceneUpdate", builder.update(scene, S.tick_time_ns(seq, self.behavior_hz))
            )
        if key:
            self._write(S.WORLD_STATUS, "xabsl.WorldStatus", {"seq": seq, "t": now_ms, "status": world.status()})
        self.seq = seq + 1

    # -- events and generations (the studio) --------------------------------------------------------

    def event(self, kind: str, now_ms: Ms, agent: str | None = None, **data: Any) -> None:
        """Write an event of ``kind`` (one of :data:`engine.record.schema.EVENT_KINDS`) before the next tick.

        Raises:
            ValueError: an unknown kind.
        """
        if kind not in S.EVENT_KINDS:
            raise ValueError(f"unknown event kind {kind!r} (known: {', '.join(S.EVENT_KINDS)})")
        self._write(S.EVENTS, "xabsl.Event", {"seq": self.seq, "t": now_ms, "kind": kind, "agent": agent, "data": data})

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
        for agent, engine in zip(self._agents, engines, strict=True):
            if agent is not None and engine is not None and engine.program is program:
                agent.bind(AgentSampler(engine, self._tables_for(key, engine)), self.generation, self.decimals)
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
        self._force_key = True

    def rebind(self, world: World, engines: Sequence[Engine | None], now_ms: Ms, reason: str = "reset") -> None:
        """Follow a world that was rebuilt (a reset): new engines, static scene again, a key frame next.

        The agents must be the same (names and order) as when recording started.

        Raises:
            ValueError: the new world has other agents.
        """
        names = [a.name if a is not None else None for a in self._agents]
        new_names = [a.name if e is not None else None for a, e in zip(world.agents, engines, strict=True)]
        if names != new_names:
            raise ValueError(f"the rebuilt world has other agents: {new_names} instead of {names}")
        self.world = world
        self.generation += 1
        for agent, engine in zip(self._agents, engines, strict=True):
            if agent is not None and engine is not None:
                agent.bind(AgentSampler(engine, self._tables_for(agent.key, engine)), self.generation, self.decimals)
                agent.last_fault = None
        self.event("reset", now_ms, None, reason=reason, gen=self.generation, seed=int(world.seed))
        self._write_static(world.static_scene())
        self._force_key = True

    # -- closing --------------------------------------------------------------------------------

    def close(self) -> RecorderStats:
        """Finish the file (summary, indexes) and move it to its final name."""
        if not self._closed:
            self._closed = True
            self._writer.finish()  # type: ignore[no-untyped-call]
            self._stream.close()
            os.replace(self._part, self.path)
        return RecorderStats(str(self.path), self.seq, self.messages, self.path.stat().st_size)

    def abort(self) -> None:
        """Stop without a file (an error in the run): the partial file is removed."""
        if not self._closed:
            self._closed = True
            self._stream.close()
            self._part.unlink(missing_ok=True)

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
