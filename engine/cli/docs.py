"""``xabsl docs``: HTML documentation of a behavior set (option graphs, state machines, symbols).

Compiles AGENTS_FILE (diagnostics as ``xabsl compile`` prints them) and, when it has no errors,
writes the documentation of :mod:`xabsl_studio.engine.docs` into DIR. Exit status: 0 written, 1 errors in the
behavior, 2 usage or I/O problems (also a missing Graphviz ``dot``).
"""

from __future__ import annotations

import argparse
import os
import time

from xabsl_studio.engine.cli import UsageError
from xabsl_studio.engine.emit.dot import GraphvizMissing
from xabsl_studio.engine.lang import compile_file


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``xabsl docs`` to the command line."""
    parser = subparsers.add_parser(
        "docs",
        help="write HTML documentation of a behavior set (option graph, options, symbols, search)",
        description=(
            "Compile AGENTS_FILE and write its HTML documentation into DIR: per agent its option graph, "
            "per option its parameters, state machine, decision trees and callers, pages for symbols, "
            "enumerations, constants and basic behaviors, and a search box. Opens offline from DIR/index.html."
        ),
    )
    parser.add_argument("agents_file", metavar="AGENTS_FILE", help="the agents file, e.g. agents.xabsl")
    parser.add_argument("-o", "--out", metavar="DIR", required=True, help="the folder to write (created if missing)")
    parser.add_argument("--jobs", type=int, default=None, help="Graphviz processes at once (default: one per core)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Compile, then write the documentation; print one summary line."""
    from xabsl_studio.engine.docs import GraphLayoutError, generate

    if not os.path.isfile(args.agents_file):
        raise UsageError(f"no such file: {args.agents_file}")
    if args.jobs is not None and args.jobs < 1:
        raise UsageError("--jobs must be at least 1")
    if os.path.exists(args.out) and not os.path.isdir(args.out):
        raise UsageError(f"not a folder: {args.out}")
    started = time.perf_counter()
    compilation = compile_file(args.agents_file)
    for diagnostic in compilation.errors:
        print(diagnostic.format())
    if compilation.program is None or compilation.errors:
        print(f"failed: {len(compilation.errors)} errors; no documentation written")
        return 1
    try:
        result = generate(compilation.program, args.out, args.jobs)
    except (GraphvizMissing, GraphLayoutError) as error:
        raise UsageError(str(error)) from error
    except OSError as error:
        raise UsageError(f"cannot write output: {error.strerror}: {error.filename}") from error
    seconds = time.perf_counter() - started
    print(
        f"ok: {len(result.pages)} pages ({len(compilation.program.options)} options) in "
        f"{os.path.join(args.out, 'index.html')} in {seconds * 1000:.0f} ms"
    )
    return 0
