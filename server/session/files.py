"""Behavior files: paths confined to the behavior folders, content versions, atomic writes.

A path in the API is relative to the example folder (``behavior/options/kick.xabsl``), the same
form compile diagnostics use. :meth:`BehaviorFiles.resolve` is the only way from such a path to
the disk and refuses, before touching anything: empty paths, NUL, backslashes, absolute paths
(and drive letters), ``.``/``..`` segments, hidden names, and any path whose *resolved* location
(symlinks followed) is not inside one of the behavior folders. Only ``.xabsl`` files are listed,
created or written, so the studio cannot be used to drop other kinds of files.

Names are checked before any system call: a segment over 255 bytes (UTF-8) or a path over
4,096 bytes is a 400, never an ``OSError``. A name the studio *creates* (a new file, a rename's
target) must also be visible (:meth:`BehaviorFiles.check_new_name`, :data:`INVISIBLE`): no
control, invisible format (zero-width, bidi override), line or paragraph separator characters,
no space other than U+0020, and no blank, leading or trailing spaces. A ``:`` is an ordinary
character (``a:b.xabsl``), but a first name that is a drive (``C:/...``) is an absolute path;
on Windows, where ``C:name`` and ``name:stream`` mean a drive and a stream, a colon is refused
everywhere. Only regular files are listed, read or written (a FIFO named ``*.xabsl`` would
otherwise block the listing for ever), each at most :data:`MAX_FILE_BYTES`.

Files are kept as they are: the text is returned exactly as stored (CR, CRLF and LF line ends
untouched), decoded as UTF-8 or, when that fails, as latin-1; a save encodes with the encoding
the file has on disk, so an unchanged save writes the same bytes. Text that the file's encoding
cannot hold (a lone surrogate; a character beyond latin-1 in a latin-1 file) is a 400 (not 422,
which a save answers when the saved file does not compile).

A file's ``version`` is a hash of its bytes: ``If-Match`` compares it under a lock, so two editors
saving the same file cannot overwrite each other silently (the second gets 409). Writes go
through ``xabsl_studio.engine.files.write_atomically`` (temp file, fsync, rename).
"""

from __future__ import annotations

import errno
import hashlib
import os
import re
import threading
import unicodedata
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from xabsl_studio.engine.files import FileTooLarge, NotRegularFile, read_regular, write_atomically
from xabsl_studio.server.protocol.errors import ServerError
from xabsl_studio.server.protocol.rest import INVISIBLE, FileStat

SUFFIX = ".xabsl"
#: The largest behavior file listed or opened (a real option file is a few kilobytes).
MAX_FILE_BYTES = 16 * 1024 * 1024
#: A first name that is a drive (``C:``, ``C:/...``): absolute on Windows, and meant so elsewhere.
_DRIVE = re.compile(r"^[A-Za-z]:(/|$)")
_INVISIBLE = re.compile(f"[{INVISIBLE}]")
#: Longest name segment and path, in bytes of UTF-8 (the usual NAME_MAX and PATH_MAX).
MAX_NAME_BYTES = 255
MAX_PATH_BYTES = 4096


class FileError(ServerError):
    """A refused file operation; ``status`` is the HTTP status to answer with."""

    def __init__(self, status: int, message: str, **extra: Any) -> None:
        super().__init__(message)
        self.status = status
        self.message = message
        self.extra = extra


def decode(data: bytes) -> tuple[str, str]:
    """``(text, encoding)`` of a file's bytes: UTF-8 when they are, else latin-1 (never fails)."""
    try:
        return data.decode("utf-8"), "utf-8"
    except UnicodeDecodeError:
        return data.decode("latin-1"), "latin-1"


def encode(text: str, encoding: str, path: str) -> bytes:
    """``text`` in ``encoding``, or FileError(400) naming the first character it cannot hold."""
    try:
        return text.encode(encoding)
    except UnicodeEncodeError as error:
        char = text[error.start]
        line = text.count("\n", 0, error.start) + 1
        if 0xD800 <= ord(char) <= 0xDFFF:
            why = f"a lone surrogate U+{ord(char):04X} (not valid Unicode)"
        else:
            why = f"U+{ord(char):04X} {char!r}, which {path} ({encoding}) cannot hold"
        raise FileError(400, f"cannot save {path}: line {line} has {why}") from None


def version_of(data: bytes) -> str:
    """The version of a file's content (16 hex digits of SHA-256)."""
    return hashlib.sha256(data).hexdigest()[:16]


@contextmanager
def _os_errors(path: str) -> Iterator[None]:
    """A failed write, rename or unlink as a FileError (403 not permitted, else 409), never a 500."""
    try:
        yield
    except OSError as error:
        status = 403 if error.errno in (errno.EACCES, errno.EPERM, errno.EROFS) else 409
        raise FileError(status, f"cannot change {path}: {error.strerror or error}") from None


class BehaviorFiles:
    """The behavior files of one example (see the module docstring).

    Args:
        root: the example folder (API paths are relative to it).
        folders: the behavior folders inside it that files may live in.
    """

    def __init__(self, root: Path, folders: Iterable[Path]) -> None:
        self.root = root.resolve()
        self.folders = tuple(sorted({f.resolve() for f in folders}))
        self._lock = threading.Lock()

    # -- paths ---------------------------------------------------------------------------------

    def check_syntax(self, path: str) -> tuple[str, ...]:
        """The segments of an API path, or FileError(400) for a path that can never be valid."""
        if not path or "\x00" in path or "\\" in path:
            raise FileError(400, "bad path: empty, NUL or backslash")
        if path.startswith("/") or _DRIVE.match(path):
            raise FileError(400, "bad path: absolute paths are not allowed")
        if os.name == "nt" and ":" in path:  # C:name, name:stream
            raise FileError(400, "bad path: ':' names a drive or a stream on Windows")
        try:
            size = len(path.encode("utf-8"))
        except UnicodeEncodeError:
            raise FileError(400, "bad path: not valid Unicode (a lone surrogate)") from None
        if size > MAX_PATH_BYTES:
            raise FileError(400, f"bad path: over {MAX_PATH_BYTES} bytes")
        parts = tuple(path.split("/"))
        for part in parts:
            if len(part.encode("utf-8")) > MAX_NAME_BYTES:
                raise FileError(400, f"bad path: a name over {MAX_NAME_BYTES} bytes")
            if part in ("", ".", ".."):
                raise FileError(400, "bad path: empty, '.' or '..' segments are not allowed")
            if part.startswith("."):
                raise FileError(400, "bad path: hidden names are not allowed")
        return parts

    def check_new_name(self, path: str) -> None:
        """FileError(400) unless the file name of ``path`` shows as what it is (see the module docstring).

        Only the last name: the folders exist already (the studio creates none).
        """
        part = self.check_syntax(path)[-1]
        stem = part.removesuffix(SUFFIX)
        if not stem.strip():
            raise FileError(400, f"bad file name {part!r}: blank")
        if stem != stem.strip(" "):
            raise FileError(400, f"bad file name {part!r}: it starts or ends with a space")
        hidden = _INVISIBLE.search(part)
        if hidden is not None:
            char = hidden.group()
            name = unicodedata.name(char, "a control character")
            raise FileError(400, f"bad file name {part!r}: U+{ord(char):04X} ({name}) does not show as itself")

    def resolve(self, path: str, *, must_exist: bool = True, writable: bool = False) -> Path:
        """The real location of API path ``path``, confined to a behavior folder.

        Raises:
            FileError: 400 bad path, 403 outside the behavior folders, 404 missing.
        """
        self.check_syntax(path)
        try:
            return self._resolve(path, must_exist, writable)
        except OSError as error:  # ELOOP, EACCES...: the path cannot name a file we may use
            raise FileError(400, f"bad path: {error.strerror or error}") from None

    def _resolve(self, path: str, must_exist: bool, writable: bool) -> Path:
        if writable and not path.endswith(SUFFIX):
            raise FileError(400, f"only {SUFFIX} files can be written")
        candidate = self.root / path
        if must_exist:
            if not candidate.exists():
                raise FileError(404, f"no such file: {path}")
            real = Path(os.path.realpath(candidate, strict=True))
            if not real.is_file():
                raise FileError(404, f"not a file: {path}")
        else:
            parent = candidate.parent
            if not parent.is_dir():
                raise FileError(404, f"no such folder: {Path(path).parent.as_posix()}")
            real = Path(os.path.realpath(parent, strict=True)) / candidate.name
            if real.is_symlink():  # a link to a new name, a dangling link or a loop
                real = Path(os.path.realpath(real))
        if not any(real.is_relative_to(folder) for folder in self.folders):
            raise FileError(403, f"{path} is outside the behavior folders")
        return real

    def api_path(self, real: Path) -> str:
        """The API path of a real location inside the example."""
        return real.relative_to(self.root).as_posix()

    # -- operations ---------------------------------------------------------------------------------

    def list(self) -> list[FileStat]:
        """Every ``.xabsl`` file below the behavior folders: path, version, size."""
        found: dict[str, FileStat] = {}
        for folder in self.folders:
            for directory, subdirs, names in os.walk(folder):
                subdirs[:] = sorted(d for d in subdirs if not d.startswith("."))
                for name in sorted(names):
                    if name.startswith(".") or not name.endswith(SUFFIX):
                        continue
                    real = Path(directory, name)
                    try:
                        if not any(Path(os.path.realpath(real)).is_relative_to(f) for f in self.folders):
                            continue  # a symlink out of the folders is not listed (nor served)
                        data = read_regular(real, MAX_FILE_BYTES)
                    except OSError:
                        continue  # not a regular file (a FIFO, a device), too large, unreadable
                    path = self.api_path(real)
                    found[path] = {"path": path, "version": version_of(data), "size": len(data)}
        return [found[p] for p in sorted(found)]

    def _bytes(self, real: Path, path: str) -> bytes:
        """The content of a resolved file: a regular file of at most MAX_FILE_BYTES (else 404/413)."""
        try:
            return read_regular(real, MAX_FILE_BYTES)
        except FileTooLarge:
            raise FileError(413, f"{path} is over {MAX_FILE_BYTES} bytes") from None
        except NotRegularFile:
            raise FileError(404, f"not a file: {path}") from None
        except FileNotFoundError:
            raise FileError(404, f"no such file: {path}") from None

    def read(self, path: str) -> tuple[str, str]:
        """``(text, version)`` of a file: its exact text (UTF-8, else latin-1), line ends untouched."""
        data = self._bytes(self.resolve(path), path)
        return decode(data)[0], version_of(data)

    def write(self, path: str, text: str, if_match: str | None) -> str:
        """Replace an existing file if its version is ``if_match``; returns the new version.

        Raises:
            FileError: 428 without a version, 409 when the file changed since that version.
        """
        real = self.resolve(path, writable=True)
        if if_match is None:
            raise FileError(428, "If-Match (the version you edited) is required to overwrite a file")
        with self._lock:
            old = self._bytes(real, path)
            current = version_of(old)
            if current != if_match:
                raise FileError(409, f"{path} changed since version {if_match}", version=current)
            data = encode(text, decode(old)[1], path)
            with _os_errors(path):
                write_atomically(real, data)
        return version_of(data)

    def create(self, path: str, text: str) -> str:
        """Create a new file (409 if it exists); returns its version."""
        self.check_new_name(path)
        real = self.resolve(path, must_exist=False, writable=True)
        data = encode(text, "utf-8", path)
        with self._lock:
            if os.path.lexists(real) or (self.root / path).is_symlink():
                raise FileError(409, f"{path} exists already")
            with _os_errors(path):
                write_atomically(real, data)
        return version_of(data)

    def delete(self, path: str, if_match: str | None) -> None:
        """Delete a file (if ``if_match`` is given, only at that version, else 409)."""
        real = self.resolve(path, writable=True)
        with self._lock:
            if if_match is not None:
                current = version_of(self._bytes(real, path))
                if current != if_match:
                    raise FileError(409, f"{path} changed since version {if_match}", version=current)
            with _os_errors(path):
                real.unlink()

    def rename(self, path: str, new_path: str, if_match: str | None) -> str:
        """Move a file to ``new_path`` (409 if that exists); returns the file's version."""
        real = self.resolve(path, writable=True)
        self.check_new_name(new_path)
        target = self.resolve(new_path, must_exist=False, writable=True)
        with self._lock:
            current = version_of(self._bytes(real, path))
            if if_match is not None and current != if_match:
                raise FileError(409, f"{path} changed since version {if_match}", version=current)
            if os.path.lexists(target) or (self.root / new_path).is_symlink():
                raise FileError(409, f"{new_path} exists already")
            with _os_errors(new_path):
                os.rename(real, target)
        return current
