"""Behavior files changed outside the studio: a ``git checkout``, the user's own editor.

:class:`FileWatcher` polls the files of every behavior set's include closure (what its last
compile read, and its agents file; nothing else of the folders) and says which changed since it
last looked: their content, not their time stamps. Each pass costs one ``stat`` per file; a file
whose modification time, size or inode moved is read and hashed (its version,
:func:`xabsl_studio.server.session.files.version_of`), and only a new version is a change, so a
``touch`` or a rewrite of the same bytes reports nothing. The API polls every
:data:`POLL_SECONDS` and treats a change as a save from the studio (compile, hot reload, events).

Polling rather than ``watchfiles`` (inotify and friends): no new dependency, nothing that differs
between platforms or between a local disk and a network mount, and a closure of a few hundred
files costs well under a millisecond a pass; the half second it may take to notice is inside
the second the studio promises.

The studio's own writes are not reported back: the API calls :meth:`FileWatcher.note` after
each write, under the lock its scans run under, so a scan never sees a studio save as new.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from xabsl_studio.engine.files import read_regular
from xabsl_studio.server.session.files import MAX_FILE_BYTES, version_of

__all__ = ["POLL_SECONDS", "Change", "FileWatcher"]

#: How often the files are looked at (the studio notices a change within about this long).
POLL_SECONDS = 0.5

#: What a ``stat`` says of a file: modification time (ns), size, inode; None: no such file.
Signature = tuple[int, int, int] | None


@dataclass(frozen=True, slots=True)
class Change:
    """A watched file whose content changed on disk: its path as the API names it, its new version."""

    path: str
    #: None: the file is gone (deleted, or renamed away)
    version: str | None


def _signature(real: Path) -> Signature:
    try:
        st = os.stat(real)
    except OSError:
        return None
    return (st.st_mtime_ns, st.st_size, st.st_ino)


def _version(real: Path) -> str | None:
    try:
        return version_of(read_regular(real, MAX_FILE_BYTES))
    except OSError:  # gone, unreadable, too large, not a regular file: as good as gone
        return None


class FileWatcher:
    """The watched files of one studio and what their content was when last looked at.

    Args:
        root: the folder the API paths are relative to (the example's root).
    """

    def __init__(self, root: Path) -> None:
        self.root = root
        #: per API path: its location, the stat signature and the version last seen
        self._seen: dict[str, tuple[Path, Signature, str | None]] = {}

    @property
    def paths(self) -> list[str]:
        """The watched API paths, sorted."""
        return sorted(self._seen)

    def watch(self, paths: Iterable[str]) -> None:
        """Watch exactly ``paths`` (API paths); a path new here is taken as it is now, not as a change."""
        wanted = set(paths)
        for path in [p for p in self._seen if p not in wanted]:
            del self._seen[path]
        for path in wanted - self._seen.keys():
            self.note(path)

    def note(self, path: str) -> None:
        """``path`` is as the studio itself just left it (written, created, deleted): no change to report."""
        real = Path(os.path.normpath(self.root / path))
        signature = _signature(real)
        self._seen[path] = (real, signature, _version(real) if signature is not None else None)

    def scan(self) -> list[Change]:
        """The watched files whose content changed since they were last looked at."""
        changes: list[Change] = []
        for path, (real, before, version) in list(self._seen.items()):
            signature = _signature(real)
            if signature == before:
                continue
            now = _version(real) if signature is not None else None
            self._seen[path] = (real, signature, now)
            if now != version:
                changes.append(Change(path, now))
        return changes
