"""The writing half of a recording: encoder operations -> MCAP messages, with no engine or world.

:class:`RecordingEncoder` owns the MCAP file. It is fed *operations*, plain picklable tuples
that the capture side (:class:`xabsl_studio.engine.record.writer.Recorder`, in the simulation's thread) builds
from the engines and the world, so it can run in the same thread or in a writer process of its
own (``Recorder(..., background=True)``), and later in the studio's server process, which
already receives the simulation's samples:

* ``("msg", topic, schema, seq, message)``: write one JSON message at the time of tick ``seq``;
* ``("agent", index, name, tables, gen)``: agent ``index`` runs a program with ``tables``
  (:class:`~xabsl_studio.engine.record.sampler.ProgramTables`) from generation ``gen`` on (its channels are
  registered on first use; the next tick is a key frame for it);
* ``("static", seq, static_scene, dynamic_scene)``: the static scene (and, for planar worlds, the
  Foxglove field; the dynamic scene shows whether the world is planar);
* ``("tick", seq, t, samples, scene, status)``: one tick; ``samples[i]`` is agent ``i``'s
  :data:`TickSample` (None: no engine), ``status`` the world status or None;
* ``("key",)``: the next tick is a key frame for every agent.

Per agent and tick the encoder writes one ``xabsl.AgentTick`` (the path; roots and assignment
values on key frames and when they changed; all symbol values on key frames every ``key_every``
ticks, the changed ones in between; what the tick's decisions read, exact, every tick), and an
``xabsl.Fault`` when the fault changes (repeated on key frames while faulted, so a seek from a
key frame sees it). Unless told not to (``columns=False``), it also keeps the ticks' raw values
for the columns a query reads, stored as attachments about once a minute
(:mod:`xabsl_studio.engine.record.stored`).
"""

from __future__ import annotations

import contextlib
import os
from itertools import compress
from operator import ne
from pathlib import Path
from typing import Any, BinaryIO

import orjson

from xabsl_studio.engine.record import foxglove, stored
from xabsl_studio.engine.record import schema as S
from xabsl_studio.engine.record.mcapfile import McapWriter
from xabsl_studio.engine.record.recover import lock_part
from xabsl_studio.engine.record.sampler import ProgramTables, reads_json
from xabsl_studio.engine.record.stored import ColumnsWriter
from xabsl_studio.engine.types import Value

__all__ = ["CHUNK_SIZE", "DECIMALS", "FOXGLOVE_EVERY", "NO_CHANGE", "Nesting", "RecordingEncoder", "TickSample"]

#: Uncompressed bytes per MCAP chunk: small enough that a seek decompresses little (a chunk is
#: about 2 s of a 10-agent match), large enough for zstd to find the repetition between ticks.
CHUNK_SIZE = 512 * 1024
#: Decimal symbol values are kept to this many fractional digits by default: the studio's display
#: precision (mm, degrees and ms to a thousandth), and a third of the bytes of exact values.
DECIMALS = 3
#: The Foxglove scene (``/foxglove/scene``) is written every this many ticks (and on the first tick
#: after a static scene, i.e. after a reset):
#: 10 Hz at 40 Hz is smooth enough for a 2D view of the field, and the message (7.5 KB for 5 vs 5)
#: was half the data and a third of the encoding of a recording when written every tick. The
#: world's own scene (``/world/scene``) stays on every tick.
FOXGLOVE_EVERY = 4
#: In a :data:`TickSample`, "the roots / the fault did not change since the last tick".
NO_CHANGE = 0

#: One agent's tick as the capture side sends it: ``(engine tick, path, assignments, inputs,
#: outputs, roots as [[kind, name], ...] or NO_CHANGE, fault dict or None or NO_CHANGE, unread,
#: reads)``; ``reads`` is what the decisions read (``Engine.reads()``, or that list as JSON bytes),
#: None when the engine did not record them.
TickSample = tuple[
    int,
    list[list[Any]],
    tuple[Value | None, ...],
    tuple[Value | None, ...],
    tuple[Value | None, ...],
    Any,
    Any,
    tuple[str, ...],
    tuple[object, ...] | bytes | None,
]


class _Agent:
    """Per-agent encoder state: channels, value encoders, what the last messages said."""

    __slots__ = (
        "assignments",
        "channel",
        "fault",
        "fault_channel",
        "gen",
        "inputs",
        "key",
        "nest_inputs",
        "nest_outputs",
        "outputs",
        "roots",
    )

    def __init__(self, channel: int, fault_channel: int) -> None:
        self.channel = channel
        self.fault_channel = fault_channel
        self.fault: dict[str, Any] | None = None
        self.roots: list[list[str]] = []

    def bind(self, tables: ProgramTables, gen: int, decimals: int | None) -> None:
        self.gen = gen
        self.nest_inputs = Nesting(tables.inputs, tables.input_enums, tables.input_decimals, tables.enums, decimals)
        self.nest_outputs = Nesting(tables.outputs, tables.output_enums, tables.output_decimals, tables.enums, decimals)
        self.inputs: tuple[Value | None, ...] = ()
        self.outputs: tuple[Value | None, ...] = ()
        self.assignments: tuple[Value | None, ...] | None = None
        self.key = True


class Nesting:
    """Symbol values -> the nested JSON object of a symbols message (``ball.x`` -> ``{"ball": {"x": ..}}``).

    Foxglove's message paths address nested fields with dots (``.inputs.ball.x``) and cannot
    quote a key that contains one, hence the nesting. A name that is also a namespace of other
    names (``a`` beside ``a.b``) is stored under the key ``"="`` of that namespace. Enum values
    are written as element names, decimals rounded to ``decimals`` fractional digits (None: exact).
    """

    __slots__ = ("_keys", "_positions", "_scale", "_slots")

    def __init__(
        self,
        names: tuple[str, ...],
        enums: tuple[str | None, ...],
        is_decimal: tuple[bool, ...],
        tables: dict[str, dict[int, str]],
        decimals: int | None,
    ) -> None:
        namespaces = {name.rsplit(".", k)[0] for name in names for k in range(1, name.count(".") + 1)}
        decimal = is_decimal if decimals is not None else (False,) * len(names)
        slots: list[tuple[dict[int, str] | None, bool, str, str | None, tuple[str, ...]]] = []
        for name, enum, is_dec in zip(names, enums, decimal, strict=True):
            parts = tuple(name.split("."))
            path = (*parts, "=") if name in namespaces else parts
            # (enum table, decimal?, first key, second key if the path has exactly two, the path)
            slots.append(
                (
                    tables.get(enum) if enum is not None else None,
                    is_dec,
                    path[0],
                    path[1] if len(path) == 2 else None,
                    path,
                )
            )
        #: per symbol position, everything encode needs, so that its loop indexes one tuple
        self._slots = tuple(slots)
        self._positions = range(len(names))
        self._keys = names
        self._scale = 10.0 ** (decimals or 0)

    def encode(self, values: tuple[Value | None, ...], previous: tuple[Value | None, ...]) -> dict[str, Any]:
        """The nested object of ``values``: every value if ``previous`` is empty, else the changed ones."""
        out: dict[str, Any] = {}
        slots, scale = self._slots, self._scale
        if len(previous) != len(values):
            changed: Any = range(len(values))
        elif values == previous:
            return out
        else:
            # In C: positions where the value differs (``==`` equal values, 0 and 0.0, count as unchanged).
            changed = compress(self._positions, map(ne, values, previous))
        get = out.get
        for i in changed:
            value = values[i]
            table, is_decimal, head, leaf, path = slots[i]
            if value is None:
                pass
            elif is_decimal:
                # ``round(v * s) / s``: exact decimal rounding with round(v, n) costs 3-4x more;
                # a try beats contextlib.suppress in this loop. NaN and infinities stay (JSON null).
                try:  # noqa: SIM105
                    value = round(value * scale) / scale
                except (ValueError, OverflowError):
                    pass
            elif table is not None:
                try:
                    number = int(value)
                    value = table.get(number, number)
                except (ValueError, OverflowError):  # NaN or an infinity: no element (JSON null)
                    value = None
            if leaf is not None:  # the common case (``ball.x``), without the loop below
                node = get(head)
                if node is None:
                    node = out[head] = {}
                node[leaf] = value
                continue
            if len(path) == 1:
                out[head] = value
                continue
            node = out
            for part in path[:-1]:
                child = node.get(part)
                if child is None:
                    child = node[part] = {}
                node = child
            node[path[-1]] = value
        return out


class RecordingEncoder:
    """Writes a recording from encoder operations (see the module docstring).

    The file is written to ``FILE.part`` and renamed to ``FILE`` by :meth:`close`, so a crashed
    run never leaves a truncated file under the final name; ``xabsl_studio.engine.record.recover``
    makes a cut ``FILE.part`` a readable ``FILE`` again.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        behavior_hz: int,
        key_every: int = S.KEY_EVERY,
        decimals: int | None = DECIMALS,
        chunk_size: int = CHUNK_SIZE,
        foxglove_scene: bool = True,
        foxglove_every: int = FOXGLOVE_EVERY,
        columns: bool = True,
    ) -> None:
        self.path = Path(path)
        #: builds the stored columns for queries (``xabsl_studio.engine.record.stored``), None: not stored
        self._columns = ColumnsWriter() if columns else None
        self.behavior_hz = behavior_hz
        self.key_every = key_every
        self.decimals = decimals
        self.messages = 0
        self.ticks = 0
        self._foxglove = foxglove_scene
        if foxglove_every < 1:
            raise ValueError(f"foxglove_every must be at least 1, got {foxglove_every}")
        self._foxglove_every = foxglove_every
        self._scene_due = True
        self._closed = False
        self._key = True
        self._part = self.path.with_name(self.path.name + ".part")
        self._stream: BinaryIO = open(self._part, "wb")  # noqa: SIM115 -- closed in close()
        # Held while writing, dropped by the kernel if this process dies: a studio recovers only
        # the ``.part`` files nobody writes (``xabsl_studio.engine.record.recover``).
        lock_part(self._stream, wait=True)
        self._writer = McapWriter(self._stream, chunk_size=chunk_size)
        self._writer.start(profile=S.PROFILE, library="xabsl-studio")
        schemas = {**S.SCHEMAS, foxglove.SCENE_UPDATE_SCHEMA["title"]: foxglove.SCENE_UPDATE_SCHEMA}
        self._schemas = {
            name: self._writer.register_schema(name, "jsonschema", orjson.dumps(s)) for name, s in schemas.items()
        }
        self._channels: dict[str, int] = {}
        self._agents: dict[int, _Agent] = {}
        self._scene_builder: foxglove.SceneBuilder | None = None

    def handle(self, op: tuple[Any, ...]) -> None:
        """Carry out one operation."""
        kind = op[0]
        if kind == "tick":
            self._tick(*op[1:])
        elif kind == "msg":
            _, topic, schema, seq, message = op
            if self._columns is not None:
                self._columns.observe(topic, message)
            self._add(self._channel(topic, schema), seq, orjson.dumps(message))
        elif kind == "agent":
            _, index, name, tables, gen = op
            agent = self._agents.get(index)
            if agent is None:
                agent = self._agents[index] = _Agent(
                    self._channel(S.agent_topic(name), "xabsl.AgentTick"),
                    self._channel(S.fault_topic(name), "xabsl.Fault"),
                )
            agent.bind(tables, gen, self.decimals)
            if self._columns is not None:
                self._columns.agent(index, name, tables, self.decimals)
        elif kind == "static":
            _, seq, static, dynamic = op
            self._add(
                self._channel(S.WORLD_STATIC, "xabsl.StaticScene"), seq, orjson.dumps({"seq": seq, "scene": static})
            )
            self._scene_builder = None
            if self._foxglove and foxglove.supports(static, dynamic):
                update = foxglove.static_update(static, S.tick_time_ns(seq, self.behavior_hz))
                self._add(self._channel(S.FOXGLOVE_FIELD, "foxglove.SceneUpdate"), seq, orjson.dumps(update))
                self._scene_builder = foxglove.SceneBuilder(static)
                self._scene_due = True  # a new world (a reset) shows at once, not up to 3 ticks later
        elif kind == "key":
            self._key = True
        else:
            raise ValueError(f"unknown encoder operation {kind!r}")

    def _channel(self, topic: str, schema_name: str) -> int:
        channel = self._channels.get(topic)
        if channel is None:
            channel = self._channels[topic] = self._writer.register_channel(topic, "json", self._schemas[schema_name])
        return channel

    def _add(self, channel: int, seq: int, data: bytes) -> None:
        time_ns = S.tick_time_ns(seq, self.behavior_hz)
        self._writer.add_message(channel, time_ns, data, time_ns, seq)
        self.messages += 1

    def _tick(
        self,
        seq: int,
        now_ms: int,
        samples: list[TickSample | None],
        scene: dict[str, Any],
        status: dict[str, Any] | None,
    ) -> None:
        every = self._key or seq % self.key_every == 0
        self._key = False
        columns = self._columns
        if every and columns is not None and columns.due(seq):
            self._store_columns(columns.cut(seq), seq)
        dumps = orjson.dumps
        write = self._writer.add_message  # every message of the tick has the tick's time
        time_ns = S.tick_time_ns(seq, self.behavior_hz)
        written = 0
        agents = self._agents
        for index, sample in enumerate(samples):
            if sample is None:
                continue
            agent = agents[index]
            tick, path, assignments, inputs, outputs, roots, fault, unread, reads = sample
            key = every or agent.key
            agent.key = False
            message: dict[str, Any] = {"seq": seq, "t": now_ms, "gen": agent.gen, "tick": tick, "path": path}
            if roots is not NO_CHANGE:
                agent.roots = roots
            if key or roots is not NO_CHANGE:
                message["roots"] = agent.roots
            if key or assignments != agent.assignments:
                agent.assignments = assignments
                message["assignments"] = assignments
            message["key"] = key
            message["inputs"] = agent.nest_inputs.encode(inputs, () if key else agent.inputs)
            message["outputs"] = agent.nest_outputs.encode(outputs, () if key else agent.outputs)
            if unread:
                message["unread"] = list(unread)
            if reads is not None:
                # Exact values every tick (a why at any tick reads one message); JSON bytes as they came.
                message["reads"] = orjson.Fragment(reads if isinstance(reads, bytes) else reads_json(reads))
            if columns is not None:
                columns.tick(index, seq, now_ms, agent.gen, path, inputs, outputs, unread, reads)
            agent.inputs, agent.outputs = inputs, outputs
            write(agent.channel, time_ns, dumps(message), time_ns, seq)
            written += 1
            changed = fault is not NO_CHANGE and fault != agent.fault
            if changed:
                agent.fault = fault
            if changed or (key and agent.fault is not None):
                write(
                    agent.fault_channel, time_ns, dumps({"seq": seq, "t": now_ms, "fault": agent.fault}), time_ns, seq
                )
                written += 1
        self._add(
            self._channel(S.WORLD_SCENE, "xabsl.DynamicScene"), seq, dumps({"seq": seq, "t": now_ms, "scene": scene})
        )
        builder = self._scene_builder
        if builder is not None and (self._scene_due or seq % self._foxglove_every == 0):
            self._scene_due = False
            update = builder.update(scene, time_ns)
            self._add(self._channel(S.FOXGLOVE_SCENE, "foxglove.SceneUpdate"), seq, dumps(update))
        if status is not None:
            self._add(
                self._channel(S.WORLD_STATUS, "xabsl.WorldStatus"),
                seq,
                dumps({"seq": seq, "t": now_ms, "status": status}),
            )
        self.messages += written
        self.ticks = max(self.ticks, seq + 1)

    def _store_columns(self, part: bytes | None, seq: int) -> None:
        if part is not None:
            time_ns = S.tick_time_ns(seq, self.behavior_hz)
            self._writer.attach(stored.NAME, stored.MEDIA_TYPE, part, time_ns, time_ns)

    def close(self) -> tuple[str, int, int, int]:
        """Finish the file (summary, indexes), move it to its final name; ``(path, ticks, messages, bytes)``."""
        if not self._closed:
            self._closed = True
            if self._columns is not None:
                self._store_columns(self._columns.close(), self.ticks)
            self._writer.finish()
            self._stream.close()
            os.replace(self._part, self.path)
        return str(self.path), self.ticks, self.messages, self.path.stat().st_size

    def abandon(self) -> Path:
        """Stop writing and keep the partial file (``FILE.mcap.part``, for ``recover``); its path.

        For a writer that failed (a full disk): what was written stays, to be recovered.
        """
        if not self._closed:
            self._closed = True
            with contextlib.suppress(OSError):  # the disk that failed the write may fail the flush too
                self._stream.close()
        return self._part

    def abort(self) -> None:
        """Stop without a file: the partial file is removed."""
        if not self._closed:
            self._closed = True
            self._stream.close()
            self._part.unlink(missing_ok=True)
