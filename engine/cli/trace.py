"""``xabsl trace``: run a behavior under the conformance host and write its per-tick trace.

``xabsl trace AGENTS_FILE --inputs IN.jsonl [--agent NAME] [--out OUT.jsonl]``

AGENTS_FILE ending in ``.ic`` or ``.dat`` is read as intermediate code (§3); anything else is
compiled from source. The input and output formats and the host conventions are those of the
conformance kit (see :mod:`engine.trace.conformance`). For intermediate code,
``--declarations agents.xabsl`` takes the external declarations (enum element order, input
parameter order) from the sources, which the IC cannot carry.

Exit status: 0 success; 1 the behavior does not compile, load or run (diagnostics, link or
option-graph errors, a fault during the trace); 2 usage and input problems (a missing file, a
malformed input line, an unknown or parameterized symbol in ``set``, a value of the wrong type,
an unqualified enum element, an unknown agent), reported as one line on stderr.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from typing import TYPE_CHECKING, Any

from engine.cli import UsageError
from engine.errors import CommandLineError

if TYPE_CHECKING:  # the IR is imported when a trace runs, not for `xabsl --help`
    from engine.ir.model import Program

_IC_SUFFIXES = (".ic", ".dat")


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``trace`` subcommand to the ``xabsl`` parser."""
    parser = subparsers.add_parser(
        "trace",
        help="run a behavior under the conformance host: input trace in, activation trace out",
        description=(
            "Run AGENTS_FILE (XABSL sources, or intermediate code if it ends in .ic/.dat) one tick "
            "per line of the input trace and write one JSON line per tick: the activation tree "
            "and every output symbol."
        ),
    )
    parser.add_argument("agents_file", metavar="AGENTS_FILE", help="agents.xabsl, or intermediate code (.ic/.dat)")
    parser.add_argument("--inputs", required=True, metavar="IN.jsonl", help="one JSON object per tick")
    parser.add_argument("--agent", metavar="NAME", help="select this agent before the first tick")
    parser.add_argument("--out", metavar="OUT.jsonl", help="write the trace here (default: standard output)")
    parser.add_argument(
        "--declarations",
        metavar="AGENTS_XABSL",
        help="for intermediate code: take external declarations from these sources",
    )
    parser.set_defaults(func=run)


class _BehaviorError(CommandLineError):
    """The behavior cannot be compiled, loaded or run (exit status 1)."""


def _compile(path: str) -> Program:
    from engine.lang import compile_file  # the source compiler is optional for IC input

    compilation = compile_file(path)
    if compilation.program is None:
        # Warnings are `xabsl compile`'s business; the trace stays quiet unless it cannot run.
        for diagnostic in compilation.diagnostics:
            print(diagnostic.format(), file=sys.stderr)
        raise _BehaviorError(f"{path}: the behavior has errors")
    return compilation.program


def _load(args: argparse.Namespace) -> Program:
    from engine.ir.ic_reader import ICError, read_ic_file

    path = args.agents_file
    if not os.path.isfile(path):
        raise UsageError(f"no such file: {path}")
    if not path.lower().endswith(_IC_SUFFIXES):
        return _compile(path)
    declarations = None
    if args.declarations:
        if not os.path.isfile(args.declarations):
            raise UsageError(f"no such file: {args.declarations}")
        declarations = _compile(args.declarations)
    try:
        return read_ic_file(path, declarations)
    except ICError as error:
        raise _BehaviorError(f"{path}: {error}") from None
    except UnicodeDecodeError as error:
        raise UsageError(f"{path}: not a text file ({error.reason})") from None


def run(args: argparse.Namespace) -> int:
    """Run one tick per input line and write the trace; returns the exit status."""
    from engine.errors import EngineError
    from engine.files import write_atomically
    from engine.trace.conformance import TraceFaultError, TraceInputError, TraceRunner

    if not os.path.isfile(args.inputs):
        raise UsageError(f"no such file: {args.inputs}")
    try:
        program = _load(args)
        try:
            runner = TraceRunner(program)
        except EngineError as error:
            raise _BehaviorError(str(error).replace("\n", "; ")) from None
        if args.agent is not None:
            if args.agent not in {a.name for a in program.agents}:
                raise UsageError(f"unknown agent {args.agent!r} (--agent)")
            runner.select_agent(args.agent)
        with open(args.inputs, encoding="utf-8") as source:
            lines = source.read().splitlines()
        records: list[str] = []
        for number, text in enumerate(lines, start=1):
            if not text.strip():
                continue
            try:
                line: Any = json.loads(text)
            except json.JSONDecodeError as error:
                raise UsageError(f"{args.inputs}:{number}: not JSON ({error.msg})") from None
            records.append(json.dumps(runner.tick(line), separators=(",", ":")))
    except TraceInputError as error:
        raise UsageError(f"{args.inputs}: {error}") from None
    except (_BehaviorError, TraceFaultError) as error:
        print(f"xabsl trace: {error}", file=sys.stderr)
        return 1
    text = "".join(r + "\n" for r in records)
    if args.out:
        try:
            write_atomically(args.out, text.encode("utf-8"))
        except OSError as error:
            raise UsageError(f"cannot write {args.out}: {error.strerror}") from None
    else:
        sys.stdout.write(text)
    return 0
