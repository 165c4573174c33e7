"""The recording flags of ``xabsl run``, shared by every example: a run records unless told not to.

``--record FILE.mcap`` records into that file; without it the run records into a new file of the
behaviors' own recordings folder in the cache (``xabsl_studio.engine.record.folder``: the folder
the studio lists for the same behaviors), whose oldest files go once it holds more than
``--record-cap-mb``; ``--no-record`` records nothing.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from xabsl_studio.engine.cli import UsageError
from xabsl_studio.engine.record.folder import DEFAULT_CAP_BYTES, default_folder, new_recording, prune

__all__ = ["RecordTarget", "add_arguments", "target"]


def add_arguments(parser: argparse.ArgumentParser, what: str = "run") -> None:
    """``--record``, ``--no-record`` and ``--record-cap-mb`` on ``parser`` (``what``: "match", "run")."""
    parser.add_argument(
        "--record",
        metavar="FILE.mcap",
        help=f"record every tick of the {what} to this MCAP file (default: a new file in the behaviors' "
        "recordings folder in the cache, the one the studio lists)",
    )
    parser.add_argument("--no-record", action="store_true", help=f"do not record the {what}")
    parser.add_argument(
        "--record-cap-mb",
        metavar="MB",
        type=float,
        default=DEFAULT_CAP_BYTES / 1e6,
        help="the recordings folder's size cap: its oldest files go beyond it (default 2000 MB)",
    )


@dataclass(frozen=True, slots=True)
class RecordTarget:
    """Where a run records (``path`` None: nowhere) and the default folder it records into (None: a given file)."""

    path: Path | None
    folder: Path | None
    cap_bytes: int

    def finish(self) -> None:
        """After the recording is closed: keep the default folder under its cap (never the new file)."""
        if self.folder is not None:
            prune(self.folder, self.cap_bytes)


def target(args: argparse.Namespace, agents_files: Iterable[Path], name: str) -> RecordTarget:
    """The flags' recording: a new ``NAME-...mcap`` in the default folder of ``agents_files`` unless told otherwise.

    Raises:
        UsageError: contradicting flags, a cap that is not a positive number, a folder that
            cannot be created.
    """
    if args.record and args.no_record:
        raise UsageError("--record and --no-record contradict each other")
    if not 0 < args.record_cap_mb < math.inf:
        raise UsageError(f"--record-cap-mb must be a positive number, got {args.record_cap_mb}")
    cap = int(args.record_cap_mb * 1e6)
    if args.no_record:
        return RecordTarget(None, None, cap)
    if args.record:
        return RecordTarget(Path(args.record), None, cap)
    folder = default_folder(agents_files)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UsageError(f"cannot create the recordings folder {folder}: {error.strerror} (or --no-record)") from None
    return RecordTarget(new_recording(folder, name), folder, cap)
