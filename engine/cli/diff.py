"""``xabsl diff OLD NEW``: what changed between two versions of a behavior set, compared as IR.

``xabsl diff OLD NEW [--json] [--html OUT] [--jobs N]``; OLD and NEW are behavior folders,
agents files or ``git:REV[:PATH]`` (:mod:`xabsl_studio.engine.cli.sides`). Prints one line per
change (:mod:`xabsl_studio.engine.compare`), or the JSON document with ``--json``; ``--html OUT``
also writes the page with the marked option graph and state machines. Exit status: 0 compared
(with or without changes), 1 a side does not compile, 2 usage or I/O problems (also a missing
Graphviz with ``--html``).
"""

from __future__ import annotations

import argparse
import os
import sys

from xabsl_studio.engine.cli import UsageError

HELP = "compare two versions of a behavior set: options, states, transitions, symbols added, removed, changed"


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``xabsl diff`` to the command line."""
    parser = subparsers.add_parser(
        "diff",
        help=HELP,
        description=(
            "Compile OLD and NEW and list what changed between them: options, states, transitions (by their "
            "decision path), conditions, action items, parameters, symbols, enumerations, constants, basic "
            "behaviors and agents, each once with the file:line of both sides; renamed options and states are "
            "found by their bodies. OLD and NEW are folders (their agents.xabsl), agents files, or git:REV[:PATH] "
            "(git:HEAD~1 alone: the other side's path at HEAD~1)."
        ),
    )
    parser.add_argument("old", metavar="OLD", help="the old version: folder, agents file or git:REV[:PATH]")
    parser.add_argument("new", metavar="NEW", help="the new version (e.g. examples/soccer/behavior)")
    parser.add_argument("--json", action="store_true", help="print the changes as one JSON document (docs/compare.md)")
    parser.add_argument("--html", metavar="OUT", help="also write the page with the marked drawings (needs Graphviz)")
    parser.add_argument("--jobs", type=int, default=None, help="Graphviz processes at once (default: one per core)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Resolve and compile both sides, diff them, print and write the report."""
    import tempfile
    from pathlib import Path

    import orjson

    from xabsl_studio.engine.cli.sides import compile_side, resolve_side
    from xabsl_studio.engine.compare import diff_programs
    from xabsl_studio.engine.compare.report import document, html_page, text_lines
    from xabsl_studio.engine.files import write_atomically

    if args.jobs is not None and args.jobs < 1:
        raise UsageError("--jobs must be at least 1")
    if args.html and os.path.isdir(args.html):
        raise UsageError(f"--html names a folder: {args.html}")
    with tempfile.TemporaryDirectory(prefix="xabsl-diff-") as scratch:
        sides = [
            resolve_side(args.old, Path(scratch) / "old", other=args.new),
            resolve_side(args.new, Path(scratch) / "new", other=args.old),
        ]
        compilations = [compile_side(side) for side in sides]
        failed = False
        for side, compilation in zip(sides, compilations, strict=True):
            if compilation.program is None:
                failed = True
                for diagnostic in compilation.errors:
                    print(f"{side.spec}: {diagnostic.format()}", file=sys.stderr)
                print(f"xabsl diff: {side.spec} has {len(compilation.errors)} errors", file=sys.stderr)
        if failed:
            return 1
        old, new = (c.program for c in compilations)
        assert old is not None and new is not None
        diff = diff_programs(old, new)
        if args.html:
            from xabsl_studio.engine.compare.graphs import draw
            from xabsl_studio.engine.docs.graphs import GraphLayoutError
            from xabsl_studio.engine.emit.dot import GraphvizMissing

            try:
                drawings = draw(diff, jobs=args.jobs)
            except (GraphvizMissing, GraphLayoutError) as error:
                raise UsageError(str(error)) from error
            page = html_page(diff, args.old, args.new, drawings)
            try:
                write_atomically(args.html, page.encode("utf-8"))
            except OSError as error:
                raise UsageError(f"cannot write {args.html}: {error.strerror}") from error
    if args.json:
        report = document(diff, sides[0].describe(), sides[1].describe())
        sys.stdout.write(orjson.dumps(report, option=orjson.OPT_INDENT_2).decode("utf-8") + "\n")
        return 0
    for line in text_lines(diff, args.old, args.new):
        print(line)
    if args.html:
        print(f"wrote {args.html}")
    return 0
