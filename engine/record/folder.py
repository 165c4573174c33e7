"""Where recordings live unless told otherwise, how they are named, and the cap on their folder.

Every run that records without being given a file (the studio's live session, an attached
session, ``xabsl run``) writes into the cache, in a sub-folder per behavior set
(:func:`default_folder`), under a name that sorts in time order and is never used twice
(:func:`new_recording`). After a file is finished, :func:`prune` deletes the oldest files of its
folder while the folder holds more than its cap; never the file just finished. The studio lists
the same folder for the same behavior sets, so a headless run's recording is one click away.
"""

from __future__ import annotations

import hashlib
import os
import re
import time
from collections.abc import Iterable
from pathlib import Path

__all__ = ["DEFAULT_CAP_BYTES", "cache_folder", "default_folder", "new_recording", "prune"]

#: A recordings folder's size cap by default.
DEFAULT_CAP_BYTES = 2_000_000_000


def cache_folder() -> Path:
    """``$XDG_CACHE_HOME/xabsl-studio/recordings`` (``~/.cache`` without XDG_CACHE_HOME)."""
    cache = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(cache) / "xabsl-studio" / "recordings"


def default_folder(agents_files: Iterable[Path] = ()) -> Path:
    """The record folder of the behavior sets of ``agents_files``: their own sub-folder of the cache.

    One folder shared by every behavior set made each studio list every other set's recordings.
    The sub-folder is keyed by the resolved paths of the agents files (a hash: stable, whatever
    the names hold), with the first one's folder name in front for people looking at the cache:
    ``~/.cache/xabsl-studio/recordings/behavior-3f2a9c01b7d4``. Without agents files: the cache.
    """
    paths = sorted(str(Path(p).expanduser().resolve()) for p in agents_files)
    if not paths:
        return cache_folder()
    digest = hashlib.sha256("\n".join(paths).encode("utf-8", "surrogateescape")).hexdigest()[:12]
    label = re.sub(r"[^A-Za-z0-9_.-]+", "_", Path(paths[0]).parent.name).strip("._")[:40] or "set"
    return cache_folder() / f"{label}-{digest}"


def new_recording(folder: Path, name: str, n: int = 1) -> Path:
    """A free path ``folder/NAME-YYYYmmdd-HHMMSS-NNN.mcap``, counting on from ``n``.

    Names sort in time order; the count goes on past names in use (also by a ``.part`` file a
    killed run left), so a name is never used twice within a second.
    """
    stamp = time.strftime("%Y%m%d-%H%M%S")
    stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("._") or "session"
    path = folder / f"{stem}-{stamp}-{n:03d}.mcap"
    while path.exists() or path.with_name(path.name + ".part").exists():
        n += 1
        path = folder / f"{stem}-{stamp}-{n:03d}.mcap"
    return path


def prune(folder: Path, cap_bytes: int) -> list[Path]:
    """Delete the oldest recordings while ``folder`` holds more than ``cap_bytes``; never the newest.

    Oldest by name (they sort in time order; modification times of files closed within one
    second do not), and the newest file stays even when it alone is over the cap. Returns the
    deleted files.
    """
    files = sorted(folder.glob("*.mcap"), key=lambda p: p.name)
    sizes: dict[Path, int] = {}
    for path in files:
        try:
            sizes[path] = path.stat().st_size
        except OSError:  # removed meanwhile (another run pruning the same folder)
            sizes[path] = 0
    total = sum(sizes.values())
    deleted: list[Path] = []
    while len(files) > 1 and total > cap_bytes:
        oldest = files.pop(0)
        total -= sizes[oldest]
        oldest.unlink(missing_ok=True)
        deleted.append(oldest)
    return deleted
