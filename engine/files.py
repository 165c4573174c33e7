"""Files the tools read and write: atomic writes that keep what is at the path, bounded reads.

Writes go to a temp file next to the target, are fsynced, then renamed over it: a reader (the
studio, a robot's loader) never sees a half-written file, and a crash leaves either the old or
the new content. A symlink is written *through* (its target is replaced, the link stays), and a
path that is neither a regular file nor a new name (a device such as ``/dev/full``, a FIFO, a
folder) is refused, so not even root replaces a device node with a regular file.

Reads of inputs (PDDL, models, traces, behavior files) take only regular files, opened without
blocking (a FIFO would otherwise hang the reader) and at most a given size (``/dev/zero`` or a
runaway file would otherwise exhaust memory).
"""

from __future__ import annotations

import errno
import os
import stat
import tempfile

from xabsl_studio.engine.errors import XabslError

#: Default bound for one input file read with :func:`read_regular`.
MAX_INPUT_BYTES = 64 * 1024 * 1024


class NotRegularFile(XabslError, OSError):
    """The path names a device, FIFO, socket or folder where a regular file is needed.

    An ``OSError`` too, so callers that report I/O problems report this one the same way.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        super().__init__(errno.EINVAL, "not a regular file", os.fspath(path))


class FileTooLarge(XabslError, OSError):
    """An input file over the size limit of its reader."""

    def __init__(self, path: str | os.PathLike[str], limit: int) -> None:
        super().__init__(errno.EFBIG, f"larger than {limit} bytes", os.fspath(path))


def read_regular(path: str | os.PathLike[str], limit: int = MAX_INPUT_BYTES) -> bytes:
    """The bytes of the regular file at ``path`` (symlinks followed), at most ``limit`` of them.

    Raises:
        NotRegularFile: a device, FIFO, socket or folder.
        FileTooLarge: more than ``limit`` bytes.
        OSError: the path cannot be opened (missing, no permission, name too long...).
    """
    fd = _open_regular(path, limit)
    try:
        chunks: list[bytes] = []
        size = 0
        while True:
            chunk = os.read(fd, min(1 << 20, limit + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
            if size > limit:  # the file grew while being read
                raise FileTooLarge(path, limit)
        return b"".join(chunks)
    finally:
        os.close(fd)


def check_regular(path: str | os.PathLike[str], limit: int | None = None) -> int:
    """The size of the regular file at ``path`` (symlinks followed), checked without reading it.

    For a reader that opens the file itself (a recording's MCAP reader): a FIFO, device or folder
    is refused here, before that reader could block on it or read without end.

    Raises:
        NotRegularFile: a device, FIFO, socket or folder.
        FileTooLarge: more than ``limit`` bytes (when given).
        OSError: the path cannot be opened.
    """
    fd = _open_regular(path, limit)
    try:
        return os.fstat(fd).st_size
    finally:
        os.close(fd)


def _open_regular(path: str | os.PathLike[str], limit: int | None) -> int:
    """A descriptor of the regular file at ``path``, at most ``limit`` bytes large (else raises)."""
    # O_NONBLOCK: opening a FIFO for reading returns at once instead of waiting for a writer;
    # the kind is then checked on the open descriptor, so a swap after a stat cannot slip by.
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise NotRegularFile(path)
        if limit is not None and info.st_size > limit:
            raise FileTooLarge(path, limit)
    except BaseException:
        os.close(fd)
        raise
    return fd


def resolve_output(path: str | os.PathLike[str]) -> str:
    """Where a write to ``path`` lands: the final target of a symlink chain, else ``path``.

    Raises:
        NotRegularFile: something other than a regular file is there.
    """
    target = os.path.realpath(os.fspath(path)) if os.path.islink(path) else os.path.abspath(path)
    try:
        info = os.stat(target)
    except FileNotFoundError:
        return target  # a new name (or a dangling link's target): created
    if not stat.S_ISREG(info.st_mode):
        raise NotRegularFile(path)
    return target


def write_atomically(path: str | os.PathLike[str], data: bytes) -> None:
    """Replace the file at ``path`` with ``data`` atomically; keeps its permission bits.

    A symlink is written through to its target; a device, FIFO or folder is refused.

    Raises:
        NotRegularFile: ``path`` is not a regular file nor a new name.
        OSError: the folder is not writable, the disk is full...
    """
    target = resolve_output(path)
    folder = os.path.dirname(target)
    fd, temp = tempfile.mkstemp(prefix=".", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        try:
            os.chmod(temp, os.stat(target).st_mode & 0o7777)
        except FileNotFoundError:
            os.chmod(temp, 0o644)
        os.replace(temp, target)
    except BaseException:
        if os.path.exists(temp):
            os.unlink(temp)
        raise
    try:
        dir_fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(dir_fd)
    finally:
        os.close(dir_fd)
