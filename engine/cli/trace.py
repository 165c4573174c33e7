"""``xabsl trace``: run a behavior under the conformance host and write its per-tick trace.

``xabsl trace AGENTS_FILE --inputs IN.jsonl [--agent NAME] [--out OUT.jsonl]``

AGENTS_FILE ending in ``.ic`` or ``.dat`` is read as intermediate code (§3); anything else is
compiled from source. The input and output formats and the host conventions are those of the
conformance kit (see :mod:`xabsl_studio.engine.trace.conformance`). For intermediate code,
``--declarations agents.xabsl`` takes the external declarations (enum element order, input
parameter order) from the sources, which the IC cannot carry.

Exit status: 0 success; 1 the behavior does not compile, load or run (diagnostics, link or
option-graph errors, a fault during the trace); 2 usage and input problems (a missing file or one that is not a regular
file, a malformed input line, NaN, Infinity or a number beyond the double range, an unknown or
parameterized symbol in ``set``, a value of the wrong type, an unqualified enum element, an
unknown agent), reported as one line on stderr naming the line and the tick.

An infinity or NaN the behavior computes from finite inputs (``1e300 * -1e300``) is its
arithmetic, not bad input: it is written as the kit's expected traces and the original engine
write it, ``Infinity``, ``-Infinity``, ``NaN`` (JSON as Python's ``json`` reads and writes it).
Only the input is held to strict JSON numbers.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

from xabsl_studio.engine.cli import UsageError
from xabsl_studio.engine.errors import CommandLineError, TraceError

if TYPE_CHECKING:  # the IR is imported when a trace runs, not for `xabsl --help`
    from xabsl_studio.engine.ir.model import Program

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
    from xabsl_studio.engine.lang import compile_file  # the source compiler is optional for IC input

    compilation = compile_file(path)
    if compilation.program is None:
        # Warnings are `xabsl compile`'s business; the trace stays quiet unless it cannot run.
        for diagnostic in compilation.diagnostics:
            print(diagnostic.format(), file=sys.stderr)
        raise _BehaviorError(f"{path}: the behavior has errors")
    return compilation.program


def _load(args: argparse.Namespace) -> Program:
    from xabsl_studio.engine.ir.ic_reader import ICError, read_ic_file

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


#: The largest input trace read (a 10,000-tick trace is about 1 MB).
MAX_INPUT_BYTES = 256 * 1024 * 1024


class _BadNumber(TraceError, ValueError):
    """A number in an input line that is not a finite double (NaN, Infinity, 1e999, 10**400)."""


def _finite_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise _BadNumber(f"{text} is not a finite number")
    return value


def _finite_int(text: str) -> int:
    if len(text) > 400:  # int() itself refuses over 4,300 digits; no double has 400
        raise _BadNumber(f"the integer {text[:20]}... ({len(text)} digits) is out of range")
    value = int(text)
    if len(text) > 300:
        try:
            float(value)
        except OverflowError:
            raise _BadNumber(f"the integer {text[:20]}... is out of range") from None
    return value


def _constant(text: str) -> Any:
    raise _BadNumber(f"{text} is not a finite number")


def _input_lines(path: str) -> Iterator[tuple[int, int, Any]]:
    """``(line number, tick number, parsed line)`` of every non-blank line of an input trace.

    Only a regular file of at most MAX_INPUT_BYTES is read; NaN, Infinity and numbers beyond the
    double range are refused (they would reach the output, which would then not be JSON).

    Raises:
        UsageError: naming the file, the line and the tick.
    """
    try:
        from xabsl_studio.engine.files import read_regular

        data = read_regular(path, MAX_INPUT_BYTES)
    except OSError as error:
        raise UsageError(f"{path}: cannot read: {error.strerror or error}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        line = data.count(b"\n", 0, error.start) + 1
        raise UsageError(f"{path}:{line}: not UTF-8 text (byte 0x{data[error.start]:02x})") from None
    tick = 0
    for number, raw in enumerate(text.splitlines(), start=1):
        if not raw.strip():
            continue
        tick += 1
        try:
            line = json.loads(raw, parse_float=_finite_float, parse_int=_finite_int, parse_constant=_constant)
        except json.JSONDecodeError as error:
            raise UsageError(f"{path}:{number}: not JSON ({error.msg})") from None
        except _BadNumber as error:
            raise UsageError(f"{path}:{number}: tick {tick}: {error}") from None
        except RecursionError:
            raise UsageError(f"{path}:{number}: tick {tick}: nested too deeply") from None
        yield number, tick, line


def run(args: argparse.Namespace) -> int:
    """Run one tick per input line and write the trace; the exit status as in the module docstring."""
    from xabsl_studio.engine.errors import EngineError
    from xabsl_studio.engine.files import write_atomically
    from xabsl_studio.engine.trace.conformance import TraceFaultError, TraceInputError, TraceRunner

    if not os.path.exists(args.inputs):
        raise UsageError(f"no such file: {args.inputs}")
    try:
        program = _load(args)
        try:
            runner = TraceRunner(program)
        except EngineError as error:
            raise _BehaviorError(str(error).replace("\n", "; ")) from None
        except ValueError as error:  # the host cannot bind a symbol (an IC without its declarations)
            hint = " (for intermediate code, --declarations AGENTS_XABSL gives the declarations)"
            raise _BehaviorError(f"{args.agents_file}: {error}{hint if args.declarations is None else ''}") from None
        if args.agent is not None:
            if args.agent not in {a.name for a in program.agents}:
                raise UsageError(f"unknown agent {args.agent!r} (--agent)")
            runner.select_agent(args.agent)
        records: list[str] = []
        for number, _tick, line in _input_lines(args.inputs):
            try:
                output = runner.tick(line)
            except TraceInputError as error:  # its message names the tick
                raise UsageError(f"{args.inputs}:{number}: {error}") from None
            # allow_nan: a computed infinity is written as the kit's traces write it (docstring)
            records.append(json.dumps(output, separators=(",", ":"), allow_nan=True))
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
