"""``xabsl plan DOMAIN PROBLEM [--json] [--stats]``: GRAPHPLAN on a PDDL domain and problem.

Prints the layered plan (dual-dynamics.md §2.1 item 6): one line per step, the step's actions
separated by ``∥`` (any order inside a step is valid). ``--json`` prints one line
``{"layers": [["goto a c"], ..., ["unload book a", "unload mug a"]]}`` with actions as lower-case
name and arguments; ``--stats`` adds the planning-graph table of §2.4.

Exit status: 0 a plan was found; 1 the task has no plan (the reason is printed; with ``--json``
``{"layers": null, "reason": ...}``); 2 unreadable or invalid PDDL and usage problems, reported as
one line ``xabsl plan: FILE:LINE:COL: message``.
"""

from __future__ import annotations

import argparse
import json

from xabsl_studio.engine.cli import UsageError


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add the ``plan`` subcommand to the ``xabsl`` parser."""
    parser = subparsers.add_parser(
        "plan",
        help="run GRAPHPLAN on a PDDL domain and problem and print the layered plan",
        description="Ground a STRIPS (+ typing) PDDL domain and problem and print GRAPHPLAN's layered plan.",
    )
    parser.add_argument("domain", metavar="DOMAIN", help="PDDL domain file")
    parser.add_argument("problem", metavar="PROBLEM", help="PDDL problem file")
    parser.add_argument("--json", action="store_true", help='print {"layers": [["goto a c"], ...]} on one line')
    parser.add_argument("--stats", action="store_true", help="also print the planning-graph level table")
    parser.set_defaults(func=run)


def _read(path: str) -> str:
    from xabsl_studio.engine.planning.strips import read_pddl

    try:
        return read_pddl(path)
    except FileNotFoundError:
        raise UsageError(f"no such file: {path}") from None
    except OSError as error:
        raise UsageError(f"{path}: cannot read: {error.strerror or error}") from None
    except UnicodeDecodeError as error:
        raise UsageError(f"{path}: not UTF-8 text (byte {error.start}: {error.reason})") from None


def _one_line(text: object) -> str:
    return " ".join(str(text).split())


def _parse_error(path: str, error: Exception) -> UsageError:
    """Turn a parser exception of the ``pddl`` package (lark underneath) into one clear line."""
    from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

    if isinstance(error, UnexpectedInput):
        where = f"{path}:{getattr(error, 'line', '?')}:{getattr(error, 'column', '?')}"
        if isinstance(error, UnexpectedToken):
            token = error.token
            what = "end of file" if token.type == "$END" else repr(str(token))
            expected = sorted(error.expected)
            hint = f"; expected {', '.join(expected[:6])}{' ...' if len(expected) > 6 else ''}" if expected else ""
            return UsageError(f"{where}: syntax error: unexpected {what}{hint}")
        if isinstance(error, UnexpectedCharacters):
            return UsageError(f"{where}: syntax error: unexpected character {error.char!r}")
        if isinstance(error, UnexpectedEOF):
            return UsageError(f"{path}: syntax error: unexpected end of file")
        return UsageError(f"{where}: syntax error")
    return UsageError(f"{path}: {_one_line(error) or type(error).__name__}")


def run(args: argparse.Namespace) -> int:
    """Parse, ground and plan; print the layered plan; 0 with a plan, 1 without, 2 for bad PDDL."""
    from pddl.parser.domain import DomainParser
    from pddl.parser.problem import ProblemParser

    from xabsl_studio.engine.errors import PlanningError
    from xabsl_studio.engine.planning.graphplan import format_stats, graphplan
    from xabsl_studio.engine.planning.strips import ground

    domain_text, problem_text = _read(args.domain), _read(args.problem)
    try:
        domain = DomainParser()(domain_text)
    except Exception as error:  # the pddl package raises lark and plain exceptions alike
        raise _parse_error(args.domain, error) from None
    try:
        problem = ProblemParser()(problem_text)
    except Exception as error:
        raise _parse_error(args.problem, error) from None
    try:
        task = ground(domain, problem)
    except PlanningError as error:
        raise UsageError(f"{args.problem}: {_one_line(error)}") from None
    except Exception as error:  # a problem inconsistent with its domain that pddl did not catch
        raise UsageError(f"{args.problem}: {_one_line(error) or type(error).__name__}") from None

    result = graphplan(task)
    if args.json:
        out: dict[str, object] = {"layers": result.plan.names() if result.plan is not None else None}
        if result.plan is None:
            out["reason"] = result.reason
        if args.stats:
            out["stats"] = [row.to_json() for row in result.stats]
        print(json.dumps(out, ensure_ascii=False))
    else:
        if result.plan is None:
            print(result.reason)
        else:
            for i, layer in enumerate(result.plan.layers, start=1):
                print(f"{i:2d}  {' ∥ '.join(a.name for a in layer)}")
            print(f"{len(result.plan.actions())} actions in {len(result.plan)} steps ({result.seconds * 1000:.1f} ms)")
        if args.stats:
            print(format_stats(result.stats))
    return 0 if result.plan is not None else 1
