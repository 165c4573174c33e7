"""``xabsl import naoth LOG --behavior AGENTS_FILE -o REC.mcap``: another system's logs as recordings.

One format so far, ``naoth``: a NaoTH game log (docs/naoth.md), converted by
``xabsl_studio.engine.naoth.importer``. The behavior's sources must be the ones the robot ran:
they are compiled here and joined by name with the log's ``BehaviorStateComplete``; a log whose
behavior differs is refused with every difference named (``--allow-mismatch`` imports it anyway).
Exit status: 0 written, 1 the behavior has errors or does not match, 2 usage or a bad log.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from xabsl_studio.engine.cli import UsageError

HELP = "convert another system's logs into a recording (naoth: a NaoTH game log): docs/naoth.md"


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``xabsl import`` to the command line."""
    parser = subparsers.add_parser("import", help=HELP, description=__doc__.split("\n\n")[0])
    parser.add_argument("format", choices=["naoth"], help="the log's format")
    parser.add_argument("log", metavar="LOG", help="the log file (a NaoTH game.log)")
    parser.add_argument("--behavior", required=True, metavar="AGENTS_FILE", help="the sources the robot ran")
    parser.add_argument("-o", "--output", required=True, metavar="REC.mcap", help="the recording to write")
    parser.add_argument("--robot", default="robot", help="the agent's name in the recording (default robot)")
    parser.add_argument(
        "--allow-mismatch", action="store_true", help="import a log whose behavior differs from the sources"
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Compile, import, report."""
    from xabsl_studio.engine.lang import compile_file
    from xabsl_studio.engine.naoth.importer import SourceMismatch, import_log
    from xabsl_studio.engine.naoth.log import LogError
    from xabsl_studio.engine.record.sources import program_sources

    behavior = Path(args.behavior)
    agents = behavior / "agents.xabsl" if behavior.is_dir() else behavior
    if not agents.is_file():
        raise UsageError(f"--behavior: no agents file {agents}")
    if not Path(args.log).is_file():
        raise UsageError(f"{args.log}: no such file")
    compilation = compile_file(str(agents))
    if compilation.program is None:
        for diagnostic in compilation.errors:
            print(diagnostic.format(), file=sys.stderr)
        return 1
    program = compilation.program
    try:
        sources = program_sources(agents, program.files)
    except Exception:  # a fork of the import needs them; the import itself does not
        sources = None
    try:
        result = import_log(
            args.log, program, args.output, robot=args.robot, sources=sources, allow_mismatch=args.allow_mismatch
        )
    except SourceMismatch as error:
        print(f"{args.log}: {error}", file=sys.stderr)
        print("(--allow-mismatch imports it anyway)", file=sys.stderr)
        return 1
    except LogError as error:
        print(str(error), file=sys.stderr)
        return 2
    except OSError as error:
        raise UsageError(str(error)) from None
    print(
        f"{result.path}: {result.frames} frames, {result.gaps} frames missing in the log, "
        f"{result.inferred} decisions certain from state changes, agents {', '.join(result.agents) or '?'}, "
        f"{result.bytes} bytes"
    )
    if result.unjoined:
        print(f"  {result.unjoined} frames before the log's first BehaviorStateComplete were left out")
    if result.unplaced:
        print(f"  {result.unplaced} actions of the log match nothing in the sources (left out)")
    for mismatch in result.mismatches:
        print(f"  mismatch: {mismatch}")
    if result.truncated is not None:
        print(f"  the log ends in an incomplete record at byte {result.truncated} (a robot switched off?)")
    return 0
