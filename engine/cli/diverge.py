"""``xabsl diverge``: the first tick where two runs act differently, per robot, and why.

``xabsl diverge A.mcap B.mcap [--agent NAME] [--json]``

For two recordings of the same seed with different behaviors (or a fork and the run it was
forked from), prints per robot the first tick where its activation paths differ, both paths side
by side, and the why of the first differing decision on each side
(:mod:`xabsl_studio.engine.compare.diverge`); ``--json`` prints the report document.

Exit status: 0 the runs diverge or not (the report says which), 2 usage and I/O problems (no such
file, not a recording, no robot or tick in common).
"""

from __future__ import annotations

import argparse
import os
import sys

from xabsl_studio.engine.cli import UsageError


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``xabsl diverge`` to the command line."""
    parser = subparsers.add_parser(
        "diverge",
        help="the first tick where two recordings act differently, per robot: both paths and the why of each",
        description=(
            "Compare two recordings of the same seed (two versions of a behavior, or a fork and its original) "
            "tick by tick: per robot the first tick whose activation paths differ (options, states, basic "
            "behaviors by name), the two paths side by side, and why the first differing decision went as it "
            "did on each side, from the recorded values."
        ),
    )
    parser.add_argument("a", metavar="A.mcap", help="the first recording")
    parser.add_argument("b", metavar="B.mcap", help="the second recording")
    parser.add_argument("--agent", action="append", metavar="NAME", help="compare only this robot; repeatable")
    parser.add_argument("--json", action="store_true", help="print the report as JSON")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Compare the two recordings; print the report."""
    import orjson

    from xabsl_studio.engine.compare.diverge import diverge
    from xabsl_studio.engine.record import Recording, RecordingError

    for path in (args.a, args.b):
        if not os.path.isfile(path):
            raise UsageError(f"no such file: {path}")
    try:
        with Recording(args.a) as a, Recording(args.b) as b:
            report = diverge(a, b, args.agent)
    except RecordingError as error:
        raise UsageError(str(error)) from error
    if args.json:
        sys.stdout.write(orjson.dumps(report.to_json(), option=orjson.OPT_INDENT_2).decode("utf-8") + "\n")
    else:
        print("\n".join(report.lines()))
    return 0
