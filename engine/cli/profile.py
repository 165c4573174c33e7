"""``xabsl profile``: time shares, activations, transitions, oscillations and coverage of a recording.

``xabsl profile RECORDING [--agent NAME] [--html OUT] [--json] [--oscillation-ms 1000]``

Prints rich tables (per team and agent), or the report document of docs/profile.md with
``--json``; ``--html OUT`` also writes the self-contained HTML report.

``xabsl profile A.mcap --against B.mcap [--team KEY] [--against-team KEY] [--against-agent NAME]
[--window-ms 1000] [--html OUT] [--json]`` is the behavioral diff
(:mod:`xabsl_studio.engine.profile.against`, docs/compare.md): per option and state of the teams
compared, the change of time share with its significance, activations, mean durations and the
transitions taken, the options that ran on one side only first.

Exit status: 0 success, 2 usage and I/O problems (no such file, not a recording, an unknown
agent or team, a bad threshold).
"""

from __future__ import annotations

import argparse
import math
import os
import sys

from xabsl_studio.engine.cli import UsageError


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``xabsl profile`` to the command line."""
    parser = subparsers.add_parser(
        "profile",
        help="profile a recording: time per option and state, transitions, oscillations, coverage",
        description=(
            "Count a recording (xabsl run ... --record FILE.mcap): per agent and per team the share of time, "
            "activations, mean and longest duration of every option and state, each option's transitions and "
            "decision leaves, oscillations (an option or state re-entered within --oscillation-ms), and the "
            "options, states, transitions and leaves never reached."
        ),
    )
    parser.add_argument("recording", metavar="RECORDING", help="an .mcap recording")
    parser.add_argument("--agent", action="append", metavar="NAME", help="profile only this agent (robot); repeatable")
    parser.add_argument("--html", metavar="OUT", help="also write the HTML report (one self-contained file)")
    parser.add_argument("--json", action="store_true", help="print the report as JSON (docs/profile.md)")
    parser.add_argument(
        "--oscillation-ms",
        type=float,
        default=1000.0,
        metavar="MS",
        help="an option or state re-entered within this many ms is an oscillation (default 1000)",
    )
    parser.add_argument(
        "--against", metavar="B.mcap", help="compare with this recording: the behavioral diff (docs/compare.md)"
    )
    parser.add_argument("--team", metavar="KEY", help="with --against: the team (program key) of RECORDING compared")
    parser.add_argument("--against-team", metavar="KEY", help="with --against: the team of B.mcap (default: --team)")
    parser.add_argument(
        "--against-agent",
        action="append",
        metavar="NAME",
        help="with --against: profile only this robot of B.mcap; repeatable (default: the --agent names)",
    )
    parser.add_argument(
        "--window-ms",
        type=float,
        default=1000.0,
        metavar="MS",
        help="with --against: robot time counted as one trial of a time share (default 1000)",
    )
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Profile the recording; print tables or JSON; write the HTML report."""
    import orjson

    from xabsl_studio.engine.files import write_atomically
    from xabsl_studio.engine.profile import ProfileError, profile
    from xabsl_studio.engine.record import Recording, RecordingError

    if not os.path.isfile(args.recording):
        raise UsageError(f"no such file: {args.recording}")
    if not math.isfinite(args.oscillation_ms) or args.oscillation_ms <= 0:
        raise UsageError(f"--oscillation-ms must be a positive number, got {args.oscillation_ms}")
    if args.html and os.path.isdir(args.html):
        raise UsageError(f"--html names a folder: {args.html}")
    if args.against is not None:
        return run_against(args)
    for flag in ("team", "against_team", "against_agent"):
        if getattr(args, flag) is not None:
            raise UsageError(f"--{flag.replace('_', '-')} needs --against")
    try:
        with Recording(args.recording) as recording:
            report = profile(recording, args.agent, args.oscillation_ms)
            descriptions = {}
            for agent, section in report["agents"].items():
                key = section["program"]
                if key not in descriptions:
                    gens = [g for (k, g) in recording.programs if k == key]
                    descriptions[key] = recording.program(agent, max(gens)).description
    except (ProfileError, RecordingError) as error:
        raise UsageError(str(error)) from error
    if args.html:
        from xabsl_studio.engine.profile.html import html_report

        try:
            write_atomically(args.html, html_report(report, descriptions).encode("utf-8"))
        except OSError as error:
            raise UsageError(f"cannot write {args.html}: {error.strerror}") from error
    if args.json:
        sys.stdout.write(orjson.dumps(report, option=orjson.OPT_INDENT_2).decode("utf-8") + "\n")
    else:
        from xabsl_studio.engine.profile.terminal import print_report

        print_report(report, details=bool(args.agent))
        if args.html:
            print(f"wrote {args.html}")
    return 0


def run_against(args: argparse.Namespace) -> int:
    """The behavioral diff of RECORDING against ``--against``: tables, JSON, HTML."""
    import orjson

    from xabsl_studio.engine.files import write_atomically
    from xabsl_studio.engine.profile import ProfileError, profile
    from xabsl_studio.engine.profile.against import compare_reports
    from xabsl_studio.engine.record import Recording, RecordingError

    if not os.path.isfile(args.against):
        raise UsageError(f"no such file: {args.against}")
    if not math.isfinite(args.window_ms) or args.window_ms <= 0:
        raise UsageError(f"--window-ms must be a positive number, got {args.window_ms}")
    try:
        with Recording(args.recording) as a:
            report_a = profile(a, args.agent, args.oscillation_ms)
        with Recording(args.against) as b:
            report_b = profile(b, args.against_agent or args.agent, args.oscillation_ms)
        document = compare_reports(report_a, report_b, args.team, args.against_team, args.window_ms)
    except (ProfileError, RecordingError) as error:
        raise UsageError(str(error)) from error
    if args.html:
        from xabsl_studio.engine.profile.against_report import html_report

        try:
            write_atomically(args.html, html_report(document).encode("utf-8"))
        except OSError as error:
            raise UsageError(f"cannot write {args.html}: {error.strerror}") from error
    if args.json:
        sys.stdout.write(orjson.dumps(document, option=orjson.OPT_INDENT_2).decode("utf-8") + "\n")
    else:
        from xabsl_studio.engine.profile.against_report import print_report

        print_report(document)
        if args.html:
            print(f"wrote {args.html}")
    return 0
