"""Recordings that survive their writer: a cut ``FILE.mcap.part`` made a readable ``FILE.mcap`` again.

A recording is written to ``FILE.mcap.part`` and renamed when it closes
(:class:`~xabsl_studio.engine.record.encoder.RecordingEncoder`); a writer killed (``kill -9``, a crash,
a power cut) or stopped by a full disk leaves the ``.part``: chunks written so far, then perhaps half
a chunk, no summary. :func:`recover` reads its data section front to back
(:func:`~xabsl_studio.engine.record.mcapread.scan_chunks`: every chunk whole, decompressing to its
size, matching its CRC), keeps every message of the complete chunks up to the last complete tick,
and writes them as a finished recording (summary, indexes) to ``FILE.mcap``, atomically; its header
gains ``"cut"``: why the file ended and how many bytes were kept. Then the ``.part`` goes.

A tick is complete when a message of a later tick follows it in the complete chunks (the encoder
writes a tick's messages together, agents first): the last tick seen may lack its status or scene,
so it is dropped. A ``.part`` with no complete tick, or that is not an MCAP file, stays as it is
(:class:`RecoveryFailed` says why; the studio lists it with that reason).

A writer holds an exclusive ``flock`` on its ``.part`` while it writes (released by the kernel when
it dies), so a studio recovers only files nobody writes; two studios sharing a folder never take
each other's open recording.
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import orjson

from xabsl_studio.engine.record import schema as S
from xabsl_studio.engine.record.mcapfile import McapWriter
from xabsl_studio.engine.record.mcapread import (
    Malformed,
    RecordingError,
    ScannedChunk,
    iter_records,
    open_regular,
    parse_channel,
    parse_message,
    parse_schema,
    scan_chunks,
)

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: no lock, recovery only on request
    fcntl = None  # type: ignore[assignment]

__all__ = ["PART", "Recovered", "RecoveryFailed", "in_use", "lock_part", "recover", "recover_folder"]

log = logging.getLogger("xabsl.record")

#: The suffix of a recording being written (or cut).
PART = ".part"

_SCHEMA, _CHANNEL, _MESSAGE = 0x03, 0x04, 0x05


class RecoveryFailed(RecordingError):
    """A ``.part`` file that cannot be recovered (in use, not MCAP, no complete tick, no space)."""


@dataclass(frozen=True, slots=True)
class Recovered:
    """What :func:`recover` made of a ``.part`` file."""

    part: Path
    path: Path
    ticks: int
    cut: dict[str, Any]


def lock_part(stream: BinaryIO, wait: bool = False) -> None:
    """Take the writer's exclusive lock on an open ``.part`` (no-op without ``fcntl``).

    ``wait``: until it is free (a writer creating its file waits out a studio that looked at it
    that very moment; an old file is never a new writer's, their names are never reused).

    Raises:
        OSError: another open file holds it (without ``wait``).
    """
    if fcntl is not None:
        fcntl.flock(stream.fileno(), fcntl.LOCK_EX if wait else fcntl.LOCK_EX | fcntl.LOCK_NB)


def in_use(part: Path) -> bool:
    """Whether a live writer holds ``part`` (False if it cannot be opened)."""
    try:
        with open_regular(str(part)) as stream:
            lock_part(stream)
    except BlockingIOError:
        return True
    except (OSError, RecordingError):
        return False
    return False


def _target(part: Path) -> Path:
    base = part.name.removesuffix(PART)
    path = part.with_name(base)
    stem = base.removesuffix(".mcap")
    n = 1
    while path.exists():  # a file of that name is there already: keep both
        path = part.with_name(f"{stem}-recovered{'' if n == 1 else f'-{n}'}.mcap")
        n += 1
    return path


def _fail(part: Path, reason: str) -> RecoveryFailed:
    return RecoveryFailed(f"{part}: {reason}", path=str(part), reason=reason)


def recover(part: str | os.PathLike[str]) -> Recovered:
    """Recover the cut recording ``part`` (``FILE.mcap.part``) to ``FILE.mcap`` (see the module docstring).

    Raises:
        RecoveryFailed: a writer holds it, it is not a cut recording, no tick in it is complete,
            or the recovered file cannot be written (the ``.part`` stays).
    """
    part = Path(part)
    if not part.name.endswith(".mcap" + PART):
        raise _fail(part, "not a cut recording (its name does not end in .mcap.part)")
    try:
        stream = open_regular(str(part))
    except OSError as error:
        raise _fail(part, f"cannot be read: {error.strerror or error}") from None
    except RecordingError as error:
        raise _fail(part, error.reason or str(error)) from None
    with stream:
        try:
            lock_part(stream)
        except OSError:
            raise _fail(part, "a running recorder is writing it") from None
        size = os.fstat(stream.fileno()).st_size
        try:
            last_time, kept, reason = _extent(stream, size)
        except Malformed as error:
            raise _fail(part, f"not an MCAP file ({error})") from None
        if last_time is None:
            raise _fail(part, f"no complete tick in it ({reason})")
        cut = {"reason": reason, "file_bytes": size, "kept_bytes": kept}
        target = _target(part)
        temp = target.with_name(target.name + ".recovering")
        try:
            ticks = _rewrite(stream, size, last_time, cut, temp)
            if ticks == 0:
                raise _fail(part, f"no complete tick in it ({reason})")
            _check_readable(temp)
            os.replace(temp, target)
            _sync_folder(target.parent)
        except OSError as error:
            with contextlib.suppress(OSError):
                temp.unlink()
            raise _fail(part, f"cannot write {target.name}: {error.strerror or error}") from None
        except Malformed as error:  # a schema or channel record that does not parse
            with contextlib.suppress(OSError):
                temp.unlink()
            raise _fail(part, f"not a recording ({error})") from None
        except RecordingError as error:  # what was written does not read back as a recording
            with contextlib.suppress(OSError):
                temp.unlink()
            raise _fail(part, error.reason or str(error)) from None
        part.unlink()  # (still locked: no writer can have reopened it)
    log.info("recovered %s: %d ticks in %s (%s)", part, ticks, target, reason)
    return Recovered(part, target, ticks, cut)


def _chunks(stream: BinaryIO, size: int) -> Iterator[ScannedChunk | str]:
    return scan_chunks(stream, size)


def _extent(stream: BinaryIO, size: int) -> tuple[int | None, int, str]:
    """``(log time of the first tick not kept, bytes of the complete chunks, why the scan stopped)``.

    The first value is the latest log time in the complete chunks (messages before it form
    complete ticks); None when no message is later than the first one (no complete tick).
    """
    first: int | None = None
    latest: int | None = None
    kept = 8
    reason = "complete"
    for item in _chunks(stream, size):
        if isinstance(item, str):
            reason = item
            break
        kept = item.end
        for opcode, body in iter_records(item.records):
            if opcode == _MESSAGE:
                _channel, _sequence, log_time, _publish, _data = parse_message(body)
                first = log_time if first is None else min(first, log_time)
                latest = log_time if latest is None else max(latest, log_time)
    if latest is None or first is None or latest <= first:
        return None, kept, reason
    return latest, kept, reason


def _rewrite(stream: BinaryIO, size: int, before: int, cut: dict[str, Any], temp: Path) -> int:
    """Write the messages logged before ``before`` of the complete chunks to ``temp``; the ticks written."""
    schemas: dict[int, int] = {}
    channels: dict[int, int] = {}
    topics: dict[int, str] = {}
    ticks = 0
    header_done = False
    with open(temp, "wb") as out:
        writer = McapWriter(out)
        writer.start(profile=S.PROFILE, library="xabsl-studio (recovered)")
        for item in _chunks(stream, size):
            if isinstance(item, str):
                break
            for opcode, body in iter_records(item.records):
                if opcode == _SCHEMA:
                    schema = parse_schema(body)
                    if schema.id not in schemas:
                        schemas[schema.id] = writer.register_schema(schema.name, schema.encoding, schema.data)
                elif opcode == _CHANNEL:
                    channel = parse_channel(body)
                    if channel.id not in channels:
                        channels[channel.id] = writer.register_channel(
                            channel.topic, channel.message_encoding, schemas.get(channel.schema_id, 0), channel.metadata
                        )
                        topics[channel.id] = channel.topic
                elif opcode == _MESSAGE:
                    ident, sequence, log_time, publish_time, data = parse_message(body)
                    if log_time >= before or ident not in channels:
                        continue
                    topic = topics[ident]
                    if topic == S.RECORDING and not header_done:
                        data = _mark_cut(data, cut)
                        header_done = True
                    elif topic == S.WORLD_SCENE:
                        ticks += 1
                    writer.add_message(channels[ident], log_time, data, publish_time, sequence)
        writer.finish()
        out.flush()
        os.fsync(out.fileno())
    return ticks


def _mark_cut(data: bytes, cut: dict[str, Any]) -> bytes:
    try:
        header = orjson.loads(data)
    except orjson.JSONDecodeError:
        return data  # not a header the reader takes anyway: it says so when the file is opened
    if isinstance(header, dict):
        header["cut"] = cut
        return orjson.dumps(header)
    return data


def _check_readable(path: Path) -> None:
    from xabsl_studio.engine.record.reader import Recording

    with Recording(path) as recording:
        if len(recording):
            recording.tick(recording.end - 1)


def _sync_folder(folder: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def recover_folder(folder: str | os.PathLike[str]) -> tuple[list[Recovered], list[RecoveryFailed]]:
    """Recover every cut recording in ``folder`` nobody writes; what was recovered and what was not."""
    done: list[Recovered] = []
    failed: list[RecoveryFailed] = []
    for part in sorted(Path(folder).glob("*.mcap" + PART)):
        if in_use(part):
            continue
        try:
            done.append(recover(part))
        except RecoveryFailed as error:
            log.warning("cannot recover %s", error)
            failed.append(error)
    return done, failed
