"""``xabsl recover PATH...``: cut recordings made readable again (``xabsl_studio.engine.record.recover``).

A PATH is a ``FILE.mcap.part`` a killed or crashed run left, or a folder (its ``*.mcap.part``
files nobody is writing). Each is recovered to its last complete tick as ``FILE.mcap``; one line
per file says what was kept, or why it could not be. Exit status: 0 every file recovered (or
none to recover), 2 a file could not be (it stays as it was) or a PATH is neither.
"""

from __future__ import annotations

import argparse
import os
import sys

from xabsl_studio.engine.cli import UsageError

HELP = "make cut recordings (FILE.mcap.part left by a killed run) readable to their last complete tick"


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``xabsl recover`` to the command line."""
    parser = subparsers.add_parser(
        "recover",
        help=HELP,
        description=(
            "Recover recordings cut by a crash, kill -9 or a full disk: FILE.mcap.part becomes FILE.mcap with every "
            "complete tick, its header marked as cut (the studio does this for its record folder when it starts). A "
            "folder recovers the cut recordings in it that no running recorder is writing."
        ),
    )
    parser.add_argument("paths", nargs="+", metavar="PATH", help="a FILE.mcap.part, or a folder of recordings")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Recover each PATH; one line per file."""
    from pathlib import Path

    from xabsl_studio.engine.record.recover import PART, RecoveryFailed, in_use, recover

    parts: list[Path] = []
    for name in args.paths:
        path = Path(name)
        if path.is_dir():
            parts.extend(p for p in sorted(path.glob("*.mcap" + PART)) if not in_use(p))
        elif os.path.lexists(path):
            parts.append(path)
        else:
            raise UsageError(f"no such file or folder: {name}")
    failed = 0
    for part in parts:
        try:
            done = recover(part)
        except RecoveryFailed as error:
            failed += 1
            print(f"error: {error}", file=sys.stderr)
            continue
        print(f"{done.path}: {done.ticks} ticks recovered from {part.name} ({done.cut['reason']})")
    if not parts:
        print("no cut recordings to recover")
    return 2 if failed else 0
