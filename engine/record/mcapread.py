"""Reading MCAP files from the spec, every length checked: the reading half of ``mcapfile``.

A recording is opened on behalf of whoever named it (a command line, a studio's record folder,
a client's request), so its bytes are not trusted: every length field is checked against what
the file and the record around it hold, and against a bound, before anything is allocated from
it; strings must be UTF-8; chunks must decompress to exactly their stated size and match their
CRC. Whatever is wrong is a :class:`RecordingError` naming the file and the byte offset, never
a ``struct.error``, ``MemoryError`` or a read of gigabytes.

* :class:`McapFile` is the seeking reader of a finished file: the footer, the summary section
  (schemas, channels, statistics, chunk indexes), and the messages of the chunks that overlap a
  time window, in file order (recordings write chunks in time order).
* :func:`scan_chunks` reads the data section front to back and stops at the first record that is
  cut or damaged (a file whose writer died: ``xabsl_studio.engine.record.recover``).

Only what recordings use is read: chunked files, ``zstd`` or uncompressed chunks, and attachments
found through their summary index (:meth:`McapFile.attachment`). Other records (metadata, message
indexes) are skipped by their length.
"""

from __future__ import annotations

import os
import stat
import struct
import zlib
from collections.abc import Container, Iterator
from dataclasses import dataclass, field
from typing import BinaryIO

import zstandard

from xabsl_studio.engine.errors import RecordError
from xabsl_studio.engine.record.mcapfile import MAGIC

__all__ = [
    "MAX_ATTACHMENT_BYTES",
    "MAX_CHUNK_BYTES",
    "MAX_SUMMARY_BYTES",
    "AttachmentIndex",
    "Channel",
    "ChunkIndex",
    "Malformed",
    "McapFile",
    "RecordingError",
    "ScannedChunk",
    "Schema",
    "iter_records",
    "open_regular",
    "parse_channel",
    "parse_message",
    "parse_schema",
    "scan_chunks",
]

#: The largest chunk read, compressed or not. The recorder closes a chunk at 512 KiB of records
#: (a little more with its last message); a program description with its sources can be a few MB.
MAX_CHUNK_BYTES = 128 * 1024 * 1024
#: The largest summary section read (a 2 GB recording's is well under 1 MB).
MAX_SUMMARY_BYTES = 64 * 1024 * 1024

_FOOTER = 0x02
_HEADER = 0x01
_SCHEMA = 0x03
_CHANNEL = 0x04
_MESSAGE = 0x05
_CHUNK = 0x06
_CHUNK_INDEX = 0x08
_STATISTICS = 0x0B
_DATA_END = 0x0F
#: The largest attachment read (a 10-minute 10-robot match's stored columns take a few MB).
MAX_ATTACHMENT_BYTES = 512 * 1024 * 1024
_ATTACHMENT = 0x09
_ATTACHMENT_INDEX = 0x0A
#: Footer record: opcode, length 20, summary start, summary offset start, summary CRC; then the magic.
_TAIL = 1 + 8 + 20 + len(MAGIC)


class RecordingError(RecordError, ValueError):
    """A file that is not a recording this reader understands, or a request outside it.

    The message names the file and what is wrong; ``path`` and ``reason`` hold the two apart.
    """

    def __init__(self, message: str, *, path: str | None = None, reason: str | None = None) -> None:
        super().__init__(message)
        self.path = path
        self.reason = reason if reason is not None else message


def _error(path: str, reason: str) -> RecordingError:
    return RecordingError(f"{path}: {reason}", path=path, reason=reason)


class Malformed(RecordError):
    """Raised by :class:`_Cursor` (turned into a RecordingError with the file's name)."""


class _Cursor:
    """Little-endian fields of one record's bytes; nothing read past ``end``."""

    __slots__ = ("buffer", "end", "pos")

    def __init__(self, buffer: bytes | memoryview, pos: int = 0, end: int | None = None) -> None:
        self.buffer = buffer
        self.pos = pos
        self.end = len(buffer) if end is None else end

    def _take(self, n: int) -> int:
        pos = self.pos
        if n < 0 or pos + n > self.end:
            raise Malformed(f"a field of {n} bytes at {pos} runs past its record (ends at {self.end})")
        self.pos = pos + n
        return pos

    def u16(self) -> int:
        return int(struct.unpack_from("<H", self.buffer, self._take(2))[0])

    def u32(self) -> int:
        return int(struct.unpack_from("<I", self.buffer, self._take(4))[0])

    def u64(self) -> int:
        return int(struct.unpack_from("<Q", self.buffer, self._take(8))[0])

    def raw(self, n: int) -> bytes:
        start = self._take(n)
        return bytes(self.buffer[start : start + n])

    def string(self) -> str:
        data = self.raw(self.u32())
        try:
            return data.decode("utf-8")
        except UnicodeDecodeError:
            raise Malformed(f"a string before byte {self.pos} is not UTF-8") from None


@dataclass(frozen=True, slots=True)
class Schema:
    """A Schema record."""

    id: int
    name: str
    encoding: str
    data: bytes


@dataclass(frozen=True, slots=True)
class Channel:
    """A Channel record."""

    id: int
    schema_id: int
    topic: str
    message_encoding: str
    metadata: dict[str, str]


@dataclass(frozen=True, slots=True)
class ChunkIndex:
    """A ChunkIndex record (where a chunk is, which channels and times it holds)."""

    start: int
    end: int
    offset: int
    length: int
    channels: frozenset[int]
    compression: str
    compressed_size: int
    uncompressed_size: int


@dataclass(frozen=True, slots=True)
class AttachmentIndex:
    """An AttachmentIndex record (where an attachment is, its name and size)."""

    offset: int
    length: int
    log_time: int
    create_time: int
    data_size: int
    name: str
    media_type: str


def _attachment_index(c: _Cursor) -> AttachmentIndex:
    offset, length, log_time, create_time, size = c.u64(), c.u64(), c.u64(), c.u64(), c.u64()
    return AttachmentIndex(offset, length, log_time, create_time, size, c.string(), c.string())


def _schema(c: _Cursor) -> Schema:
    return Schema(c.u16(), c.string(), c.string(), c.raw(c.u32()))


def _channel(c: _Cursor) -> Channel:
    ident, schema_id, topic, encoding = c.u16(), c.u16(), c.string(), c.string()
    size = c.u32()
    start = c._take(size)
    pairs = _Cursor(c.buffer, start, start + size)
    metadata: dict[str, str] = {}
    while pairs.pos < pairs.end:
        key = pairs.string()
        metadata[key] = pairs.string()
    return Channel(ident, schema_id, topic, encoding, metadata)


def _chunk_index(c: _Cursor) -> ChunkIndex:
    start, end, offset, length = c.u64(), c.u64(), c.u64(), c.u64()
    size = c.u32()
    if size % 10:
        raise Malformed(f"a chunk index's message index offsets take {size} bytes, not a multiple of 10")
    channels = set()
    for _ in range(size // 10):
        channels.add(c.u16())
        c.u64()  # the offset of the channel's message index
    c.u64()  # message index length
    compression = c.string()
    return ChunkIndex(start, end, offset, length, frozenset(channels), compression, c.u64(), c.u64())


def _statistics_counts(c: _Cursor) -> dict[int, int]:
    c.u64(), c.u16(), c.u32(), c.u32(), c.u32(), c.u32(), c.u64(), c.u64()
    size = c.u32()
    if size % 10:
        raise Malformed(f"the statistics' channel counts take {size} bytes, not a multiple of 10")
    counts: dict[int, int] = {}
    for _ in range(size // 10):
        channel = c.u16()
        counts[channel] = c.u64()
    return counts


def _decompress(compression: str, payload: bytes, size: int, crc: int) -> bytes:
    """A chunk's records: exactly ``size`` bytes, matching ``crc`` (0: not given)."""
    if size > MAX_CHUNK_BYTES:
        raise Malformed(f"a chunk of {size} bytes uncompressed (at most {MAX_CHUNK_BYTES} are read)")
    if compression == "zstd":
        try:
            declared = zstandard.get_frame_parameters(payload).content_size
            if declared != zstandard.CONTENTSIZE_UNKNOWN and declared != size:
                raise Malformed(f"a chunk's zstd frame holds {declared} bytes, its record says {size}")
            records = zstandard.ZstdDecompressor().decompress(payload, max_output_size=size)
        except zstandard.ZstdError as error:
            raise Malformed(f"a chunk does not decompress ({error})") from None
    elif compression == "":
        records = payload
    else:
        raise Malformed(f"a chunk compressed with {compression!r} (recordings use zstd)")
    if len(records) != size:
        raise Malformed(f"a chunk decompresses to {len(records)} bytes, its record says {size}")
    if crc and zlib.crc32(records) != crc:
        raise Malformed("a chunk's CRC does not match its contents (the file is damaged)")
    return records


def _chunk_records(body: bytes | memoryview) -> bytes:
    """The uncompressed records of a Chunk record's body."""
    c = _Cursor(body)
    c.u64(), c.u64()  # message start and end time
    size, crc = c.u64(), c.u32()
    compression = c.string()
    length = c.u64()
    return _decompress(compression, c.raw(length), size, crc)


def iter_records(records: bytes | memoryview) -> Iterator[tuple[int, _Cursor]]:
    """``(opcode, cursor over its body)`` of each record in a chunk's records."""
    c = _Cursor(records)
    while c.pos < c.end:
        opcode = c.buffer[c._take(1)]
        length = c.u64()
        start = c._take(length)
        yield opcode, _Cursor(records, start, start + length)


def _messages_of(records: bytes, channels: Container[int] | None) -> Iterator[tuple[int, int, bytes]]:
    """The messages of a chunk's records; a record running past the chunk is :class:`Malformed`.

    Scanned with ``struct`` directly: the profiler reads hundreds of thousands.
    """
    unpack_from = struct.unpack_from
    position, size = 0, len(records)
    while position < size:
        if position + 9 > size:
            raise Malformed(f"a record header at {position} runs past the chunk's {size} bytes")
        opcode = records[position]
        (length,) = unpack_from("<Q", records, position + 1)
        body = position + 9
        end = body + length
        if end > size:
            raise Malformed(f"a record of {length} bytes at {position} runs past the chunk's {size} bytes")
        if opcode == _MESSAGE:
            if length < 22:
                raise Malformed(f"a message record of {length} bytes at {position} (at least 22)")
            channel, _sequence, log_time = unpack_from("<HIQ", records, body)
            if channels is None or channel in channels:
                yield channel, log_time, records[body + 22 : end]
        position = end


def open_regular(path: str) -> BinaryIO:
    """``path`` opened for reading if it is a regular file (a FIFO or a device never is)."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise _error(path, "not a regular file")
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


@dataclass(slots=True)
class McapFile:
    """A finished MCAP file's summary and messages (see the module docstring).

    Raises:
        RecordingError: not an MCAP file, cut (no footer or summary), or a damaged summary.
    """

    path: str
    stream: BinaryIO
    size: int = 0
    summary_start: int = 0
    schemas: dict[int, Schema] = field(default_factory=dict)
    channels: dict[int, Channel] = field(default_factory=dict)
    counts: dict[int, int] = field(default_factory=dict)
    chunks: list[ChunkIndex] = field(default_factory=list)
    attachments: list[AttachmentIndex] = field(default_factory=list)

    @classmethod
    def open(cls, path: str, stream: BinaryIO) -> McapFile:
        """Read the footer and the summary of ``stream`` (the file ``path``)."""
        self = cls(path, stream)
        try:
            self._read_summary()
        except Malformed as error:
            raise _error(path, f"damaged MCAP summary: {error}") from None
        return self

    def _read_at(self, offset: int, n: int) -> bytes:
        if offset < 0 or n < 0 or offset + n > self.size:
            raise Malformed(f"{n} bytes at {offset} are past the end of the file ({self.size} bytes)")
        self.stream.seek(offset)
        data = self.stream.read(n)
        if len(data) != n:
            raise Malformed(f"the file ended at {offset + len(data)} while reading {n} bytes at {offset}")
        return data

    def _read_summary(self) -> None:
        path = self.path
        self.stream.seek(0, os.SEEK_END)
        self.size = size = self.stream.tell()
        if size < len(MAGIC):
            raise _error(path, f"not an MCAP file ({size} bytes)")
        if self._read_at(0, len(MAGIC)) != MAGIC:
            raise _error(path, "not an MCAP file (no MCAP magic at its start)")
        if size < len(MAGIC) + _TAIL or self._read_at(size - len(MAGIC), len(MAGIC)) != MAGIC:
            raise _error(path, "the MCAP file is cut (no footer): the recording was not closed")
        tail = self._read_at(size - _TAIL, _TAIL - len(MAGIC))
        opcode, length, summary_start, _offsets, crc = struct.unpack("<BQQQI", tail)
        if opcode != _FOOTER or length != 20:
            raise _error(path, "the MCAP file is cut (no footer): the recording was not closed")
        if summary_start == 0:
            raise _error(path, "no MCAP summary (the recording was not closed)")
        footer_at = size - _TAIL
        if not len(MAGIC) <= summary_start <= footer_at:
            raise Malformed(f"the summary start {summary_start} is outside the file")
        if footer_at - summary_start > MAX_SUMMARY_BYTES:
            raise Malformed(f"a summary of {footer_at - summary_start} bytes (at most {MAX_SUMMARY_BYTES})")
        summary = self._read_at(summary_start, footer_at - summary_start)
        if crc and zlib.crc32(tail[:-4], zlib.crc32(summary)) != crc:
            raise Malformed("its CRC does not match (the file is damaged)")
        self.summary_start = summary_start
        for opcode, body in iter_records(summary):
            if opcode == _SCHEMA:
                schema = _schema(body)
                self.schemas[schema.id] = schema
            elif opcode == _CHANNEL:
                channel = _channel(body)
                self.channels[channel.id] = channel
            elif opcode == _STATISTICS:
                self.counts = _statistics_counts(body)
            elif opcode == _CHUNK_INDEX:
                index = _chunk_index(body)
                if not len(MAGIC) <= index.offset <= index.offset + index.length <= summary_start:
                    raise Malformed(f"a chunk index points at bytes {index.offset}+{index.length}, outside the data")
                if index.length > MAX_CHUNK_BYTES + 1024:
                    raise Malformed(f"a chunk of {index.length} bytes (at most {MAX_CHUNK_BYTES} are read)")
                self.chunks.append(index)
            elif opcode == _ATTACHMENT_INDEX:
                attachment = _attachment_index(body)
                if not len(MAGIC) <= attachment.offset <= attachment.offset + attachment.length <= summary_start:
                    raise Malformed(
                        f"an attachment index points at bytes {attachment.offset}+{attachment.length}, outside the data"
                    )
                self.attachments.append(attachment)
        for channel in self.channels.values():
            if channel.schema_id and channel.schema_id not in self.schemas:
                raise Malformed(f"channel {channel.topic!r} names schema {channel.schema_id}, which is not in it")
        self.chunks.sort(key=lambda c: (c.start, c.offset))

    def attachment(self, index: AttachmentIndex) -> bytes:
        """The data of the attachment ``index`` points at, checked against the index and its CRC.

        Raises:
            RecordingError: the attachment is not where its index says, larger than
                :data:`MAX_ATTACHMENT_BYTES`, or damaged.
        """
        try:
            if index.data_size > MAX_ATTACHMENT_BYTES:
                raise Malformed(f"{index.data_size} bytes (at most {MAX_ATTACHMENT_BYTES} are read)")
            data = self._read_at(index.offset, index.length)
            c = _Cursor(data)
            opcode = c.buffer[c._take(1)]
            length = c.u64()
            if opcode != _ATTACHMENT or length != index.length - 9:
                raise Malformed("no attachment record where its index points")
            body = _Cursor(data, c.pos, c.pos + length)
            log_time, create_time, name, media_type = body.u64(), body.u64(), body.string(), body.string()
            size = body.u64()
            if (log_time, create_time, name, media_type, size) != (
                index.log_time,
                index.create_time,
                index.name,
                index.media_type,
                index.data_size,
            ):
                raise Malformed("the attachment record does not match its index")
            content = body.raw(size)
            crc = body.u32()
            if crc and zlib.crc32(memoryview(data)[9 : body.pos - 4]) != crc:
                raise Malformed("its CRC does not match its contents (the file is damaged)")
            return content
        except Malformed as error:
            raise _error(self.path, f"damaged attachment {index.name!r} at byte {index.offset}: {error}") from None

    def chunk_records(self, index: ChunkIndex) -> bytes:
        """The uncompressed records of the chunk ``index`` points at.

        Raises:
            RecordingError: the chunk is not where its index says, or damaged.
        """
        try:
            data = self._read_at(index.offset, index.length)
            c = _Cursor(data)
            opcode = c.buffer[c._take(1)]
            length = c.u64()
            if opcode != _CHUNK:
                raise Malformed(f"no chunk at byte {index.offset}, where its index points")
            start = c._take(length)
            return _chunk_records(memoryview(data)[start : start + length])
        except Malformed as error:
            raise _error(self.path, f"damaged chunk at byte {index.offset}: {error}") from None

    def messages(
        self, channels: Container[int] | None = None, start: int | None = None, stop: int | None = None
    ) -> Iterator[tuple[int, int, bytes]]:
        """``(channel id, log time, data)`` of the messages with ``start <= log time < stop``, file order.

        Only chunks that overlap the window and hold one of ``channels`` (None: all) are read.

        Raises:
            RecordingError: a damaged chunk or message record.
        """
        for index in self.chunks:
            if (start is not None and index.end < start) or (stop is not None and index.start >= stop):
                continue
            if channels is not None and index.channels and not any(c in channels for c in index.channels):
                continue
            records = self.chunk_records(index)
            try:
                for channel, log_time, data in _messages_of(records, channels):
                    if (start is None or log_time >= start) and (stop is None or log_time < stop):
                        yield channel, log_time, data
            except Malformed as error:
                raise _error(self.path, f"damaged chunk at byte {index.offset}: {error}") from None


@dataclass(slots=True)
class ScannedChunk:
    """One complete chunk of a data section scanned front to back: its records, where it ends."""

    records: bytes
    end: int


def scan_chunks(stream: BinaryIO, size: int) -> Iterator[ScannedChunk | str]:
    """The complete chunks of the data section of ``stream`` (``size`` bytes), in file order.

    Yields each chunk that is whole and undamaged, then, where the scan stopped, a string: why
    (``"complete"`` at the DataEnd record or the footer). Records outside chunks are skipped.

    Raises:
        Malformed: not an MCAP file.
    """
    stream.seek(0)
    if stream.read(len(MAGIC)) != MAGIC:
        raise Malformed("no MCAP magic at its start")
    offset = len(MAGIC)
    while True:
        head = stream.read(9)
        if len(head) < 9:
            if not head and offset == size:
                yield "the file ends after its last complete record, without a summary (its writer stopped)"
            else:
                yield f"cut in the record at byte {offset}"
            return
        opcode, length = struct.unpack("<BQ", head)
        if opcode in (_DATA_END, _FOOTER):
            yield "complete"
            return
        if length > size - offset - 9:
            yield f"cut in the record at byte {offset} ({length} bytes, the file holds {size - offset - 9} more)"
            return
        if opcode != _CHUNK:
            stream.seek(length, os.SEEK_CUR)
            offset += 9 + length
            continue
        if length > MAX_CHUNK_BYTES + 1024:
            yield f"a chunk of {length} bytes at byte {offset} (at most {MAX_CHUNK_BYTES} are read)"
            return
        body = stream.read(length)
        try:
            records = _chunk_records(body)
            for _ in iter_records(records):  # every record of it whole
                pass
        except Malformed as error:
            yield f"damaged chunk at byte {offset}: {error}"
            return
        offset += 9 + length
        yield ScannedChunk(records, offset)


def parse_schema(body: _Cursor) -> Schema:
    """A Schema record's body."""
    return _schema(body)


def parse_channel(body: _Cursor) -> Channel:
    """A Channel record's body."""
    return _channel(body)


def parse_message(body: _Cursor) -> tuple[int, int, int, int, bytes]:
    """A Message record's body: ``(channel, sequence, log time, publish time, data)``."""
    channel, sequence, log_time, publish_time = body.u16(), body.u32(), body.u64(), body.u64()
    return channel, sequence, log_time, publish_time, bytes(body.buffer[body.pos : body.end])
