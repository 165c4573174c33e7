"""Frames: what one tick looked like, kept in a ring buffer and sent to clients as deltas.

The simulation process samples each tick into display values
(:mod:`xabsl_studio.server.simulation.sampling`); here, in the server process:

1. **Recording a sample**: :class:`FrameRecorder` compares the values with the previous sample and
   stores, per robot, a bit mask of the symbols that changed, encodes the tick's delta (and,
   every :data:`KEY_EVERY` ticks, a full frame), then appends an :class:`Entry` to the :class:`Ring`.
2. **Storage**: the ring keeps the last ``seconds`` of ticks. Old entries keep only their encoded
   tick delta (bytes), once per :data:`KEY_EVERY` ticks a full frame, and per robot what its
   decisions read (the sample's JSON bytes, for "why" at that tick); values as Python objects
   are kept only for the most recent :data:`LIVE_ENTRIES` entries, so memory is bounded by about
   ``seconds x behavior_hz x bytes per tick`` (see :meth:`Ring.nbytes`).
3. **Encoding for a client** (asyncio loop, :class:`FrameEncoder`): a client that last received
   frame L gets frame K with the values of the symbols whose bit is set in any mask of
   (L, K] -- so a client that skips frames still ends with exact values. Clients with the same L,
   K and robot filter share one encoding (a cache per K), which is what makes twenty clients
   cheap: with the same rate they receive the same ticks.

Ids are those of the program JSON (``xabsl_studio.engine.emit.json``); see docs/protocol.md for the layout.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from itertools import islice
from typing import Any

import orjson

from xabsl_studio.engine.types import Value
from xabsl_studio.server.protocol.display import SampleDisplay
from xabsl_studio.server.protocol.host import NewGeneration, Sample
from xabsl_studio.server.protocol.limits import FULL_EVERY
from xabsl_studio.server.protocol.packing import compress_structure, pack_structure
from xabsl_studio.server.protocol.types import (
    HelloReason,
    WireValue,
)

#: A key frame (full values stored) every this many ticks, so history can start anywhere cheaply.
KEY_EVERY = 40
#: Entries at the end of the ring that keep their values as objects (for live encoding).
LIVE_ENTRIES = 64

_OPT = orjson.OPT_NON_STR_KEYS


@dataclass(slots=True)
class Generation:
    """The ids in force between two reloads or resets: structure, static scene, symbol id tables."""

    number: int
    reason: HelloReason
    structure: dict[str, Any]
    structure_bytes: bytes
    scene_bytes: bytes
    #: per robot: symbol ids of its program (inputs, outputs), aligned with the sampled tuples
    input_ids: tuple[tuple[int, ...], ...]
    output_ids: tuple[tuple[int, ...], ...]
    #: per robot (robot id order): whether it runs an XABSL engine
    engines: tuple[bool, ...] = ()
    #: ms the session's timeline adds to this generation's behavior times: a reset restarts the
    #: world's clock, the timeline goes on (set by :class:`FrameRecorder` at its first tick)
    offset: int = 0
    #: per behavior key: the source texts (display name -> text) its running program came from,
    #: texts unchanged since the previous generation shared with it (``xabsl_studio.server.session.live``)
    sources: dict[str, dict[str, str]] = field(default_factory=dict)
    #: per behavior key: the files whose text differs from the previous generation's
    changed: dict[str, list[str]] = field(default_factory=dict)
    #: per behavior key: enum name -> host value -> element (the raw enum values of an entry's ``reads``)
    enums: dict[str, dict[str, dict[int, str]]] = field(default_factory=dict)
    #: turns this generation's samples into display values when they come raw (None: they do not)
    display: SampleDisplay | None = field(default=None, repr=False)
    #: the structure as browsers get it (spans packed), made on first use
    _wire: tuple[dict[str, Any], bytes, bytes | None] | None = field(default=None, repr=False)

    def wire_structure(self) -> tuple[dict[str, Any], bytes, bytes | None]:
        """The structure as a browser gets it, encoded, and compressed for a hello (None: sent as it is).

        Made once per generation, when the first client needs it (``xabsl_studio.server.protocol.packing``).
        """
        if self._wire is None:
            packed = pack_structure(self.structure)
            encoded = orjson.dumps(packed)
            self._wire = (packed, encoded, compress_structure(encoded))
        return self._wire

    def shown(self, sample: Sample) -> Sample:
        """``sample`` of this generation with display values (as it came when it came with them).

        Every sample of the generation passes here once, in order: the conversion keeps each
        robot's last values and converts only what changed.
        """
        return self.display.convert(sample) if self.display is not None else sample

    @classmethod
    def from_message(cls, message: NewGeneration) -> Generation:
        """The generation announced by the simulation process."""
        structure = orjson.loads(message.structure)
        return cls(
            number=message.number,
            reason=message.reason,
            structure=structure,
            structure_bytes=message.structure,
            scene_bytes=message.scene,
            input_ids=message.input_ids,
            output_ids=message.output_ids,
            engines=tuple(r["program"] is not None for r in structure["robots"]),
            enums=message.enums,
            display=(
                SampleDisplay(structure, message.enums, message.input_ids, message.output_ids)
                if message.raw_values
                else None
            ),
        )


@dataclass(slots=True, eq=False)
class Entry:
    """One recorded tick (see the module docstring for what is kept how long)."""

    seq: int
    gen: Generation
    t: int
    wall: float
    in_masks: tuple[int, ...]
    out_masks: tuple[int, ...]
    status_changed: bool
    key: bool
    delta: bytes
    full: bytes | None = None
    # live part, dropped once the entry is LIVE_ENTRIES old:
    paths: tuple[bytes, ...] | None = None
    extras: tuple[bytes, ...] | None = None
    inputs: tuple[tuple[WireValue, ...], ...] | None = None
    outputs: tuple[tuple[WireValue, ...], ...] | None = None
    scene: bytes = b"{}"
    status: bytes = b"{}"
    nbytes: int = field(default=0)
    #: per robot: what its decisions read in the tick (JSON bytes, kept as long as the entry: why at any tick)
    reads: tuple[bytes, ...] = ()


def _head(entry: Entry, full: bool) -> bytes:
    return b'{"type":"frame","seq":%d,"gen":%d,"t":%d,"wall":%.1f,"full":%s,"robots":[' % (
        entry.seq,
        entry.gen.number,
        entry.t,
        entry.wall,
        b"true" if full else b"false",
    )


def _values(ids: tuple[int, ...], values: tuple[Value | None, ...], mask: int | None) -> bytes:
    if mask is None:
        return orjson.dumps(dict(zip(ids, values, strict=True)), option=_OPT)
    picked = {}
    i = 0
    while mask:
        if mask & 1:
            picked[ids[i]] = values[i]
        mask >>= 1
        i += 1
    return orjson.dumps(picked, option=_OPT)


def encode(
    entry: Entry,
    in_masks: Sequence[int] | None,
    out_masks: Sequence[int] | None,
    robots: frozenset[int] | None,
    with_status: bool,
) -> bytes:
    """The frame message of ``entry`` (a live entry): values by masks (None: full), for ``robots``."""
    assert entry.paths is not None and entry.inputs is not None and entry.outputs is not None and entry.extras, (
        "only live entries can be encoded"
    )
    gen = entry.gen
    full = in_masks is None
    parts = [_head(entry, full)]
    for i, path in enumerate(entry.paths):
        if i:
            parts.append(b",")
        if not gen.engines[i]:
            parts.append(b'{"id":%d,"path":[]}' % i)
            continue
        parts.append(b'{"id":%d,"path":%s' % (i, path))
        if robots is None or i in robots:
            parts.append(b',"outputs":')
            parts.append(_values(gen.output_ids[i], entry.outputs[i], None if out_masks is None else out_masks[i]))
            parts.append(b',"inputs":')
            parts.append(_values(gen.input_ids[i], entry.inputs[i], None if in_masks is None else in_masks[i]))
        parts.append(entry.extras[i])
        parts.append(b"}")
    parts.append(b'],"scene":')
    parts.append(entry.scene)
    if with_status or full:
        parts.append(b',"status":')
        parts.append(entry.status)
    parts.append(b"}")
    return b"".join(parts)


class Ring:
    """The last ``seconds`` of entries (ticks), appended as samples arrive from the simulation.

    Seqs may have gaps (samples the simulation dropped when the server fell behind): lookups
    check the seq they found, so a gap reads as a missing entry, never as a wrong one.
    """

    def __init__(self, seconds: float, behavior_hz: int) -> None:
        self.seconds = seconds
        self.capacity = max(1, round(seconds * behavior_hz))
        self.period_ms = 1000 / behavior_hz
        self._entries: deque[Entry] = deque(maxlen=self.capacity)
        self._bytes = 0

    def append(self, entry: Entry) -> None:
        """Append the newest entry; entries older than LIVE_ENTRIES drop their live part."""
        entries = self._entries
        if len(entries) == entries.maxlen:
            self._bytes -= entries[0].nbytes
        entries.append(entry)
        self._bytes += entry.nbytes
        if len(entries) > LIVE_ENTRIES:
            old = entries[-LIVE_ENTRIES - 1]
            if old.paths is not None:
                old.paths = old.extras = old.inputs = old.outputs = None
                old.scene = old.status = b""

    def __len__(self) -> int:
        return len(self._entries)

    @property
    def latest(self) -> Entry | None:
        """The newest entry (None before the first sample)."""
        try:
            return self._entries[-1]
        except IndexError:
            return None

    def get(self, seq: int) -> Entry | None:
        """The entry with ``seq``, or None when it left the ring (or was never recorded)."""
        for _ in range(4):
            entries = self._entries
            try:
                last = entries[-1].seq
            except IndexError:
                return None
            back = last - seq
            if back < 0:
                return None
            if back >= len(entries):
                break  # older than a gap-free ring reaches: maybe there, behind a gap
            try:
                entry = entries[-back - 1]
            except IndexError:
                continue
            if entry.seq == seq:
                return entry
            break
        # Gaps (samples the pipe dropped) shift the entries behind them: a binary search by seq,
        # in place (no copy: client encoders ask for ticks near a gap on the frame path).
        entries = self._entries
        low, high = 0, len(entries)
        try:
            while low < high:
                middle = (low + high) // 2
                if entries[middle].seq < seq:
                    low = middle + 1
                else:
                    high = middle
            entry = entries[low]
        except IndexError:  # past the end, or an append dropped the oldest meanwhile
            return None
        return entry if entry.seq == seq else None

    def newest(self, count: int) -> list[Entry]:
        """The newest ``count`` entries (fewer in a shorter ring), oldest first, without copying the ring."""
        return list(islice(reversed(self._entries), count))[::-1]

    def snapshot(self) -> list[Entry]:
        """A copy of the entries, oldest first (a C-level copy, safe against a racing append)."""
        return list(self._entries)

    def nbytes(self) -> int:
        """Bytes of the encoded frames the ring holds (the dominant part of its memory)."""
        return self._bytes


class FrameRecorder:
    """Turns the simulation's samples into :class:`Entry` objects and appends them to the ring.

    ``record(gen, sample)`` takes a :class:`~xabsl_studio.server.protocol.host.Sample` of generation ``gen``.
    """

    def __init__(self, ring: Ring) -> None:
        self.ring = ring
        self._prev_inputs: tuple[tuple[Value | None, ...], ...] = ()
        self._prev_outputs: tuple[tuple[Value | None, ...], ...] = ()
        self._prev_status = b""
        self._prev_gen: Generation | None = None
        self._last_key = -KEY_EVERY
        self.record_seconds = 0.0
        self.recorded = 0

    def record(self, gen: Generation, sample: Sample) -> Entry:
        """Record one sample as the ring's newest entry (masks, delta, key frame); returns it."""
        started = time.perf_counter()
        seq, t, wall, paths, extras = sample.seq, sample.t, sample.wall, sample.paths, sample.extras
        inputs, outputs, scene, status = sample.inputs, sample.outputs, sample.scene, sample.status
        n = len(paths)
        new_gen = gen is not self._prev_gen
        prev_inputs, prev_outputs = self._prev_inputs, self._prev_outputs
        if new_gen or len(prev_inputs) != n:
            prev_inputs = prev_outputs = ((),) * n
        in_masks = tuple(map(_changed, inputs, prev_inputs))
        out_masks = tuple(map(_changed, outputs, prev_outputs))
        self._prev_inputs, self._prev_outputs = inputs, outputs
        # Clocks (keys ending in _ms) change every tick and are in `t` and the scene already.
        steady = orjson.dumps({k: v for k, v in orjson.loads(status).items() if not k.endswith("_ms")})
        status_changed = steady != self._prev_status
        self._prev_status = steady
        # A key frame every KEY_EVERY seqs (and when a dropped sample skipped the due one).
        key = new_gen or seq % KEY_EVERY == 0 or seq - self._last_key >= KEY_EVERY
        if key:
            self._last_key = seq
        entry = Entry(
            seq=seq,
            gen=gen,
            t=t,
            wall=wall,
            in_masks=in_masks,
            out_masks=out_masks,
            status_changed=status_changed,
            key=key,
            delta=b"",
            paths=paths,
            extras=extras,
            inputs=inputs,
            outputs=outputs,
            scene=scene,
            status=status,
            reads=sample.reads,
        )
        if new_gen:
            _place(gen, self.ring.latest, t, self.ring.period_ms)
        self._prev_gen = gen
        if new_gen:
            entry.delta = encode(entry, None, None, None, True)
            entry.full = entry.delta
        else:
            entry.delta = encode(entry, entry.in_masks, entry.out_masks, None, status_changed)
            if key:
                entry.full = encode(entry, None, None, None, True)
        entry.nbytes = (
            len(entry.delta)
            + (len(entry.full) if entry.full is not None and not new_gen else 0)
            + sum(map(len, sample.reads))
            + 200
        )
        self.ring.append(entry)
        self.recorded += 1
        self.record_seconds += time.perf_counter() - started
        return entry


def _place(gen: Generation, previous: Entry | None, t: int, period_ms: float) -> None:
    """Set ``gen``'s timeline offset from the tick before its first tick (at ``t``).

    A clock that went back (a reset, a restart) continues one tick after that tick on the
    timeline; one that goes on (a reload) keeps the previous offset.
    """
    if previous is None or previous.gen is gen:
        return
    if t < previous.t:
        gen.offset = previous.t + previous.gen.offset + round(period_ms) - t
    else:
        gen.offset = previous.gen.offset


def _changed(new: tuple[Value | None, ...], old: tuple[Value | None, ...]) -> int:
    if new == old:
        return 0
    if len(new) != len(old):
        return (1 << len(new)) - 1
    mask = 0
    bit = 1
    for a, b in zip(new, old, strict=True):
        if a != b:
            mask |= bit
        bit <<= 1
    return mask


class FrameEncoder:
    """Frames for clients, each a delta against the last frame *that client* received (asyncio side).

    ``frame(last_seq, last_gen, entry, robots)`` returns the bytes to send; results are
    cached for the current entry, so clients in the same position share one encoding.
    """

    def __init__(self, ring: Ring) -> None:
        self.ring = ring
        self._cache_seq = -1
        self._cache: dict[tuple[int | None, frozenset[int] | None], bytes] = {}
        self.encoded = 0
        self.cache_hits = 0

    def frame(self, last_seq: int | None, last_gen: int | None, entry: Entry, robots: frozenset[int] | None) -> bytes:
        """The bytes of ``entry`` for a client that last received ``last_seq`` of ``last_gen``."""
        if entry.seq != self._cache_seq:
            self._cache_seq = entry.seq
            self._cache = {}
        in_masks, out_masks, status = self._masks(last_seq, last_gen, entry)
        cache_key = (None if in_masks is None else last_seq, robots)
        cached = self._cache.get(cache_key)
        if cached is not None:
            self.cache_hits += 1
            return cached
        if in_masks is not None and robots is None and last_seq == entry.seq - 1:
            data = entry.delta  # exactly the tick's own delta, already encoded by the recorder
        elif in_masks is None and robots is None and entry.full is not None:
            data = entry.full
        else:
            data = encode(entry, in_masks, out_masks, robots, status)
        self.encoded += 1
        self._cache[cache_key] = data
        return data

    def _masks(
        self, last_seq: int | None, last_gen: int | None, entry: Entry
    ) -> tuple[list[int] | None, list[int] | None, bool]:
        if last_seq is None or last_gen != entry.gen.number or last_seq >= entry.seq:
            return None, None, True
        if last_seq // FULL_EVERY != entry.seq // FULL_EVERY:
            return None, None, True
        n = len(entry.in_masks)
        in_masks = [0] * n
        out_masks = [0] * n
        status = False
        for seq in range(last_seq + 1, entry.seq + 1):
            e = entry if seq == entry.seq else self.ring.get(seq)
            if e is None or e.gen is not entry.gen or len(e.in_masks) != n:
                return None, None, True
            for i in range(n):
                in_masks[i] |= e.in_masks[i]
                out_masks[i] |= e.out_masks[i]
            status = status or e.status_changed
        return in_masks, out_masks, status


def history(ring: Ring, t0: int, t1: int, every: int = 1) -> Iterator[bytes]:
    """Encoded frames of the current generation with ``t0 <= t <= t1``: full first, then deltas.

    Each later frame is a delta against the previous one yielded (``every`` > 1 merges the deltas
    of the skipped ticks into the next yielded frame).
    """
    entries = ring.snapshot()
    if not entries:
        return
    gen = entries[-1].gen
    yield from _run_frames([e for e in entries if e.gen is gen], t0, t1, every)


def runs(ring: Ring, x0: int, x1: int) -> list[list[Entry]]:
    """The ring's entries per generation (oldest first) that hold a tick with ``x0 <= x <= x1``.

    ``x`` is the session's timeline time, ``t + gen.offset``: it goes on across resets.
    """
    out: list[list[Entry]] = []
    for entry in ring.snapshot():
        if not out or out[-1][-1].gen is not entry.gen:
            out.append([])
        out[-1].append(entry)
    return [run for run in out if any(x0 <= e.t + e.gen.offset <= x1 for e in run)]


def span_history(ring: Ring, x0: int, x1: int, every: int = 1) -> tuple[list[Generation], int, Iterator[bytes]]:
    """The ``history`` of every generation in the ring with timeline times ``x0 <= x <= x1``.

    Returns the generations (oldest first), about how many frames follow and the frames: per
    generation a full frame, then deltas (as :func:`history`); each frame names its generation.
    """
    found = runs(ring, x0, x1)
    count = 0
    for run in found:
        n = sum(1 for e in run if x0 <= e.t + e.gen.offset <= x1)
        count += 1 + (n - 1) // every if n else 0

    def frames() -> Iterator[bytes]:
        for run in found:
            offset = run[0].gen.offset
            yield from _run_frames(run, x0 - offset, x1 - offset, every)

    return [run[0].gen for run in found], count, frames()


def _run_frames(entries: list[Entry], t0: int, t1: int, every: int) -> Iterator[bytes]:
    """The frames of ``entries`` (one generation, oldest first) with ``t0 <= t <= t1``."""
    start = next((k for k, e in enumerate(entries) if e.t >= t0), None)
    if start is None:
        return
    # A full frame at `start`: the last key frame at or before it, with the deltas up to it merged.
    # At the old end of the ring that key frame may be gone: then start at the first key frame.
    key = start
    while key >= 0 and entries[key].full is None:
        key -= 1
    if key < 0:
        first_key = next((k for k in range(start, len(entries)) if entries[k].full is not None), None)
        if first_key is None:
            return
        key = start = first_key
    if entries[start].t > t1:
        return
    state = orjson.loads(entries[key].full)  # type: ignore[arg-type]
    for e in entries[key + 1 : start + 1]:
        _merge(state, orjson.loads(e.delta))
    state["full"] = True
    yield orjson.dumps(state)
    pending: dict[str, Any] | None = None
    for count, e in enumerate(entries[start + 1 :], 1):
        if e.t > t1:
            break
        delta = orjson.loads(e.delta)
        if pending is None:
            pending = delta
        else:
            _merge(pending, delta)
        if count % every == 0:
            yield orjson.dumps(pending)
            pending = None


def _merge(into: dict[str, Any], delta: dict[str, Any]) -> None:
    """Apply a decoded delta frame to a decoded frame (values merged, everything else replaced)."""
    robots = {r["id"]: r for r in into["robots"]}
    merged = []
    for a in delta["robots"]:
        old = robots.get(a["id"], {})
        for name in ("inputs", "outputs"):
            if name in a:
                values = dict(old.get(name, {}))
                values.update(a[name])
                a[name] = values
        merged.append(a)
    status = into.get("status")
    into.update(delta)
    into["robots"] = merged
    if "status" not in delta and status is not None:
        into["status"] = status


def recorded_ticks(
    ring: Ring, seq: int, resume: tuple[int, dict[str, Any]] | None = None
) -> Iterator[tuple[Entry, list[dict[str, Any]]]]:
    """The ticks of ``seq``'s generation up to ``seq``, decoded: ``(entry, robots)`` oldest first.

    ``robots`` are the frame's robot objects with every value merged in (``inputs``/``outputs``
    by symbol id as a string). Decoding starts at the generation's oldest key frame in the ring,
    or, with ``resume`` = ``(seq, decoded frame)`` of an earlier pass that is still in the ring,
    after that tick (the frame given is not changed).
    Nothing is yielded when ``seq`` has left the ring.
    """
    entries = ring.snapshot()
    target = next((e for e in reversed(entries) if e.seq == seq), None)
    if target is None:
        return
    gen = target.gen
    state: dict[str, Any] | None = None
    after = -1
    if resume is not None and any(e.seq == resume[0] and e.gen is gen for e in entries):
        after, state = resume[0], dict(resume[1])  # merging replaces robots, never mutates them
    for entry in entries:
        if entry.gen is not gen or entry.seq > seq or entry.seq <= after:
            continue
        if state is None:
            if entry.full is None:
                continue
            state = orjson.loads(entry.full)
        else:
            _merge(state, orjson.loads(entry.delta))
        yield entry, state["robots"]


def decoded_frame(robots: list[dict[str, Any]]) -> dict[str, Any]:
    """A frame dict around ``robots`` for :func:`recorded_ticks`' ``resume``."""
    return {"robots": robots}
