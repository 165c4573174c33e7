"""Reading NaoTH game logs: a file of records ``int32 frameNumber, NUL-terminated name, int32 size, bytes``.

A NaoTH robot's ``GameLogger`` (and LogSimulator, which replays such a file) writes one record
per representation and frame, little-endian: the frame number, the representation's name ended
by a NUL byte, the payload size, the serialized protobuf. A log carries ``FrameInfo`` per frame,
``BehaviorStateComplete`` whenever the behavior was (re)loaded and ``BehaviorStateSparse`` per
frame; other representations (images, percepts) are passed over unread.

:func:`read_records` yields records as they are; :func:`frames` groups them into
:class:`LogFrame` (a frame's records are consecutive). Every bound is checked: a name longer
than :data:`MAX_NAME` bytes or a payload over :data:`MAX_RECORD` bytes is a :class:`LogError`
naming the byte offset; a log cut off in its last record (a robot switched off while writing)
ends at the last whole record, and :attr:`LogReader.truncated` says where.
"""

from __future__ import annotations

import os
import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO

from xabsl_studio.engine.errors import HostError

__all__ = ["MAX_NAME", "MAX_RECORD", "LogError", "LogFrame", "LogReader", "Record"]

#: Longest representation name read (NaoTH's are under 40 bytes).
MAX_NAME = 256
#: Largest payload read (a camera image is about 600 KB).
MAX_RECORD = 64 * 1024 * 1024
_INT = struct.Struct("<i")


class LogError(HostError, ValueError):
    """A file that is not a NaoTH game log (the message names the byte offset)."""


@dataclass(frozen=True, slots=True)
class Record:
    """One record of a log: where it starts, its frame, its representation's name, its payload."""

    offset: int
    frame: int
    name: str
    data: bytes


@dataclass(slots=True)
class LogFrame:
    """The records of one frame, by representation name (the last one if a name repeats)."""

    number: int
    records: dict[str, bytes] = field(default_factory=dict)


class LogReader:
    """The records of a log file, read once from the start (see the module docstring).

    Args:
        path: the log file.
        wanted: names whose payloads are read (None: every name); others are skipped unread.
    """

    def __init__(self, path: str | Path, wanted: frozenset[str] | None = None) -> None:
        self.path = Path(path)
        self.wanted = wanted
        #: the byte offset of an incomplete last record (None: the log ends with a whole record)
        self.truncated: int | None = None
        self.records = 0

    def __iter__(self) -> Iterator[Record]:
        with open(self.path, "rb") as stream:
            yield from self._read(stream, os.fstat(stream.fileno()).st_size)

    def _read(self, stream: BinaryIO, total: int) -> Iterator[Record]:
        offset = 0
        while True:
            head = stream.read(4)
            if not head:
                return
            if len(head) < 4:
                self.truncated = offset
                return
            (frame,) = _INT.unpack(head)
            name_bytes = bytearray()
            while True:
                byte = stream.read(1)
                if not byte:
                    self.truncated = offset
                    return
                if byte == b"\0":
                    break
                name_bytes += byte
                if len(name_bytes) > MAX_NAME:
                    raise LogError(
                        f"{self.path}: byte {offset}: a record name longer than {MAX_NAME} bytes: not a game log"
                    )
            try:
                name = name_bytes.decode("ascii")
            except UnicodeDecodeError:
                raise LogError(f"{self.path}: byte {offset}: a record name that is not ASCII: not a game log") from None
            size_bytes = stream.read(4)
            if len(size_bytes) < 4:
                self.truncated = offset
                return
            (size,) = _INT.unpack(size_bytes)
            if not 0 <= size <= MAX_RECORD:
                raise LogError(f"{self.path}: byte {offset}: record {name!r} of {size} bytes (at most {MAX_RECORD})")
            if self.wanted is not None and name not in self.wanted:
                if stream.seek(size, 1) > total:
                    self.truncated = offset
                    return
                data = b""
            else:
                data = stream.read(size)
                if len(data) < size:
                    self.truncated = offset
                    return
            self.records += 1
            yield Record(offset, frame, name, data)
            offset = stream.tell()

    def frames(self) -> Iterator[LogFrame]:
        """The log's frames in file order (consecutive records of one frame number make a frame)."""
        current: LogFrame | None = None
        for record in self:
            if current is None or record.frame != current.number:
                if current is not None:
                    yield current
                current = LogFrame(record.frame)
            if self.wanted is None or record.name in self.wanted:
                current.records[record.name] = record.data
        if current is not None:
            yield current
