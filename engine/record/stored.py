"""The columns a recording stores of its ticks: built by its writer, read back by queries.

A query over a recording needs its ticks as columns (:mod:`xabsl_studio.engine.record.columns`).
Reading them from the tick messages means parsing every robot's JSON message of every tick
(about 15 us each, 2-3 s for a 10-minute 10-robot match on two cores), so the writer keeps the
raw values and paths it encodes (:class:`ColumnsWriter`, fed by the encoder: references, nothing
converted per tick), converts them in bulk with numpy at each cut and stores them in the file as
MCAP attachments named :data:`NAME`: one *part* per about a minute of ticks (:data:`PART_TICKS`,
cut on a key frame, so that each part starts on one), each holding every robot's ticks of its
range as :class:`~xabsl_studio.engine.record.columns.RobotEvents`. A cold query then reads a few
MB instead of every message. The input functions' calls come from the ticks' reads: of the
engine's reads only the arrays that can be calls are kept per tick, and the part's are turned
into JSON and back at once at the cut, so they read as the file holds them.

The attachments are a cache of the messages, never a second truth: the conversion is the one the
encoder's JSON and a scan's :class:`~xabsl_studio.engine.record.columns.ColumnsBuilder` make
together (rounding to the file's decimals, enum values as element codes, what JSON holds as
null, NaN, infinities and getters that raised, unknown; the calls by the scan's own
:func:`~xabsl_studio.engine.record.columns.collect_calls`), checked against a scan tick for tick
(tests/record/test_stored_columns.py), and a reader uses them only when they cover every tick of
every robot the statistics count and number enum elements as the file's programs do; otherwise
it scans the messages.

Layout of an attachment (media type :data:`MEDIA_TYPE`, docs/recordings.md "Stored columns"): a
zstd frame of a little-endian ``uint32`` length, that many bytes of a JSON header, then the arrays
the header lists (``[dtype, count, codec, scale]`` each, in the order :func:`_arrays` gives), back
to back. Hand-written because no columnar library of the dependencies (numpy's ``.npz`` is a zip
of pickle-capable files) reads untrusted bytes with the bounds a recording's reader must hold.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass
from itertools import chain, compress
from operator import itemgetter
from typing import Any

import numpy as np
import orjson
import zstandard

from xabsl_studio.engine.record import schema as S
from xabsl_studio.engine.record.columns import (
    Calls,
    CallTable,
    Codes,
    Floats,
    Ints,
    Mask,
    NodeTable,
    ProgramCodes,
    RobotEvents,
    call_table,
    collect_calls,
    raw_number,
    scalar,
    seed_codes,
)
from xabsl_studio.engine.record.mcapread import MAX_ATTACHMENT_BYTES, Malformed
from xabsl_studio.engine.record.reader import ProgramBook
from xabsl_studio.engine.record.sampler import ProgramTables, reads_json

__all__ = ["MEDIA_TYPE", "NAME", "PART_TICKS", "ColumnsWriter", "StoredPart", "decode_part", "encode_part"]

#: The name of every columns attachment of a recording.
NAME = "xabsl.columns"
#: Its media type (the layout in the module docstring).
MEDIA_TYPE = "application/vnd.xabsl.columns+zstd"
#: Version of the layout.
VERSION = 1
#: A part is cut at the first key frame after this many ticks (a minute at 40 Hz): the writer
#: holds one part's messages' columns at a time.
PART_TICKS = 2400
#: The largest uncompressed part read.
MAX_PART_BYTES = 4 * MAX_ATTACHMENT_BYTES
#: The largest JSON header of a part (names of a team's sets are a few hundred KB at most).
MAX_HEADER_BYTES = 64 * 1024 * 1024

_NODE_FIELDS = (
    ("row", "<i8"),
    ("kind", "<i8"),
    ("ident", "<i8"),
    ("state", "<i8"),
    ("decided", "<i8"),
    ("leaf", "<i8"),
    ("option_time", "<f8"),
    ("state_time", "<f8"),
    ("param_start", "<i8"),
    ("param_count", "<i8"),
    ("params", "<f8"),
    ("params_known", "|b1"),
)
_DTYPES = frozenset({"|i1", "<i2", "<i4", "<i8", "<f8", "|b1"})
_CODECS = frozenset({"raw", "delta", "scaled", "scaled-nan"})


@dataclass(frozen=True)
class StoredPart:
    """One attachment read back: ticks ``start`` .. ``stop - 1`` of every robot it holds."""

    start: int
    stop: int
    #: the writer's enum element names in code order when it wrote the part
    codes: list[str]
    robots: dict[str, RobotEvents]


def _since(t: Ints, rows: Ints, times: Floats) -> Floats | None:
    """``t[row] - time`` per node (constant while a node stays active), None unless it reads back exactly."""
    at = t[rows].astype(np.float64) if len(rows) else np.zeros(0)
    since = at - times
    with np.errstate(invalid="ignore"):
        back = at - since
    return since if np.array_equal(back, times, equal_nan=True) else None


def _arrays(robot: RobotEvents, since: tuple[Floats, Floats] | None) -> Iterator[np.ndarray]:
    """Every array of one robot's ticks, in stored order (``since``: the node times as :func:`_since`)."""
    yield robot.seq
    yield robot.t
    yield robot.gen
    nodes = robot.nodes
    for name, _dtype in _NODE_FIELDS:
        if name == "param_start":
            continue  # the running sum of the counts
        if since is not None and name in ("option_time", "state_time"):
            yield since[name == "state_time"]
        else:
            yield getattr(nodes, name)
    for rows, values, known in robot.events.values():
        yield rows
        yield np.where(known, values, np.nan)  # what an unknown value was does not matter
        yield known
    for table in robot.calls.values():
        counts = np.fromiter(map(len, table.args), dtype=np.int64, count=len(table.args))
        flat = list(chain.from_iterable(table.args))
        try:
            values = np.fromiter(flat, dtype=np.float64, count=len(flat))
            known = np.ones(len(flat), dtype=np.bool_)
        except TypeError:  # an argument that is not known (None)
            known = np.fromiter((v is not None for v in flat), dtype=np.bool_, count=len(flat))
            values = np.fromiter((np.nan if v is None else v for v in flat), dtype=np.float64, count=len(flat))
        yield table.row
        yield table.result
        yield table.known
        yield counts
        yield values
        yield known


#: Scales tried for float arrays: whole numbers, then the recordings' decimals (thousandths).
_SCALES = (1.0, 1000.0)
_INT_DTYPES = ("|i1", "<i2", "<i4", "<i8")


def _smallest(values: Ints) -> str:
    """The smallest integer dtype that holds ``values``."""
    low, high = (int(values.min()), int(values.max())) if len(values) else (0, 0)
    for dtype in _INT_DTYPES:
        info = np.iinfo(np.dtype(dtype))
        if info.min <= low and high <= info.max:
            return dtype
    return "<i8"


def _deltas(values: Ints) -> Ints:
    out = values.copy()
    out[1:] -= values[:-1]
    return out


def _pack(array: np.ndarray) -> list[tuple[list[Any], bytes]]:
    """One array as stored: ``[dtype, count, codec, scale]`` and its bytes, and a NaN mask after it when needed.

    Integers are stored as differences to the previous one (``delta``) in the smallest dtype that
    holds them; floats that are whole numbers or thousandths, as such integers (``scaled``),
    others as they are (``raw``); zstd then finds the repetition between ticks.
    """
    n = len(array)
    if array.dtype == np.bool_:
        return [(["|b1", n, "raw", 1.0], array.tobytes())]
    if array.dtype.kind == "i":
        deltas = _deltas(array.astype(np.int64))
        dtype = _smallest(deltas)
        return [([dtype, n, "delta", 1.0], deltas.astype(dtype).tobytes())]
    values = array.astype(np.float64)
    nan = np.isnan(values)
    finite = values[~nan]
    if np.isfinite(finite).all():
        for scale in _SCALES:
            scaled = np.rint(finite * scale)
            if np.abs(scaled).max(initial=0.0) < 2.0**53 and np.array_equal(scaled / scale, finite):
                whole = np.zeros(n, dtype=np.int64)
                whole[~nan] = scaled.astype(np.int64)
                if nan.any():  # unknown: the last known value (a difference of 0), and the mask after it
                    filled = np.maximum.accumulate(np.where(~nan, np.arange(n), 0))
                    whole = whole[filled]
                deltas = _deltas(whole)
                dtype = _smallest(deltas)
                packed = [
                    ([dtype, n, "scaled" if not nan.any() else "scaled-nan", scale], deltas.astype(dtype).tobytes())
                ]
                if nan.any():
                    packed.append((["|b1", n, "raw", 1.0], nan.tobytes()))
                return packed
    return [(["<f8", n, "raw", 1.0], values.astype("<f8").tobytes())]


def encode_part(start: int, stop: int, codes: list[str], robots: list[RobotEvents]) -> bytes:
    """The attachment data of one part (see the module docstring)."""
    described: list[list[Any]] = []
    chunks: list[bytes] = []
    entries: list[dict[str, Any]] = []
    for robot in robots:
        option_since = _since(robot.t, robot.nodes.row, robot.nodes.option_time)
        state_since = _since(robot.t, robot.nodes.row, robot.nodes.state_time)
        since = (option_since, state_since) if option_since is not None and state_since is not None else None
        for array in _arrays(robot, since):
            for description, data in _pack(array):
                described.append(description)
                chunks.append(data)
        entries.append(
            {
                "name": robot.robot,
                "has_reads": robot.has_reads,
                "times": "since" if since is not None else "raw",
                "functions": sorted(robot.functions),
                "events": list(robot.events),
                "calls": list(robot.calls),
            }
        )
    header = orjson.dumps(
        {"version": VERSION, "start": start, "stop": stop, "codes": codes, "robots": entries, "arrays": described}
    )
    body = struct.pack("<I", len(header)) + header + b"".join(chunks)
    return zstandard.ZstdCompressor(level=3).compress(body)


class _Slot:
    """Where one stored array is in a part's bytes, and how it reads (see :func:`_pack`)."""

    __slots__ = ("body", "codec", "count", "dtype", "mask", "offset", "scale")

    def __init__(self, body: bytes, dtype: str, count: int, codec: str, scale: float, offset: int) -> None:
        self.body, self.dtype, self.count, self.codec, self.scale, self.offset = (
            body,
            dtype,
            count,
            codec,
            scale,
            offset,
        )
        #: the NaN mask that follows a "scaled-nan" array
        self.mask: _Slot | None = None

    def decode(self) -> np.ndarray:
        """The array: int64, float64 or bool."""
        stored = np.frombuffer(self.body, dtype=np.dtype(self.dtype), count=self.count, offset=self.offset)
        if self.codec == "raw":
            return stored.astype(np.bool_ if self.dtype == "|b1" else np.float64)
        whole = np.cumsum(stored, dtype=np.int64)
        if self.codec == "delta":
            return whole
        values = whole / self.scale
        if self.mask is not None:
            values[self.mask.decode()] = np.nan
        return values


def _strings(value: Any, what: str) -> list[str]:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise Malformed(f"its {what} are not a list of names")
    return value


def decode_part(
    data: bytes, symbols: frozenset[str] | None = None, functions: frozenset[str] | None = None
) -> StoredPart:
    """One attachment's part, every length and index checked; of the values ``symbols``, of the calls ``functions``.

    None: all. The arrays of the values and calls not asked for are not decoded (a query reads a
    few of hundreds).

    Raises:
        Malformed: the data is not a columns part, or its arrays do not fit together.
    """
    try:
        size = zstandard.get_frame_parameters(data).content_size
        if size == zstandard.CONTENTSIZE_UNKNOWN or size > MAX_PART_BYTES:
            raise Malformed(f"a columns part of {size} bytes uncompressed (at most {MAX_PART_BYTES} are read)")
        body = zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
    except zstandard.ZstdError as error:
        raise Malformed(f"the columns part does not decompress ({error})") from None
    if len(body) < 4:
        raise Malformed("the columns part is empty")
    (length,) = struct.unpack_from("<I", body)
    if length > min(MAX_HEADER_BYTES, len(body) - 4):
        raise Malformed(f"a columns header of {length} bytes in a part of {len(body)}")
    try:
        header = orjson.loads(body[4 : 4 + length])
    except orjson.JSONDecodeError as error:
        raise Malformed(f"the columns header is not JSON ({error})") from None
    if not isinstance(header, dict) or header.get("version") != VERSION:
        raise Malformed("not a columns part of this version")
    start, stop = header.get("start"), header.get("stop")
    if type(start) is not int or type(stop) is not int or not 0 <= start <= stop:
        raise Malformed("its tick range is not two ticks in order")
    codes = _strings(header.get("codes"), "codes")
    described = header.get("arrays")
    if not isinstance(described, list):
        raise Malformed("it does not list its arrays")
    slots: list[_Slot] = []
    position = 4 + length
    for entry in described:
        if (
            not isinstance(entry, list)
            or len(entry) != 4
            or entry[0] not in _DTYPES
            or type(entry[1]) is not int
            or entry[1] < 0
            or entry[2] not in _CODECS
            or type(entry[3]) is not float
            or entry[3] not in _SCALES
        ):
            raise Malformed("an array is not described by a dtype, a count, a codec and a scale")
        if entry[2] != "raw" and entry[0] in ("|b1", "<f8"):
            raise Malformed(f"a {entry[0]} array with codec {entry[2]!r}")
        end = position + np.dtype(entry[0]).itemsize * entry[1]
        if end > len(body):
            raise Malformed("its arrays run past its end")
        slot = _Slot(body, entry[0], entry[1], entry[2], entry[3], position)
        position = end
        if slots and slots[-1].codec == "scaled-nan" and slots[-1].mask is None:
            if entry[0] != "|b1" or entry[1] != slots[-1].count:
                raise Malformed("a NaN mask does not follow its array")
            slots[-1].mask = slot
            continue
        slots.append(slot)
    if slots and slots[-1].codec == "scaled-nan" and slots[-1].mask is None:
        raise Malformed("a NaN mask does not follow its array")
    if position != len(body):
        raise Malformed("bytes follow its last array")
    taken = iter(slots)

    def take(count: int) -> list[_Slot]:
        got = [next(taken, None) for _ in range(count)]
        if any(a is None for a in got):
            raise Malformed("it has fewer arrays than its robots need")
        return got  # type: ignore[return-value]

    robots: dict[str, RobotEvents] = {}
    listed = header.get("robots")
    if not isinstance(listed, list):
        raise Malformed("it does not list its robots")
    for entry in listed:
        if not isinstance(entry, dict) or not isinstance(entry.get("name"), str) or entry["name"] in robots:
            raise Malformed("a robot without a name of its own")
        robot = _robot(entry, take, start, stop, symbols, functions)
        robots[robot.robot] = robot
    if next(taken, None) is not None:
        raise Malformed("it has more arrays than its robots use")
    return StoredPart(start, stop, codes, robots)


def _expect(arrays: tuple[np.ndarray, ...], kind: str, robot: str) -> None:
    """Integers, floats or booleans (``kind``) where the columns hold them."""
    if any(a.dtype.kind != kind for a in arrays):
        raise Malformed(f"robot {robot!r}: an array holds other values than its field's")


def _robot(
    entry: dict[str, Any],
    take: Any,
    start: int,
    stop: int,
    symbols: frozenset[str] | None,
    functions: frozenset[str] | None,
) -> RobotEvents:
    """One robot of a part, checked: what queries index must lie inside what it holds."""
    name = entry["name"]
    events_names = _strings(entry.get("events"), "value names")
    call_names = _strings(entry.get("calls"), "call tables")
    collected = _strings(entry.get("functions"), "functions")
    if not isinstance(entry.get("has_reads"), bool) or len(set(events_names)) != len(events_names):
        raise Malformed(f"robot {name!r} is not described right")
    seq, t, gen = (slot.decode() for slot in take(3))
    n = len(seq)
    if len(t) != n or len(gen) != n:
        raise Malformed(f"robot {name!r}: its tick arrays differ in length")
    if n and (seq[0] < start or seq[-1] >= stop or np.any(np.diff(seq) <= 0) or gen.min() < 0):
        raise Malformed(f"robot {name!r}: its ticks are not in the part's range, in order")
    if entry.get("times") not in ("since", "raw"):
        raise Malformed(f"robot {name!r}: its node times are of no known kind")
    _expect((seq, t, gen), "i", name)
    stored_fields = [f for f, _ in _NODE_FIELDS if f != "param_start"]
    fields = dict(zip(stored_fields, (slot.decode() for slot in take(len(stored_fields))), strict=True))
    for field_name, dtype in _NODE_FIELDS:
        if field_name != "param_start":
            _expect((fields[field_name],), np.dtype(dtype).kind, name)
    row, count = fields["row"], fields["param_count"]
    m = len(row)
    if any(len(fields[f]) != m for f in stored_fields[:9]) or len(fields["params"]) != len(fields["params_known"]):
        raise Malformed(f"robot {name!r}: its path node arrays differ in length")
    if m and (
        row.min() < 0
        or row.max() >= n
        or np.any(np.diff(row) < 0)
        or not np.isin(fields["kind"], (0, 1)).all()
        or count.min() < 0
        or int(count.sum()) != len(fields["params"])
    ):
        raise Malformed(f"robot {name!r}: a path node points outside its ticks or parameters")
    if entry["times"] == "since":  # stored as t[row] - time
        at = t[row].astype(np.float64)
        with np.errstate(invalid="ignore"):
            fields["option_time"] = at - fields["option_time"]
            fields["state_time"] = at - fields["state_time"]
    fields["param_start"] = np.concatenate(([0], np.cumsum(count)[:-1])).astype(np.int64) if m else count
    nodes = NodeTable(**fields)
    events: dict[str, tuple[Any, Any, Any]] = {}
    for value_name in events_names:
        slots = take(3)
        if symbols is not None and value_name not in symbols:
            continue
        rows, values, known = (slot.decode() for slot in slots)
        if not len(rows) or len(values) != len(rows) or len(known) != len(rows):
            raise Malformed(f"robot {name!r}: the changes of {value_name!r} differ in length")
        if rows[0] < 0 or rows[-1] >= n or np.any(np.diff(rows) <= 0):
            raise Malformed(f"robot {name!r}: a change of {value_name!r} is outside its ticks")
        _expect((rows,), "i", name)
        _expect((values,), "f", name)
        _expect((known,), "b", name)
        events[value_name] = (rows, values, known)
    calls: dict[str, CallTable] = {}
    for function in call_names:
        slots = take(6)
        if functions is not None and function not in functions:
            continue
        row, result, known, counts, flat, flat_known = (slot.decode() for slot in slots)
        k = len(row)
        if len(result) != k or len(known) != k or len(counts) != k or len(flat) != len(flat_known):
            raise Malformed(f"robot {name!r}: the calls of {function!r} differ in length")
        if k and (row.min() < 0 or row.max() >= n or counts.min() < 0 or int(counts.sum()) != len(flat)):
            raise Malformed(f"robot {name!r}: a call of {function!r} is outside its ticks or arguments")
        _expect((row, counts), "i", name)
        _expect((result, flat), "f", name)
        _expect((known, flat_known), "b", name)
        values = [None if not ok else v for v, ok in zip(flat.tolist(), flat_known.tolist(), strict=True)]
        ends = np.cumsum(counts).tolist()
        starts = [0, *ends[:-1]]
        args = [tuple(values[a:b]) for a, b in zip(starts, ends, strict=True)]
        calls[function] = CallTable(row, args, result, known)
    return RobotEvents(
        name,
        seq,
        t,
        gen,
        events,
        nodes,
        calls,
        frozenset(collected),
        entry["has_reads"],
    )


class _Binding:
    """How one agent's raw values of a program generation read (from the encoder's tables)."""

    __slots__ = ("decimal", "enums", "names", "scale")

    def __init__(self, tables: ProgramTables, decimals: int | None) -> None:
        self.names = (*tables.inputs, *tables.outputs)
        flags = (*tables.input_decimals, *tables.output_decimals)
        self.decimal = flags if decimals is not None else (False,) * len(flags)
        self.enums = tuple(
            tables.enums.get(e) if e is not None else None for e in (*tables.input_enums, *tables.output_enums)
        )
        self.scale = 10.0 ** (decimals or 0)


class _AgentColumns:
    """One agent's ticks of the open part, as the encoder had them (raw, converted at the cut)."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.seq: list[int] = []
        self.t: list[int] = []
        self.gen: list[int] = []
        self.paths: list[list[Any]] = []
        self.inputs: list[tuple[Any, ...]] = []
        self.outputs: list[tuple[Any, ...]] = []
        #: (first row, binding) of each run of ticks under one binding
        self.bindings: list[tuple[int, _Binding]] = []
        #: (row, names) of the ticks where getters raised
        self.unread: list[tuple[int, tuple[str, ...]]] = []
        #: per tick what may hold input function calls: the arrays of ``Engine.reads()`` that are
        #: three or more long, the reads as JSON (from a pipe), or None (not recorded)
        self.reads: list[list[Any] | bytes | None] = []


class ColumnsWriter:
    """Builds the columns of a recording while it is written (see the module docstring).

    The encoder hands it what it writes: the header, program and event messages
    (:meth:`observe`), each agent's binding (:meth:`agent`: its name, value tables and precision)
    and per agent and tick the raw path and values it encodes (:meth:`tick`: references, nothing
    converted). At a key frame tick :meth:`cut` turns the open part into columns with numpy, the
    conversions of the encoder's JSON and of the reader's columns in bulk (rounding, enum
    elements as codes, NaN and infinities unknown as JSON null reads back), and returns the part
    when it is due; :meth:`close` returns the last one.
    """

    def __init__(self, part_ticks: int | None = None) -> None:
        self.part_ticks = PART_TICKS if part_ticks is None else part_ticks
        self.codes = Codes()
        self._book: ProgramBook | None = None
        self._agents: dict[int, _AgentColumns] = {}
        self._bindings: dict[int, tuple[str, _Binding]] = {}
        self._programs: dict[tuple[str, int], ProgramCodes] = {}
        self._unseeded: list[tuple[str, int]] = []
        self._start: int | None = None
        self._last = -1
        #: False once something made the columns unfit to store (they are then not written)
        self.ok = True

    def observe(self, topic: str, message: dict[str, Any]) -> None:
        """A message on the header, program or events topic (others are ignored)."""
        if topic == S.RECORDING:
            self._book = ProgramBook(message)
        elif self._book is None:
            self.ok = self.ok and topic not in (S.PROGRAM, S.EVENTS)
        elif topic == S.PROGRAM:
            view = self._book.add_program(message)
            self._unseeded.append((view.key, view.gen))
        elif topic == S.EVENTS:
            self._book.add_event(message)

    def agent(self, index: int, name: str, tables: ProgramTables, decimals: int | None) -> None:
        """Agent ``index`` of the encoder's samples is ``name`` and reads with ``tables`` from its next tick."""
        self._bindings[index] = (name, _Binding(tables, decimals))
        agent = self._agents.get(index)
        if agent is not None:
            agent.bindings.append((len(agent.seq), self._bindings[index][1]))

    def tick(
        self,
        index: int,
        seq: int,
        t: int,
        gen: int,
        path: list[Any],
        inputs: tuple[Any, ...],
        outputs: tuple[Any, ...],
        unread: tuple[str, ...],
        reads: tuple[object, ...] | bytes | None,
    ) -> None:
        """Agent ``index``'s tick as the encoder writes it (raw values in the binding's order).

        ``unread``: the symbols whose getters raised (unknown, whatever their value says);
        ``reads``: what the tick's decisions read (``Engine.reads()`` or that as JSON; None: not
        recorded).
        """
        agent = self._agents.get(index)
        if agent is None:
            bound = self._bindings.get(index)
            if bound is None:
                self.ok = False
                return
            agent = self._agents[index] = _AgentColumns(bound[0])
            agent.bindings.append((0, bound[1]))
        if self._start is None:
            self._start = seq
        self._last = seq
        agent.seq.append(seq)
        agent.t.append(t)
        agent.gen.append(gen)
        agent.paths.append(path)
        agent.inputs.append(inputs)
        agent.outputs.append(outputs)
        if unread:
            agent.unread.append((len(agent.seq) - 1, unread))
        if reads is None or isinstance(reads, bytes):
            agent.reads.append(reads)
        else:  # a call: an input id, one value per parameter and the result (three or more)
            agent.reads.append([e for e in reads if type(e) is tuple and len(e) > 2 and type(e[0]) is int])

    def due(self, seq: int) -> bool:
        """Whether the part open at key frame tick ``seq`` is long enough to be cut there."""
        return self._start is not None and seq - self._start >= self.part_ticks

    def cut(self, seq: int) -> bytes | None:
        """The open part, ending before tick ``seq`` (None: nothing to store); a new part opens."""
        start = self._start
        agents, self._agents = self._agents, {}
        self._start = None
        if not self.ok or start is None:
            return None
        try:
            if self._unseeded:
                # what the reader numbers first: every program's elements, in file order
                book = self._book
                assert book is not None
                seed_codes([book.views[key] for key in self._unseeded], self.codes)
                self._unseeded = []
            robots = [self._events(agent) for agent in agents.values() if agent.seq]
        except Exception:  # ticks this writer cannot follow: the recording goes on without its columns
            self.ok = False
            return None
        return encode_part(start, seq, list(self.codes.by_name), robots)

    def close(self) -> bytes | None:
        """The last part (None: nothing to store)."""
        return self.cut(self._last + 1)

    # -- converting a part ------------------------------------------------------------------------

    def _program(self, robot: str, gen: int) -> ProgramCodes:
        view = self._book.program(robot, gen) if self._book is not None else None
        if view is None:
            raise LookupError(f"no program of generation {gen} for {robot!r}")
        found = self._programs.get((view.key, view.gen))
        if found is None:
            found = self._programs[(view.key, view.gen)] = ProgramCodes(view, None, self.codes)
        return found

    def _events(self, agent: _AgentColumns) -> RobotEvents:
        n = len(agent.seq)
        events: dict[str, tuple[list[Any], list[Any], list[Any]]] = {}
        unread: dict[str, list[int]] = {}
        for row, names in agent.unread:
            for name in names:
                unread.setdefault(name, []).append(row)
        ends = [first for first, _ in agent.bindings[1:]] + [n]
        for (first, binding), end in zip(agent.bindings, ends, strict=True):
            if first >= end:
                continue
            present = set(binding.names)
            for name, found in events.items():  # not in this generation's symbols: unknown from here
                if name not in present:
                    found[0].append(np.array([first]))
                    found[1].append(np.array([np.nan]))
                    found[2].append(np.array([False]))
            # one tuple per symbol (inputs, then outputs, as the binding names them)
            columns = [
                *zip(*agent.inputs[first:end], strict=True),
                *zip(*agent.outputs[first:end], strict=True),
            ]
            for i, name in enumerate(binding.names):
                values, known = self._column(columns[i], binding, i)
                raised = unread.get(name)
                if raised is not None:
                    at = np.asarray(raised, dtype=np.int64) - first
                    known[at[(at >= 0) & (at < end - first)]] = False
                rows, values, known = _changes(values, known)
                found = events.setdefault(name, ([], [], []))
                found[0].append(rows + first)
                found[1].append(values)
                found[2].append(known)
        joined = {
            name: (np.concatenate(r).astype(np.int64), np.concatenate(v), np.concatenate(k))
            for name, (r, v, k) in events.items()
        }
        gen = np.asarray(agent.gen, dtype=np.int64)
        nodes = self._nodes(agent.name, agent.paths, gen)  # first: it reads the programs of every generation
        calls, functions = self._calls(agent, gen)
        return RobotEvents(
            agent.name,
            np.asarray(agent.seq, dtype=np.int64),
            np.asarray(agent.t, dtype=np.int64),
            gen,
            joined,
            nodes,
            calls,
            functions,
            all(r is not None for r in agent.reads),
        )

    def _calls(self, agent: _AgentColumns, gen: Ints) -> tuple[dict[str, CallTable], frozenset[str]]:
        """The input functions' calls of the part's ticks, and the names of every input function.

        The calls read as the scan reads them from the file: the engine's candidate arrays of the
        part go through JSON at once (in C, as the encoder writes them), then each function's
        calls are converted together; a call whose values are not all numbers, or a boolean for an
        enum, takes the scan's own rule (:func:`~xabsl_studio.engine.record.columns.collect_calls`).
        """
        programs = {g: self._program(agent.name, g) for g in np.unique(gen).tolist()}
        functions = frozenset(name for p in programs.values() for name, _e, _r in p.functions.values())
        if not functions:
            return {}, functions
        rows: list[int] = []
        entries: list[Any] = []  # in row order: JSON arrays (from a pipe) or the engine's tuples
        for row, reads in enumerate(agent.reads):
            if reads is None:
                continue
            found = reads if not isinstance(reads, bytes) else [e for e in orjson.loads(reads) if type(e) is list]
            entries.extend(found)
            rows.extend([row] * len(found))
        tuples = [e for e in entries if type(e) is tuple]
        if tuples:  # exactly what the file holds: NaN, infinities and other types null
            converted = iter(orjson.loads(reads_json(tuple(tuples))))
            entries = [next(converted) if type(e) is tuple else e for e in entries]
        row_of = np.asarray(rows, dtype=np.int64)
        ids = np.fromiter((e[0] if type(e[0]) is int else -1 for e in entries), dtype=np.int64, count=len(entries))
        lengths = np.fromiter(map(len, entries), dtype=np.int64, count=len(entries))
        entry_gen = gen[row_of] if len(row_of) else row_of
        found_calls: dict[str, list[tuple[Ints, CallTable]]] = {}
        for g, program in programs.items():
            for ident, (name, param_enums, result_enum) in program.functions.items():
                at = np.flatnonzero((ids == ident) & (entry_gen == g) & (lengths == len(param_enums) + 2))
                if len(at):
                    table = self._function_calls(
                        [entries[i] for i in at.tolist()], row_of[at], program, param_enums, result_enum
                    )
                    found_calls.setdefault(name, []).append((at, table))
        calls: dict[str, CallTable] = {}
        for name, pieces in found_calls.items():
            order = np.argsort(np.concatenate([at for at, _ in pieces]), kind="stable")
            args = [a for _, t in pieces for a in t.args]
            calls[name] = CallTable(
                np.concatenate([t.row for _, t in pieces])[order],
                [args[i] for i in order.tolist()],
                np.concatenate([t.result for _, t in pieces])[order],
                np.concatenate([t.known for _, t in pieces])[order],
            )
        return calls, functions

    def _function_calls(
        self,
        entries: list[list[Any]],
        rows: Ints,
        program: ProgramCodes,
        param_enums: list[str | None],
        result_enum: str | None,
    ) -> CallTable:
        """One function's calls (``[id, argument..., result]`` as JSON reads them) as the scan converts them."""
        width = len(param_enums) + 2
        flat = list(chain.from_iterable(entries))
        enums = [*param_enums, result_enum]
        try:
            if any(e is not None for e in enums) and any(type(v) is bool for v in flat):
                raise TypeError("a boolean for an enum")  # no element: the exact rule below
            matrix = np.fromiter(flat, dtype=np.float64, count=len(flat)).reshape(len(entries), width)[:, 1:]
        except (TypeError, ValueError):  # the scan's rule, call by call
            calls: Calls = {}
            for row, entry in zip(rows.tolist(), entries, strict=True):
                collect_calls(row, program, [entry], self.codes, calls)
            (found,) = calls.values()
            return call_table(*found)
        known = np.ones(matrix.shape, dtype=np.bool_)
        for column, enum in enumerate(enums):
            if enum is None:
                continue
            values = matrix[:, column]
            whole = values == np.floor(values)
            codes = np.full(len(values), np.nan)
            for number, code in program.read_enums.get(enum, {}).items():
                codes[whole & (values == number)] = code
            matrix[:, column] = codes
            known[:, column] = ~np.isnan(codes)
        arguments = matrix[:, :-1]
        if known[:, :-1].all():
            args = list(map(tuple, arguments.tolist()))
        else:
            args = [
                tuple(v if k else None for v, k in zip(values, flags, strict=True))
                for values, flags in zip(arguments.tolist(), known[:, :-1].tolist(), strict=True)
            ]
        result = matrix[:, -1]
        return CallTable(rows.astype(np.int64), args, np.where(known[:, -1], result, np.nan), known[:, -1].copy())

    def _column(self, raw: tuple[Any, ...], binding: _Binding, i: int) -> tuple[Floats, Mask]:
        """One symbol's values as the reader's columns hold them after the file's JSON."""
        n = len(raw)
        try:
            values = np.fromiter(raw, dtype=np.float64, count=n)
            known = np.ones(n, dtype=np.bool_)
        except TypeError:  # a getter that raised (None)
            known = np.fromiter((v is not None for v in raw), dtype=np.bool_, count=n)
            values = np.fromiter((np.nan if v is None else v for v in raw), dtype=np.float64, count=n)
        table = binding.enums[i]
        if table is not None:  # the encoder writes the element of int(value); others are unknown
            codes = self.codes
            ok = known & np.isfinite(values)
            host = np.where(ok, values, 0).astype(np.int64)
            mapped = np.full(n, np.nan)
            for number in np.unique(host[ok]).tolist():
                element = table.get(number)
                if element is not None:
                    mapped[ok & (host == number)] = codes.code(element)
            values = mapped
        elif binding.decimal[i]:
            with np.errstate(invalid="ignore", over="ignore"):
                values = np.rint(values * binding.scale) / binding.scale
        return values, known & np.isfinite(values)

    def _nodes(self, robot: str, paths: list[list[Any]], gen: Ints) -> NodeTable:
        """The path nodes of a part, as the reader's columns hold them (see ``ColumnsBuilder``)."""
        lengths = np.fromiter(map(len, paths), dtype=np.int64, count=len(paths))
        nodes = list(chain.from_iterable(paths))
        m = len(nodes)
        rows = np.repeat(np.arange(len(paths), dtype=np.int64), lengths)
        kind = np.fromiter(map(itemgetter(0), nodes), dtype=np.int64, count=m)
        ident = np.fromiter(map(itemgetter(2), nodes), dtype=np.int64, count=m)
        option = kind == 0
        options = list(compress(nodes, option.tolist()))
        behaviors = list(compress(nodes, (~option).tolist()))

        def field(source: list[Any], index: int, dtype: Any) -> Any:
            return np.fromiter(map(itemgetter(index), source), dtype=dtype, count=len(source))

        state = np.full(m, -1, dtype=np.int64)
        decided = np.full(m, -1, dtype=np.int64)
        leaf = np.full(m, -1, dtype=np.int64)
        option_time = np.empty(m, dtype=np.float64)
        state_time = np.full(m, np.nan)
        state[option] = field(options, 3, np.int64)
        decided[option] = field(options, 6, np.int64)
        leaf[option] = field(options, 7, np.int64)
        option_time[option] = field(options, 4, np.float64)
        state_time[option] = field(options, 5, np.float64)
        option_time[~option] = field(behaviors, 3, np.float64)
        raw_params = list(map(itemgetter(-1), nodes))  # the last field of both kinds of node
        count = np.fromiter(map(len, raw_params), dtype=np.int64, count=m)
        flat = list(chain.from_iterable(raw_params))
        start = np.concatenate(([0], np.cumsum(count)[:-1])).astype(np.int64) if m else count
        owner = np.repeat(np.arange(m, dtype=np.int64), count)
        position = np.arange(len(flat), dtype=np.int64) - start[owner]
        declared = np.zeros(m, dtype=np.int64)
        enum_owner = np.zeros(m, dtype=np.bool_)
        node_gen = gen[rows] if m else rows
        programs: dict[int, ProgramCodes] = {}
        for g in np.unique(node_gen).tolist():
            program = programs[g] = self._program(robot, g)
            in_gen = node_gen == g
            for kind_id, enums_of in ((0, program.option_param_enums), (1, program.behavior_param_enums)):
                mask = in_gen & (kind == kind_id)
                declared[mask] = np.asarray([len(e) for e in enums_of], dtype=np.int64)[ident[mask]]
                enum_owner[mask] = np.asarray([any(x is not None for x in e) for e in enums_of])[ident[mask]]
        try:
            params = np.fromiter(flat, dtype=np.float64, count=len(flat))
            known = np.ones(len(flat), dtype=np.bool_)
        except (TypeError, ValueError):  # a value of another type: the reader's own rule per value
            exact = [scalar(v, self.codes) if not isinstance(v, str) else None for v in flat]
            known = np.fromiter((v is not None for v in exact), dtype=np.bool_, count=len(flat))
            params = np.fromiter((np.nan if v is None else v for v in exact), dtype=np.float64, count=len(flat))
        known &= position < declared[owner]
        for j in np.flatnonzero(enum_owner[owner] & known).tolist():  # enum parameters: few, exact
            node = int(owner[j])
            program = programs[int(node_gen[node])]
            enums_of = program.option_param_enums if kind[node] == 0 else program.behavior_param_enums
            code = raw_number(flat[j], enums_of[ident[node]][position[j]], program.host_enums, self.codes)
            params[j] = np.nan if code is None else code
            known[j] = code is not None
        known &= np.isfinite(params)
        return NodeTable(rows, kind, ident, state, decided, leaf, option_time, state_time, start, count, params, known)


def _changes(values: Floats, known: Mask) -> tuple[Ints, Floats, Mask]:
    """The ticks where a column changes (value or known), with the value and known from there on."""
    n = len(values)
    if not n:
        return np.zeros(0, dtype=np.int64), values, known
    change = np.ones(n, dtype=np.bool_)
    change[1:] = (known[1:] != known[:-1]) | (known[1:] & (values[1:] != values[:-1]))
    rows = np.flatnonzero(change)
    return rows, values[rows], known[rows]
