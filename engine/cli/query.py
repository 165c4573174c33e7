"""``xabsl query``: the ticks of a recording in which an XABSL condition holds, as intervals.

``xabsl query RECORDING 'CONDITION' [--robot NAME] [--json]``

The condition is a breakpoint condition plus the activation predicates (``striker.state ==
shoot``, ``kick.active``, ``go_to_position.x > 1000``; docs/queries.md). Prints one line per
interval of consecutive matching ticks (robot, first and last tick, their times, length), ordered
by first tick; ``--json`` prints :meth:`xabsl_studio.engine.query.QueryResult.to_json` with the
recording's path.

Exit status: 0 the query ran (whether or not anything matched), 1 the condition has errors
(each printed as ``<condition>:line:col: message``, with a caret under the first), 2 usage and
I/O problems (no such file, not a recording, an unknown robot).
"""

from __future__ import annotations

import argparse
import os
import sys

from xabsl_studio.engine.cli import UsageError


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``xabsl query`` to the command line."""
    parser = subparsers.add_parser(
        "query",
        help="find the ticks of a recording where an XABSL condition holds (docs/queries.md)",
        description=(
            "Evaluate an XABSL condition over every tick of a recording (xabsl run ... --record FILE.mcap) and "
            "print the intervals of consecutive ticks in which it is true. The condition is a breakpoint "
            "condition (symbols, constants, enumerations, comparisons, &&, ||, input functions with the "
            "results the behavior got) that may also name options, states, decision leaves and basic behaviors: "
            "'striker.state == shoot && ball.distance > 500', 'kick.active', 'go_to_position.x > 1000'. "
            "What the recording does not hold is unknown and never matches."
        ),
    )
    parser.add_argument("recording", metavar="RECORDING", help="an .mcap recording")
    parser.add_argument("condition", metavar="CONDITION", help="the XABSL condition (quote it for the shell)")
    parser.add_argument("--robot", metavar="NAME", help="only this robot (default: every robot)")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")
    parser.set_defaults(func=run)


def _seconds(ms: int) -> str:
    return f"{ms / 1000:.3f} s"


def run(args: argparse.Namespace) -> int:
    """Run the query; print the intervals (or the condition's errors)."""
    import orjson

    from xabsl_studio.engine.errors import QueryError
    from xabsl_studio.engine.query import QueryConditionError, query_recording
    from xabsl_studio.engine.record import RecordingError

    if not os.path.isfile(args.recording):
        raise UsageError(f"no such file: {args.recording}")
    try:
        result = query_recording(args.recording, args.condition, args.robot)
    except QueryConditionError as error:
        print(error.format(), file=sys.stderr)
        return 1
    except (QueryError, RecordingError) as error:
        raise UsageError(str(error)) from error
    if args.json:
        document = {"recording": args.recording, **result.to_json()}
        sys.stdout.write(orjson.dumps(document, option=orjson.OPT_INDENT_2).decode("utf-8") + "\n")
        return 0
    count = len(result.intervals)
    print(
        f"{args.recording}: {args.condition}\n"
        f"{count} interval{'s' if count != 1 else ''}, {result.matched} of {result.ticks} robot ticks match"
        f" ({result.unknown} unknown)"
    )
    if result.intervals:
        width = max(5, *(len(i.robot) for i in result.intervals))
        print(f"{'robot':<{width}}  {'first':>7}  {'last':>7}  {'from':>11}  {'to':>11}  {'ticks':>6}")
        for interval in result.intervals:
            print(
                f"{interval.robot:<{width}}  {interval.first_seq:>7}  {interval.last_seq:>7}  "
                f"{_seconds(interval.first_t_ms):>11}  {_seconds(interval.last_t_ms):>11}  {interval.ticks:>6}"
            )
    by_reason: dict[str, list[str]] = {}
    for robot, why in result.skipped.items():
        by_reason.setdefault(why, []).append(robot)
    for why, robots in by_reason.items():
        print(f"not evaluated for {', '.join(robots)}: {why}")
    return 0
