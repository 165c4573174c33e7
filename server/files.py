"""Behavior files: paths confined to the behavior folders, content versions, atomic writes.

A path in the API is relative to the example folder (``behavior/options/kick.xabsl``), the same
form compile diagnostics use. :meth:`BehaviorFiles.resolve` is the only way from such a path to
the disk and refuses, before touching anything: empty paths, NUL, backslashes, absolute paths
(and drive letters), ``.``/``..`` segments, hidden names, and any path whose *resolved* location
(symlinks followed) is not inside one of the behavior folders. Only ``.xabsl`` files are listed,
created or written, so the studio cannot be used to drop other kinds of files.

A file's ``version`` is a hash of its bytes: ``If-Match`` compares it under a lock, so two editors
saving the same file cannot overwrite each other silently (the second gets 409). Writes go
through ``engine.files.write_atomically`` (temp file, fsync, rename).
"""

from __future__ import annotations

import hashlib
import os
import threading
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from engine.errors import ServerError
from engine.files import write_atomically

SUFFIX = ".xabsl"


class FileError(ServerError):
    """A refused file operation; ``status`` is the HTTP status to answer with."""

    def __init__(self, status: int, message: str, **extra: Any) -> None:
        super().__init__(message)
        self.status = status
        self.message = message
        self.extra = extra


def version_of(data: bytes) -> str:
    """The version of a file's content (16 hex digits of SHA-256)."""
    return hashlib.sha256(data).hexdigest()[:16]


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
        if path.startswith("/") or (len(path) > 1 and path[1] == ":"):
            raise FileError(400, "bad path: absolute paths are not allowed")
        parts = tuple(path.split("/"))
        for part in parts:
            if part in ("", ".", ".."):
                raise FileError(400, "bad path: empty, '.' or '..' segments are not allowed")
            if part.startswith("."):
                raise FileError(400, "bad path: hidden names are not allowed")
        return parts

    def resolve(self, path: str, *, must_exist: bool = True, writable: bool = False) -> Path:
        """The real location of API path ``path``, confined to a behavior folder.

        Raises:
            FileError: 400 bad path, 403 outside the behavior folders, 404 missing.
        """
        self.check_syntax(path)
        if writable and not path.endswith(SUFFIX):
            raise FileError(400, f"only {SUFFIX} files can be written")
        candidate = self.root / path
        if must_exist:
            if not candidate.exists():
                raise FileError(404, f"no such file: {path}")
            real = candidate.resolve(strict=True)
            if not real.is_file():
                raise FileError(404, f"not a file: {path}")
        else:
            parent = candidate.parent
            if not parent.is_dir():
                raise FileError(404, f"no such folder: {Path(path).parent.as_posix()}")
            real = parent.resolve(strict=True) / candidate.name
            if real.is_symlink():
                real = real.resolve()
        if not any(real.is_relative_to(folder) for folder in self.folders):
            raise FileError(403, f"{path} is outside the behavior folders")
        return real

    def api_path(self, real: Path) -> str:
        """The API path of a real location inside the example."""
        return real.relative_to(self.root).as_posix()

    # -- operations ---------------------------------------------------------------------------------

    def list(self) -> list[dict[str, Any]]:
        """Every ``.xabsl`` file below the behavior folders: path, version, size."""
        found: dict[str, dict[str, Any]] = {}
        for folder in self.folders:
            for directory, subdirs, names in os.walk(folder):
                subdirs[:] = sorted(d for d in subdirs if not d.startswith("."))
                for name in sorted(names):
                    if name.startswith(".") or not name.endswith(SUFFIX):
                        continue
                    real = Path(directory, name)
                    try:
                        if not any(real.resolve().is_relative_to(f) for f in self.folders):
                            continue  # a symlink out of the folders is not listed (nor served)
                        data = real.read_bytes()
                    except OSError:
                        continue
                    path = self.api_path(real)
                    found[path] = {"path": path, "version": version_of(data), "size": len(data)}
        return [found[p] for p in sorted(found)]

    def read(self, path: str) -> tuple[str, str]:
        """``(text, version)`` of a file."""
        data = self.resolve(path).read_bytes()
        try:
            return data.decode("utf-8"), version_of(data)
        except UnicodeDecodeError:
            raise FileError(415, f"{path} is not UTF-8 text") from None

    def write(self, path: str, text: str, if_match: str | None) -> str:
        """Replace an existing file if its version is ``if_match``; returns the new version.

        Raises:
            FileError: 428 without a version, 409 when the file changed since that version.
        """
        real = self.resolve(path, writable=True)
        if if_match is None:
            raise FileError(428, "If-Match (the version you edited) is required to overwrite a file")
        data = text.encode("utf-8")
        with self._lock:
            current = version_of(real.read_bytes())
            if current != if_match:
                raise FileError(409, f"{path} changed since version {if_match}", version=current)
            write_atomically(real, data)
        return version_of(data)

    def create(self, path: str, text: str) -> str:
        """Create a new file (409 if it exists); returns its version."""
        real = self.resolve(path, must_exist=False, writable=True)
        data = text.encode("utf-8")
        with self._lock:
            if real.exists() or (self.root / path).is_symlink():
                raise FileError(409, f"{path} exists already")
            write_atomically(real, data)
        return version_of(data)

    def delete(self, path: str, if_match: str | None) -> None:
        real = self.resolve(path, writable=True)
        with self._lock:
            if if_match is not None:
                current = version_of(real.read_bytes())
                if current != if_match:
                    raise FileError(409, f"{path} changed since version {if_match}", version=current)
            real.unlink()

    def rename(self, path: str, new_path: str, if_match: str | None) -> str:
        """Move a file to ``new_path`` (409 if that exists); returns the file's version."""
        real = self.resolve(path, writable=True)
        target = self.resolve(new_path, must_exist=False, writable=True)
        with self._lock:
            data = real.read_bytes()
            current = version_of(data)
            if if_match is not None and current != if_match:
                raise FileError(409, f"{path} changed since version {if_match}", version=current)
            if target.exists():
                raise FileError(409, f"{new_path} exists already")
            os.rename(real, target)
        return current
