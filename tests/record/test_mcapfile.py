"""The recordings' own MCAP writer, checked with the ``mcap`` package's readers (written independently)."""

from __future__ import annotations

import dataclasses
import io
import random

import pytest
import zstandard
from mcap.reader import make_reader
from mcap.records import Chunk, DataEnd, Footer, Message, MessageIndex, Statistics
from mcap.stream_reader import StreamReader, breakup_chunk

from xabsl_studio.engine.record.mcapfile import McapWriter
from xabsl_studio.engine.record.mcapread import MAX_ATTACHMENT_BYTES, McapFile, RecordingError


def _file(chunk_size: int, messages: int = 500, compress: bool = True) -> tuple[bytes, list[tuple[int, int, bytes]]]:
    rng = random.Random(7)
    stream = io.BytesIO()
    writer = McapWriter(stream, chunk_size=chunk_size, compress=compress)
    writer.start(profile="xabsl", library="test")
    schema = writer.register_schema("thing", "jsonschema", b'{"type": "object"}')
    channels = [writer.register_channel(f"/topic/{i}", "json", schema, {"n": str(i)}) for i in range(3)]
    written = []
    for k in range(messages):
        channel = channels[rng.randrange(3)]
        data = b'{"k": %d, "pad": "%s"}' % (k, b"x" * rng.randrange(200))
        time_ns = 25_000_000 * (k // 3)
        writer.add_message(channel, time_ns, data, time_ns, k)
        written.append((channel, time_ns, data))
        if k == 100:  # a channel registered mid-file
            channels.append(writer.register_channel("/late", "json", schema))
    writer.finish()
    return stream.getvalue(), written


def test_the_mcap_reader_reads_every_message_in_order_with_valid_crcs() -> None:
    data, written = _file(chunk_size=4096)
    reader = make_reader(io.BytesIO(data), validate_crcs=True)
    read = [(c.id, m.log_time, m.data) for _, c, m in reader.iter_messages()]
    assert read == written
    assert [m.sequence for _, _, m in reader.iter_messages()] == list(range(len(written)))
    summary = reader.get_summary()
    assert summary is not None
    assert [c.topic for c in summary.channels.values()] == ["/topic/0", "/topic/1", "/topic/2", "/late"]
    assert summary.channels[0].metadata == {"n": "0"}
    assert summary.schemas[1].name == "thing" and summary.schemas[1].data == b'{"type": "object"}'
    stats = summary.statistics
    assert stats is not None and stats.message_count == len(written) and stats.channel_count == 4
    assert stats.chunk_count == len(summary.chunk_indexes) > 10
    assert stats.message_start_time == written[0][1] and stats.message_end_time == written[-1][1]
    assert stats.channel_message_counts == {c: sum(1 for w in written if w[0] == c) for c in range(3)}


def test_seeking_by_time_and_topic_reads_the_right_messages() -> None:
    data, written = _file(chunk_size=4096)
    reader = make_reader(io.BytesIO(data), validate_crcs=True)
    t0, t1 = 25_000_000 * 40, 25_000_000 * 60
    found = reader.iter_messages(topics=["/topic/1"], starting_at=t0, ending_before=t1)
    got = [(c.id, m.log_time, m.data) for _, c, m in found]
    assert got == [w for w in written if w[0] == 1 and t0 <= w[1] < t1]


def test_every_record_streams_with_crcs_and_the_message_indexes_point_at_their_messages() -> None:
    data, written = _file(chunk_size=4096)
    records = list(StreamReader(io.BytesIO(data), validate_crcs=True, emit_chunks=True).records)  # checks DataEnd's CRC
    assert isinstance(records[-1], Footer)
    assert any(isinstance(r, DataEnd) and r.data_section_crc != 0 for r in records)
    assert sum(isinstance(r, Statistics) for r in records) == 1
    seen = 0
    for i, record in enumerate(records):
        if not isinstance(record, Chunk):
            continue
        assert record.compression == "zstd"
        raw = zstandard.ZstdDecompressor().decompress(record.data, max_output_size=record.uncompressed_size)
        messages = [r for r in breakup_chunk(record, validate_crc=True) if isinstance(r, Message)]
        assert record.message_start_time == messages[0].log_time and record.message_end_time == messages[-1].log_time
        j = i + 1
        while j < len(records) and isinstance(records[j], MessageIndex):
            index = records[j]
            assert isinstance(index, MessageIndex)
            for log_time, offset in index.records:
                assert raw[offset] == 0x05  # a Message record starts there
                channel = int.from_bytes(raw[offset + 9 : offset + 11], "little")
                stamp = int.from_bytes(raw[offset + 15 : offset + 23], "little")
                assert (channel, stamp) == (index.channel_id, log_time)
            seen += len(index.records)
            j += 1
    assert seen == len(written)


def test_uncompressed_and_single_chunk_files_read_back_too() -> None:
    for compress, chunk_size in ((False, 4096), (True, 1 << 30)):
        data, written = _file(chunk_size=chunk_size, messages=50, compress=compress)
        reader = make_reader(io.BytesIO(data), validate_crcs=True)
        assert [(c.id, m.log_time, m.data) for _, c, m in reader.iter_messages()] == written


def test_a_file_without_messages_is_valid() -> None:
    stream = io.BytesIO()
    writer = McapWriter(stream)
    writer.start()
    writer.register_channel("/empty", "json", writer.register_schema("s", "jsonschema", b"{}"))
    writer.finish()
    reader = make_reader(io.BytesIO(stream.getvalue()), validate_crcs=True)
    assert list(reader.iter_messages()) == []
    summary = reader.get_summary()
    assert summary is not None and [c.topic for c in summary.channels.values()] == ["/empty"]


def test_chunk_and_file_time_ranges_hold_messages_out_of_order() -> None:
    stream = io.BytesIO()
    writer = McapWriter(stream, chunk_size=1 << 20)
    writer.start()
    channel = writer.register_channel("/t", "json", writer.register_schema("s", "jsonschema", b"{}"))
    for time_ns in (50, 20, 70, 10):
        writer.add_message(channel, time_ns, b"{}", time_ns)
    writer.finish()
    reader = make_reader(io.BytesIO(stream.getvalue()), validate_crcs=True)
    summary = reader.get_summary()
    assert summary is not None and summary.statistics is not None
    (index,) = summary.chunk_indexes
    assert (index.message_start_time, index.message_end_time) == (10, 70)
    assert (summary.statistics.message_start_time, summary.statistics.message_end_time) == (10, 70)
    assert sorted(m.log_time for _, _, m in reader.iter_messages()) == [10, 20, 50, 70]


def _attached() -> tuple[bytes, list[tuple[str, bytes]]]:
    stream = io.BytesIO()
    writer = McapWriter(stream, chunk_size=4096)
    writer.start(profile="xabsl", library="test")
    schema = writer.register_schema("thing", "jsonschema", b'{"type": "object"}')
    channel = writer.register_channel("/topic", "json", schema)
    attached = [("first.bin", bytes(range(256)) * 3), ("second.bin", b"")]
    for k in range(300):
        writer.add_message(channel, k, b'{"k": %d}' % k, k, k)
        if k == 120:  # mid-file: the open chunk closes before it
            writer.attach(attached[0][0], "application/octet-stream", attached[0][1], log_time=k, create_time=7)
    writer.attach(attached[1][0], "application/octet-stream", attached[1][1], log_time=300)
    writer.finish()
    return stream.getvalue(), attached


def test_attachments_read_back_with_the_mcap_reader_and_ours() -> None:
    data, attached = _attached()
    reader = make_reader(io.BytesIO(data), validate_crcs=True)
    assert [(a.name, a.data) for a in reader.iter_attachments()] == attached
    assert [m.log_time for _, _, m in reader.iter_messages()] == list(range(300))
    summary = reader.get_summary()
    assert summary is not None and summary.statistics is not None
    assert summary.statistics.attachment_count == 2
    assert [(i.name, i.log_time, i.create_time, i.data_size) for i in summary.attachment_indexes] == [
        ("first.bin", 120, 7, 768),
        ("second.bin", 300, 0, 0),
    ]
    records = list(StreamReader(io.BytesIO(data), skip_magic=False).records)
    assert sum(isinstance(r, Footer) for r in records) == 1

    ours = McapFile.open("attached.mcap", io.BytesIO(data))
    assert [(i.name, ours.attachment(i)) for i in ours.attachments] == attached


def test_a_damaged_attachment_is_a_recording_error_naming_it() -> None:
    data, _ = _attached()
    ours = McapFile.open("attached.mcap", io.BytesIO(data))
    index = ours.attachments[0]
    start = data.index(bytes(range(256)))
    damaged = bytearray(data)
    damaged[start + 10] ^= 0xFF
    broken = McapFile.open("attached.mcap", io.BytesIO(bytes(damaged)))
    with pytest.raises(RecordingError, match=r"damaged attachment 'first\.bin'.*CRC"):
        broken.attachment(broken.attachments[0])
    moved = dataclasses.replace(index, offset=index.offset + 1)
    with pytest.raises(RecordingError, match="no attachment record"):
        ours.attachment(moved)
    huge = dataclasses.replace(index, data_size=MAX_ATTACHMENT_BYTES + 1)
    with pytest.raises(RecordingError, match="at most"):
        ours.attachment(huge)
