"""The columns a recording stores for queries are the columns a scan of its messages gives.

The recording's writer builds them from the raw values it encodes, in bulk
(``xabsl_studio.engine.record.stored``); a query's scan builds them from the JSON messages one by
one (``ColumnsBuilder``). Both must say the same at every tick: the same ticks, path nodes, and
known values, with unknown where the file holds null. Checked on a real match with a hot reload,
with the operations edited to hold what hosts send rarely (NaN, infinities, getters that raise,
-0.0, enum values outside their table), at the studio's exact precision and the command line's
thousandths, cut into several parts.
"""

from __future__ import annotations

import dataclasses
import math
import struct
from pathlib import Path
from typing import Any
from unittest.mock import patch

import numpy as np
import orjson
import pytest
import zstandard
from mcap.reader import make_reader
from mcap.writer import Writer

from xabsl_studio.engine.cli import main
from xabsl_studio.engine.host import BehaviorLoop
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.query import query_recording, scan
from xabsl_studio.engine.record import Recorder, Recording, RecordingEncoder, RecordingError, stored
from xabsl_studio.engine.record.columns import Codes, RobotColumns, Selection
from xabsl_studio.engine.record.mcapread import Malformed
from xabsl_studio.engine.record.sampler import reads_json
from xabsl_studio.examples.soccer.run import DEFAULT_AWAY, DEFAULT_HOME, build_world, load_team

SOCCER = Path(__file__).resolve().parents[2] / "examples" / "soccer"
TICKS = 400
#: everything: every value and every input function's calls
SELECTION = Selection()


@pytest.fixture(scope="module")
def operations() -> list[tuple[Any, ...]]:
    """The encoder operations of a 2 v 2 match with a hot reload of the home team at tick 150."""
    home, away = load_team(DEFAULT_HOME), load_team(DEFAULT_AWAY)
    world = build_world(4, home, away, players=2)
    engines = [a.controller.engine for a in world.agents]  # type: ignore[union-attr]
    ops: list[tuple[Any, ...]] = []

    class Capture:
        def __init__(self, **_options: object) -> None:
            pass

        def handle(self, op: tuple[Any, ...]) -> None:
            ops.append(op)

        def close(self) -> tuple[str, int, int, int]:
            return "", 0, 0, 0

    reloaded = compile_file(str(DEFAULT_HOME / "agents.xabsl")).program
    assert reloaded is not None
    with patch("xabsl_studio.engine.record.writer.RecordingEncoder", Capture):
        recorder = Recorder(
            "unused.mcap", world, {"behavior": home, "chase": away}, example="soccer", behavior_hz=40, physics_hz=120
        )
        loop = BehaviorLoop(world)
        for tick in range(TICKS):
            if tick == 150:
                for agent, engine in zip(world.agents, engines, strict=True):
                    if agent.team_index == 0:
                        engine.reload(reloaded)
                recorder.reload("behavior", reloaded, engines, loop.now_ms)
            now = loop.now_ms
            loop.tick()
            recorder.tick(now)
        recorder.close()
    return ops


def _odd(ops: list[tuple[Any, ...]]) -> list[tuple[Any, ...]]:
    """The operations with rare values put into the first agent's inputs now and then."""
    rare: list[Any] = [math.nan, math.inf, -math.inf, None, -0.0, 1e15, 2.0**60, 0.0005, True, 7]
    out = []
    for op in ops:
        if op[0] == "tick" and op[1] % 7 == 3 and op[3][0] is not None:
            samples = list(op[3])
            sample = list(samples[0])
            inputs = list(sample[3])
            for i in range(len(inputs)):
                if (i + op[1]) % 5 == 0:
                    inputs[i] = rare[(i + op[1]) % len(rare)]
            sample[3] = tuple(inputs)
            sample[7] = ("robot.x",) if op[1] % 2 else ()  # a getter that raised
            samples[0] = tuple(sample)
            op = (*op[:3], samples, *op[4:])
        out.append(op)
    return out


def _encode(ops: list[tuple[Any, ...]], path: Path, decimals: int | None, part_ticks: int) -> Path:
    with patch.object(stored, "PART_TICKS", part_ticks):
        encoder = RecordingEncoder(path, 40, key_every=40, decimals=decimals)
        for op in ops:
            encoder.handle(op)
        encoder.close()
    return path


def _columns(path: Path, use_stored: bool) -> dict[str, RobotColumns]:
    with Recording(path) as recording:
        codes = Codes()
        scan.seed_codes(recording, codes)
        if use_stored:
            found = scan.stored_columns(recording, recording.agents, codes, SELECTION)
            assert found is not None
            return found
        return scan.read_columns(_without_stored(recording), recording.agents, codes, SELECTION, workers=1)


def _without_stored(recording: Recording) -> Recording:
    """The recording, its stored columns not offered (a scan of its messages)."""
    recording.attachments = lambda name, media_type: []  # type: ignore[method-assign]
    return recording


def assert_same(a: RobotColumns, b: RobotColumns) -> None:
    """The same ticks, nodes, and at every tick the same known values (unknown ones are not compared)."""
    for name in ("seq", "t", "gen"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    for field in dataclasses.fields(a.nodes):
        assert np.array_equal(getattr(a.nodes, field.name), getattr(b.nodes, field.name), equal_nan=True), field.name
    n = len(a)
    unknown = (np.zeros(n), np.zeros(n, dtype=np.bool_))
    for name in sorted(set(a.values) | set(b.values)):
        (va, ka), (vb, kb) = a.values.get(name, unknown), b.values.get(name, unknown)
        assert np.array_equal(ka, kb), (name, np.flatnonzero(ka != kb)[:5])
        assert np.array_equal(va[ka], vb[kb]), (name, np.flatnonzero(va[ka] != vb[kb])[:5])
    assert a.has_reads == b.has_reads
    assert set(a.programs) == set(b.programs)
    assert a.functions == b.functions and set(a.calls) == set(b.calls)
    for name, calls in a.calls.items():
        other = b.calls[name]
        assert np.array_equal(calls.row, other.row) and calls.args == other.args, name
        assert np.array_equal(calls.known, other.known), name
        assert np.array_equal(calls.result[calls.known], other.result[other.known]), name


def _piped(ops: list[tuple[Any, ...]]) -> list[tuple[Any, ...]]:
    """The operations with each tick's reads as JSON bytes, as they come through the studio's pipe."""
    out = []
    for op in ops:
        if op[0] == "tick":
            samples = [None if s is None else (*s[:8], reads_json(s[8]) if s[8] is not None else None) for s in op[3]]
            op = (*op[:3], samples, *op[4:])
        out.append(op)
    return out


@pytest.mark.parametrize(
    ("decimals", "piped"), [(3, False), (None, False), (None, True)], ids=["thousandths", "exact", "piped"]
)
def test_stored_columns_equal_the_scan_of_the_messages(
    operations: list[tuple[Any, ...]], tmp_path: Path, decimals: int | None, piped: bool
) -> None:
    odd = _odd(operations)
    path = _encode(_piped(odd) if piped else odd, tmp_path / "odd.mcap", decimals, part_ticks=90)
    with Recording(path) as recording:
        parts = [
            stored.decode_part(recording.attachment(a)) for a in recording.attachments(stored.NAME, stored.MEDIA_TYPE)
        ]
    # cut at the first key frame (every 40 ticks) 90 ticks or more after a part began
    assert [(p.start, p.stop) for p in parts] == [(0, 120), (120, 240), (240, 360), (360, TICKS)]
    mine, scanned = _columns(path, use_stored=True), _columns(path, use_stored=False)
    assert list(mine) == list(scanned) == ["blue1", "blue2", "red1", "red2"]
    for robot in mine:
        assert_same(mine[robot], scanned[robot])
    blue = mine["blue1"]
    assert set(np.unique(blue.gen).tolist()) == {0, 1}
    _values, known = blue.values["robot.x"]
    assert not known.all() and known.any()  # the raised getter and the rare values are unknown
    assert len(blue.calls["distance_to"].row) > 100  # the calls the decisions made


def test_the_independent_reader_sees_the_parts_and_the_messages_alike(
    operations: list[tuple[Any, ...]], tmp_path: Path
) -> None:
    path = _encode(operations, tmp_path / "plain.mcap", 3, part_ticks=150)
    with open(path, "rb") as stream:
        reader = make_reader(stream, validate_crcs=True)
        attachments = list(reader.iter_attachments())
        messages = sum(1 for _ in reader.iter_messages())
    assert [a.name for a in attachments] == [stored.NAME] * 3
    assert {a.media_type for a in attachments} == {stored.MEDIA_TYPE}
    parts = [stored.decode_part(a.data) for a in attachments]
    assert [(p.start, p.stop) for p in parts] == [(0, 160), (160, 320), (320, TICKS)]
    with Recording(path) as recording:
        assert messages > TICKS * 4
        for robot in recording.agents:
            assert sum(len(p.robots[robot]) for p in parts) == recording.tick_messages(robot)


def _rewritten(path: Path, out: Path, keep: int | None) -> Path:
    """``path`` written again by the mcap package: every message, and only attachment ``keep``."""
    with open(path, "rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None
        attachments = list(reader.iter_attachments())
        with open(out, "wb") as target:
            writer = Writer(target)
            writer.start(profile="xabsl", library="test")
            schemas = {i: writer.register_schema(s.name, s.encoding, s.data) for i, s in summary.schemas.items()}
            channels = {
                i: writer.register_channel(c.topic, c.message_encoding, schemas.get(c.schema_id, 0), c.metadata)
                for i, c in summary.channels.items()
            }
            for _schema, channel, message in reader.iter_messages():
                writer.add_message(
                    channels[channel.id], message.log_time, message.data, message.publish_time, message.sequence
                )
            for k, attachment in enumerate(attachments):
                if k == keep:
                    writer.add_attachment(
                        attachment.create_time,
                        attachment.log_time,
                        attachment.name,
                        attachment.media_type,
                        attachment.data,
                    )
            writer.finish()  # type: ignore[no-untyped-call]
    return out


@pytest.mark.parametrize(
    "condition",
    [
        "game.state == ready && ball.distance > 2000",
        "team.role == striker || robot.x < -2000",
        "robot.rotation > 10 && ball.seen",
        "abs(value = ball.angle) < 30 || team.rank(time = team.time_to_ball) == 0",
    ],
)
def test_a_query_answers_the_same_with_the_stored_columns_without_them_and_with_a_part_missing(
    operations: list[tuple[Any, ...]], tmp_path: Path, condition: str
) -> None:
    path = _encode(operations, tmp_path / "plain.mcap", 3, part_ticks=150)
    with_columns = query_recording(path, condition)
    assert with_columns.matched  # the condition holds somewhere
    for keep in (None, 1):  # none of the parts, or one: the messages are scanned
        other = _rewritten(path, tmp_path / f"keep-{keep}.mcap", keep)
        with Recording(other) as recording:
            codes = Codes()
            scan.seed_codes(recording, codes)
            assert scan.stored_columns(recording, recording.agents, codes, SELECTION) is None
        assert query_recording(other, condition) == with_columns


def test_a_damaged_part_is_an_error_naming_the_file(operations: list[tuple[Any, ...]], tmp_path: Path) -> None:
    path = _encode(operations, tmp_path / "plain.mcap", 3, part_ticks=150)
    with Recording(path) as recording:
        index = recording.attachments(stored.NAME, stored.MEDIA_TYPE)[1]
    data = bytearray(path.read_bytes())
    data[index.offset + index.length - 40] ^= 0x10  # in the part's bytes: its CRC no longer matches
    damaged = tmp_path / "damaged.mcap"
    damaged.write_bytes(bytes(data))
    with pytest.raises(RecordingError, match=r"damaged\.mcap: damaged attachment 'xabsl\.columns'.*CRC"):
        Recording(damaged)


def _part(header: dict[str, Any], body: bytes = b"") -> bytes:
    text = orjson.dumps(header)
    return zstandard.ZstdCompressor().compress(struct.pack("<I", len(text)) + text + body)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"not zstd", "does not decompress"),
        (zstandard.ZstdCompressor(write_content_size=False).compress(b"x" * 100), "uncompressed"),
        (zstandard.ZstdCompressor().compress(b"\xff\xff\xff\x7f{}"), "header of"),
        (_part({"version": 99}), "not a columns part"),
        (_part({"version": 1, "start": 5, "stop": 2, "codes": [], "robots": [], "arrays": []}), "tick range"),
        (
            _part({"version": 1, "start": 0, "stop": 2, "codes": [], "robots": [], "arrays": [["<i8", 9, "raw", 1.0]]}),
            "run past",
        ),
        (
            _part({"version": 1, "start": 0, "stop": 2, "codes": [], "robots": [], "arrays": [["<u8", 1, "raw", 1.0]]}),
            "not described",
        ),
        (
            _part({"version": 1, "start": 0, "stop": 2, "codes": [], "robots": [{"name": "a"}], "arrays": []}),
            "not described right|not a list",
        ),
        (
            _part(
                {
                    "version": 1,
                    "start": 0,
                    "stop": 2,
                    "codes": [],
                    "arrays": [["<i8", 1, "delta", 1.0]] * 3,
                    "robots": [
                        {"name": "a", "has_reads": True, "times": "raw", "functions": [], "events": [], "calls": []}
                    ],
                },
                struct.pack("<3q", 7, 0, 0),
            ),
            "not in the part's range",
        ),
    ],
)
def test_a_part_that_does_not_hold_together_is_refused(data: bytes, message: str) -> None:
    with pytest.raises(Malformed, match=message):
        stored.decode_part(data)


def test_xabsl_run_records_the_columns_a_scan_of_its_messages_gives(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    assert main(["run", str(SOCCER), "--duration", "10", "--players", "2", "--record", str(path)]) == 0
    with Recording(path) as recording:
        assert recording.attachments(stored.NAME, stored.MEDIA_TYPE)
        codes = Codes()
        scan.seed_codes(recording, codes)
        mine = scan.stored_columns(recording, recording.agents, codes, SELECTION)
    assert mine is not None
    with Recording(path) as recording:
        codes = Codes()
        scan.seed_codes(recording, codes)
        scanned = scan.read_columns(_without_stored(recording), recording.agents, codes, SELECTION, workers=1)
    for robot in mine:
        assert_same(mine[robot], scanned[robot])
