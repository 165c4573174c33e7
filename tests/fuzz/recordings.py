"""A generator of hostile recordings: MCAP files that are cut, flipped, lying or of the wrong shape.

:func:`hostile_recordings` derives them from one real recording (``base``), deterministically
(a seeded ``random.Random``): the probes of issue 25, kept. Three families:

* bytes: empty, not MCAP, the magic alone, cut at many offsets, bit flips all over, random bytes
  between two magics, and length fields that lie (a footer pointing past the end, a summary
  record of 2^64-1 bytes, a chunk that claims 2^40 bytes uncompressed, a zstd frame that says so);
* shape: the base's messages read with the ``mcap`` package (an independent reader) and written
  again with one JSON message changed: a header without ``behavior_hz``, rates of 0, names with
  NUL or 300 characters, an agent twice, programs without options, paths naming options that
  do not exist, values that are lists, bad JSON, 5,000 nested brackets, unknown world options,
  recorded source names with NUL or 300 characters;
* missing: the base without its program messages, its scene channel, one agent's ticks.

Each is ``(name, bytes)``; names are plain file names (``NN-what.mcap``). Files that are not
regular (a FIFO, a link to ``/dev/zero``, a folder) are made by the tests themselves.
"""

from __future__ import annotations

import random
import struct
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from io import BytesIO
from pathlib import Path
from typing import Any

import orjson
import zstandard
from mcap.reader import make_reader

from xabsl_studio.engine.record import schema as S
from xabsl_studio.engine.record.mcapfile import MAGIC, McapWriter

SEED = 25


@dataclass(frozen=True)
class Message:
    """One message of the base recording, with its schema and channel."""

    schema: str
    encoding: str
    schema_data: bytes
    topic: str
    log_time: int
    publish_time: int
    sequence: int
    data: bytes


def read_messages(base: bytes) -> list[Message]:
    """The messages of ``base`` in file order (the ``mcap`` package's reader, not ours)."""
    out = []
    for schema, channel, message in make_reader(BytesIO(base)).iter_messages(log_time_order=False):
        assert schema is not None
        out.append(
            Message(
                schema.name,
                schema.encoding,
                schema.data,
                channel.topic,
                message.log_time,
                message.publish_time,
                message.sequence,
                message.data,
            )
        )
    return out


def write_messages(messages: list[Message]) -> bytes:
    """A finished MCAP file of ``messages`` (our spec writer; small chunks, so there are many)."""
    stream = BytesIO()
    writer = McapWriter(stream, chunk_size=16 * 1024)
    writer.start(profile=S.PROFILE, library="hostile")
    schemas: dict[str, int] = {}
    channels: dict[str, int] = {}
    for m in messages:
        if m.schema not in schemas:
            schemas[m.schema] = writer.register_schema(m.schema, m.encoding, m.schema_data)
        if m.topic not in channels:
            channels[m.topic] = writer.register_channel(m.topic, "json", schemas[m.schema])
        writer.add_message(channels[m.topic], m.log_time, m.data, m.publish_time, m.sequence)
    writer.finish()
    return stream.getvalue()


Edit = Callable[[Any], Any]


def _edit_first(messages: list[Message], topic: str, edit: Callable[[Any], Any]) -> list[Message]:
    out = list(messages)
    for i, m in enumerate(out):
        if m.topic == topic or (topic.endswith("/") and m.topic.startswith(topic)):
            data = edit(orjson.loads(m.data))
            out[i] = Message(**{**m.__dict__, "data": data if isinstance(data, bytes) else orjson.dumps(data)})
            return out
    raise AssertionError(f"no message on {topic}")


def _set(path: str, value: Any) -> Edit:
    def edit(doc: Any) -> Any:
        keys = path.split(".")
        node = doc
        for key in keys[:-1]:
            node = node[int(key)] if isinstance(node, list) else node[key]
        last = keys[-1]
        if value is _DELETE:
            del node[last]
        elif isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value
        return doc

    return edit


_DELETE = object()


def _path_edit(node: list[Any]) -> Edit:
    def edit(doc: Any) -> Any:
        doc["path"] = [node]
        return doc

    return edit


def _shape_edits() -> list[tuple[str, str, Edit]]:
    header, program, agents = S.RECORDING, S.PROGRAM, "/xabsl/agents/"
    return [
        ("no-behavior-hz", header, _set("behavior_hz", _DELETE)),
        ("behavior-hz-0", header, _set("behavior_hz", 0)),
        ("behavior-hz-string", header, _set("behavior_hz", "40")),
        ("behavior-hz-huge", header, _set("behavior_hz", 2**62)),
        ("behavior-hz-float", header, _set("behavior_hz", 1e300)),
        ("key-every-0", header, _set("key_every", 0)),
        ("key-every-negative", header, _set("key_every", -4)),
        ("version-newer", header, _set("version", 99)),
        ("format-other", header, _set("format", "rosbag")),
        ("header-a-list", header, lambda doc: [doc]),
        ("header-not-json", header, lambda doc: b"{\"format\": xabsl"),
        ("agents-not-a-list", header, _set("agents", {"a": 1})),
        ("agent-name-nul", header, _set("agents.0.name", "blue\x001")),
        ("agent-name-300", header, _set("agents.0.name", "b" * 300)),
        ("agent-twice", header, lambda doc: {**doc, "agents": doc["agents"] + doc["agents"][:1]}),
        ("agent-program-unknown", header, _set("agents.0.program", "nobody")),
        ("tables-missing", header, _set("tables", {})),
        ("enum-table-bad", header, lambda doc: _first_tables(doc, "enums", {"e": {"x": "y"}})),
        ("first-seq-negative", header, _set("first_seq", -5)),
        ("world-option-unknown", header, _set("world_options", {"robots": 1, "half_duration_s": 5, "bogus": 1})),
        ("world-option-wrong-type", header, _set("world_options", {"robots": "many", "half_duration_s": 5})),
        ("seed-missing", header, _set("seed", _DELETE)),
        ("program-without-options", program, _set("program.options", _DELETE)),
        ("program-options-shifted", program, lambda doc: _shift_ids(doc)),
        ("program-state-less", program, lambda doc: _no_states(doc)),
        ("program-key-unknown", program, _set("key", "nobody")),
        ("program-sources-nul", program, lambda doc: _sources(doc, "options/a\x00b.xabsl")),
        ("program-sources-300", program, lambda doc: _sources(doc, "options/" + "s" * 300 + ".xabsl")),
        ("program-sources-up", program, lambda doc: _sources(doc, "../" * 40 + "x.xabsl")),
        ("program-ic-garbage", program, _set("ic", "garbage\x00ic")),
        ("tick-not-json", agents, lambda doc: b"{\"seq\": 0, \"path\": [[0"),
        ("tick-nested-5000", agents, lambda doc: b"[" * 5000 + b"]" * 5000),
        ("tick-path-option-unknown", agents, _path_edit([0, 0, 9999, 0, 0, 0, 0, -1, []])),
        ("tick-path-state-unknown", agents, _path_edit([0, 0, 0, 9999, 0, 0, 0, -1, []])),
        ("tick-path-string", agents, _set("path", "option")),
        ("tick-path-node-short", agents, _path_edit([0, 0])),
        ("tick-path-depth-jump", agents, lambda doc: {**doc, "path": [doc["path"][0], _deeper(doc["path"][0])]}),
        ("tick-inputs-list", agents, _set("inputs", [1, 2])),
        ("tick-value-list", agents, lambda doc: {**doc, "inputs": {"x": [1, 2, 3]}}),
        ("tick-seq-missing", agents, _set("seq", _DELETE)),
        ("tick-seq-string", agents, _set("seq", "0")),
        ("tick-gen-unknown", agents, _set("gen", 7)),
        ("tick-roots-bad", agents, _set("roots", [["option"]])),
        ("scene-not-object", S.WORLD_SCENE, _set("scene", 5)),
        ("static-not-object", S.WORLD_STATIC, _set("scene", [])),
    ]  # fmt: skip


def _deeper(node: list[Any]) -> list[Any]:
    return [node[0], 5, *node[2:]]


def _first_tables(doc: Any, field: str, value: Any) -> Any:
    key = next(iter(doc["tables"]))
    doc["tables"][key][field] = value
    return doc


def _shift_ids(doc: Any) -> Any:
    for option in doc["program"]["options"]:
        option["id"] += 1
    return doc


def _no_states(doc: Any) -> Any:
    doc["program"]["options"][0]["states"] = []
    return doc


def _sources(doc: Any, name: str) -> Any:
    sources = doc.get("sources") or {"agents": "agents.xabsl", "files": {"agents.xabsl": ""}}
    sources["files"] = {**sources["files"], name: "option o { initial state s { action { } } }"}
    doc["sources"] = sources
    return doc


_BAD_RELOAD = {"seq": 3, "t": 0, "kind": "reload", "agent": None, "data": {"key": "k", "gen": 1, "tables": 5}}


def _with_event(messages: list[Message], event: dict[str, Any]) -> list[Message]:
    """``messages`` with ``event`` on ``/xabsl/events`` after the header."""
    first = messages[0]
    schema = orjson.dumps(S.SCHEMAS["xabsl.Event"])
    data = orjson.dumps(event)
    extra = Message("xabsl.Event", "jsonschema", schema, S.EVENTS, first.log_time, first.publish_time, 0, data)
    return [first, extra, *messages[1:]]


def _missing(messages: list[Message]) -> Iterator[tuple[str, list[Message]]]:
    yield "no-program-messages", [m for m in messages if m.topic != S.PROGRAM]
    yield "no-scene-channel", [m for m in messages if m.topic != S.WORLD_SCENE]
    agent = next(m.topic for m in messages if m.topic.startswith("/xabsl/agents/"))
    yield "no-ticks-of-one-agent", [m for m in messages if m.topic != agent]
    yield "no-header", [m for m in messages if m.topic != S.RECORDING]
    yield "header-only", [m for m in messages if m.topic == S.RECORDING]


def _lying_lengths(base: bytes) -> Iterator[tuple[str, bytes]]:
    size = len(base)
    footer_at = size - 8 - 29
    opcode, length, summary_start, offsets, _crc = struct.unpack_from("<BQQQI", base, footer_at)
    assert opcode == 0x02 and length == 20
    yield "footer-summary-past-end", base[:footer_at] + struct.pack("<BQQQI", 2, 20, 2**63, offsets, 0) + MAGIC
    huge = struct.pack("<BQQQI", 2, 2**64 - 1, summary_start, offsets, 0)
    yield "footer-length-huge", base[:footer_at] + huge + MAGIC
    # the first summary record (a Schema) claiming 2^64-1 bytes, the CRC cleared so it is believed
    lie = bytearray(base)
    struct.pack_into("<Q", lie, summary_start + 1, 2**64 - 1)
    struct.pack_into("<I", lie, footer_at + 25, 0)
    yield "summary-record-huge", bytes(lie)
    # a schema name of 4 GiB in the summary
    lie = bytearray(base)
    struct.pack_into("<I", lie, summary_start + 9 + 2, 2**32 - 1)
    struct.pack_into("<I", lie, footer_at + 25, 0)
    yield "summary-string-huge", bytes(lie)
    # the first chunk: its uncompressed size 2^40, then its zstd frame claiming 2^40 too
    chunk = 8 + 9 + struct.unpack_from("<Q", base, 9)[0]  # after the magic and the Header record
    assert base[chunk] == 0x06
    lie = bytearray(base)
    struct.pack_into("<Q", lie, chunk + 9 + 16, 2**40)
    yield "chunk-uncompressed-huge", bytes(lie)
    body = chunk + 9
    compression_len = struct.unpack_from("<I", base, body + 28)[0]
    payload_at = body + 32 + compression_len + 8
    frame = zstandard.ZstdCompressor(level=1).compress(b"x" * 100)
    forged = bytearray(frame)
    forged[4] = 0xE0  # frame header descriptor: an 8-byte content size, single segment
    forged_frame = bytes(forged[:5]) + struct.pack("<Q", 2**40) + bytes(frame[6:])
    lie = bytearray(base)
    lie[payload_at : payload_at + len(forged_frame)] = forged_frame
    yield "chunk-zstd-frame-huge", bytes(lie)
    lie = bytearray(base)
    struct.pack_into("<Q", lie, chunk + 1, 2**63)
    yield "chunk-record-huge", bytes(lie)


def hostile_recordings(base: bytes, seed: int = SEED) -> list[tuple[str, bytes]]:
    """The hostile files derived from ``base`` (see the module docstring), in a fixed order."""
    rnd = random.Random(seed)
    out: list[tuple[str, bytes]] = [
        ("empty", b""),
        ("not-mcap", b"hello, I am not a recording\n"),
        ("magic-only", MAGIC),
        ("two-magics", MAGIC + MAGIC),
        ("random-between-magics", MAGIC + rnd.randbytes(4096) + MAGIC),
    ]
    for k in range(12):
        at = rnd.randrange(8, len(base) - 1)
        out.append((f"cut-{k}", base[:at]))
    for k in range(16):
        flipped = bytearray(base)
        for _ in range(rnd.randint(1, 3)):
            at = rnd.randrange(len(base))
            flipped[at] ^= 1 << rnd.randrange(8)
        out.append((f"flip-{k}", bytes(flipped)))
    out.extend(_lying_lengths(base))
    messages = read_messages(base)
    for what, topic, edit in _shape_edits():
        out.append((what, write_messages(_edit_first(messages, topic, edit))))
    for what, event in (("event-no-seq", {"kind": "note", "data": {}}), ("event-reload-bad", _BAD_RELOAD)):
        out.append((what, write_messages(_with_event(messages, event))))
    for what, kept in _missing(messages):
        out.append((what, write_messages(kept)))
    return [(f"{i:02d}-{what}.mcap", data) for i, (what, data) in enumerate(out)]


def write_all(folder: Path, base: bytes, seed: int = SEED) -> list[Path]:
    """Write every hostile recording into ``folder``; their paths."""
    paths = []
    for name, data in hostile_recordings(base, seed):
        path = folder / name
        path.write_bytes(data)
        paths.append(path)
    return paths
