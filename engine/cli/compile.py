"""``xabsl compile``: check a behavior and write its intermediate code and JSON description.

Text diagnostics are one per line (``path:line:col: error|warning: message [code]``) followed by
a summary line; ``--format json`` prints one JSON object instead. An output named ``-`` is written
to standard output; the diagnostics then go to standard error. Exit status: 0 without errors,
1 with errors (or warnings under ``--werror``), 2 for usage or I/O problems.
"""

from __future__ import annotations

import argparse
import gc
import os
import sys
import time

from xabsl_studio.engine.cli import UsageError


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``compile`` subcommand to the ``xabsl`` parser."""
    parser = subparsers.add_parser(
        "compile",
        help="check a behavior; write intermediate code (--ic) and a JSON description (--json)",
        description=(
            "Compile AGENTS_FILE and every file it includes. Prints diagnostics and a summary; "
            "writes output files only when there is no error."
        ),
    )
    parser.add_argument("agents_file", metavar="AGENTS_FILE", help="the agents file, e.g. agents.xabsl")
    parser.add_argument(
        "--ic", metavar="OUT", help="write the intermediate code for the C++ XabslEngine ('-': standard output)"
    )
    parser.add_argument(
        "--json", metavar="OUT", help="write the behavior description the studio reads ('-': standard output)"
    )
    parser.add_argument("--format", choices=("text", "json"), default="text", help="diagnostics format")
    parser.add_argument("--werror", action="store_true", help="treat warnings as errors")
    parser.add_argument(
        "--no-lint",
        action="store_true",
        help=(
            "omit the warnings the original compiler does not print (naming, missing parameters, "
            "unreachable and unused declarations)"
        ),
    )
    parser.set_defaults(func=run, exit_at_once=True)


def run(args: argparse.Namespace) -> int:
    """Compile, print the diagnostics and a summary, write the outputs; returns the exit status."""
    # One compile, then the process ends: the cyclic garbage collector would only traverse the
    # program's hundreds of thousands of live objects (once more when `compile_file` re-enables
    # it), so it stays off for the command. Reference counting still frees what dies.
    gc.disable()
    # Imported here, not at the top: `xabsl --help` and the other subcommands need none of it;
    # the emitters and orjson (which imports uuid, platform, datetime) only when asked for.
    from xabsl_studio.engine.lang import compile_file, deep_recursion

    if not os.path.isfile(args.agents_file):
        raise UsageError(f"no such file: {args.agents_file}")
    if args.ic == STDOUT and args.json == STDOUT:
        raise UsageError("only one of --ic and --json can be written to standard output")
    # with an output on standard output, the diagnostics must not mix into it
    report = sys.stderr if STDOUT in (args.ic, args.json) else sys.stdout
    started = time.perf_counter()
    compilation = compile_file(args.agents_file)
    diagnostics = [d for d in compilation.diagnostics if not (args.no_lint and d.is_lint)]
    errors = sum(d.is_error for d in diagnostics)
    warnings = len(diagnostics) - errors
    failed = errors > 0 or (args.werror and warnings > 0)

    emit_started = time.perf_counter()
    if not failed and compilation.program is not None:
        try:
            if args.ic:
                from xabsl_studio.engine.emit.ic import emit_ic

                with deep_recursion():
                    text = emit_ic(compilation.program)
                _write(args.ic, text.encode("utf-8"))
            if args.json:
                from xabsl_studio.engine.emit.json import dumps, program_to_json

                document = program_to_json(compilation.program, compilation.source_text)
                _write(args.json, dumps(document))
        except OSError as error:
            raise UsageError(f"cannot write output: {error.strerror}: {error.filename}") from error
    finished = time.perf_counter()

    summary = {
        "files": len(compilation.files),
        "options": len(compilation.option_names),
        "errors": errors,
        "warnings": warnings,
        "milliseconds": round((finished - started) * 1000, 1),
        "parse_ms": round(compilation.timings.get("parse", 0) * 1000, 1),
        "check_ms": round(compilation.timings.get("check", 0) * 1000, 1),
        "emit_ms": round((finished - emit_started) * 1000, 1),
    }
    if args.format == "json":
        import orjson

        report.buffer.write(
            orjson.dumps({"ok": not failed, "diagnostics": [d.as_dict() for d in diagnostics], "summary": summary})
        )
        report.write("\n")
    else:
        for diagnostic in diagnostics:
            print(diagnostic.format(), file=report)
        verdict = "failed" if failed else "ok"
        counts = ", ".join(
            _count(n, noun)
            for n, noun in (
                (summary["files"], "file"),
                (summary["options"], "option"),
                (errors, "error"),
                (warnings, "warning"),
            )
        )
        print(f"{verdict}: {counts} in {summary['milliseconds']} ms", file=report)
    return 1 if failed else 0


#: The output name that means standard output.
STDOUT = "-"


def _write(out: str, data: bytes) -> None:
    """``data`` to the file ``out`` (atomically), or to standard output for ``-``."""
    from xabsl_studio.engine.files import write_atomically

    if out == STDOUT:
        sys.stdout.buffer.write(data)
        sys.stdout.buffer.flush()
    else:
        write_atomically(out, data)


def _count(n: object, noun: str) -> str:
    """``1 warning``, ``2 warnings``, ``0 warnings``."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"
