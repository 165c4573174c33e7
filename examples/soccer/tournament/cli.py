"""``xabsl tournament HOME AWAY``: the command line of soccer tournaments.

Registered under the ``xabsl.commands`` entry-point group (``tournament =
"xabsl_studio.examples.soccer.tournament.cli:register"`` in ``pyproject.toml``). Exit status: 0 every match
was played, 1 a behavior does not compile or a match failed, 2 usage, 130 interrupted (the
report of the finished matches is printed first).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

from xabsl_studio.engine.cli import UsageError

# This module registers `xabsl tournament` whenever `xabsl` starts: what a match needs loads when
# the command runs.
TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing
if TYPE_CHECKING:
    from typing import Any

    from xabsl_studio.engine.ir.model import Program


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not Linux
        return os.cpu_count() or 1


def _positive(kind: type, what: str) -> Any:
    def parse(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what} must be a number, got {text!r}") from None
        if not (math.isfinite(value) and value > 0):
            raise argparse.ArgumentTypeError(f"{what} must be positive and finite, got {text}")
        return value

    return parse


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``xabsl tournament`` to the command line."""
    parser = subparsers.add_parser(
        "tournament",
        help="play N seeded soccer matches between two behavior versions (folders or git:REV:PATH)",
        description=(
            "Play N seeded matches of the soccer world between two team behaviors and report wins, "
            "draws and losses with 95 % Wilson intervals, goal difference, team statistics and "
            "where the versions' option activations and decisions differ. Every seed is played "
            "twice, each version once as blue (kick-off) and once as red."
        ),
    )
    parser.add_argument("home", metavar="HOME", help="behavior folder with agents.xabsl, or git:REV:PATH")
    parser.add_argument("away", metavar="AWAY", help="the other version (e.g. git:HEAD~1:examples/soccer/behavior)")
    parser.add_argument("-n", "--matches", type=_positive(int, "-n"), default=10, help="matches (default 10)")
    parser.add_argument(
        "--duration",
        metavar="S",
        type=_positive(float, "--duration"),
        default=600.0,
        help="playing time per match in simulated seconds, two halves (default 600)",
    )
    parser.add_argument("--seed", metavar="S", type=int, default=1, help="seed of the first match pair (default 1)")
    parser.add_argument("--players", metavar="N", type=int, default=5, help="robots per team, 1..7 (default 5)")
    parser.add_argument(
        "-j",
        "--jobs",
        metavar="J",
        type=_positive(int, "--jobs"),
        default=None,
        help="worker processes (default: the cores)",
    )
    parser.add_argument(
        "--ray",
        metavar="ADDRESS",
        help=(
            "play on a Ray cluster: auto (join the one started with `ray start --head`), "
            "local (start one here), or HOST:PORT"
        ),
    )
    parser.add_argument(
        "--timeout",
        metavar="S",
        type=_positive(float, "--timeout"),
        default=600.0,
        help="wall-clock limit per match; a match over it is reported as failed (default 600)",
    )
    parser.add_argument(
        "--record",
        metavar="DIR",
        help=(
            "record every match into DIR (created if missing; match-NNN-seedS-home-COLOUR.mcap, "
            "with both versions' sources, so each can be replayed and forked); the report lists them"
        ),
    )
    parser.add_argument("--json", action="store_true", help="print the report as one JSON object")
    parser.add_argument("--html", metavar="OUT", help="also write the report as one self-contained HTML file")
    parser.set_defaults(func=main)


def main(args: argparse.Namespace) -> int:
    """Run the tournament the flags describe; returns the exit status."""
    import tempfile

    import orjson

    from xabsl_studio.engine.files import write_atomically
    from xabsl_studio.examples.soccer.run import TeamError, load_team
    from xabsl_studio.examples.soccer.tournament import match, report, runners, versions

    if not 1 <= args.players <= 7:
        raise UsageError(f"--players must be in 1..7, got {args.players}")
    jobs = args.jobs or _cores()
    with tempfile.TemporaryDirectory(prefix="xabsl-tournament-") as scratch:
        sides = [versions.resolve(spec, Path(scratch)) for spec in (args.home, args.away)]
        try:
            programs: tuple[Program, Program] = (load_team(sides[0].folder), load_team(sides[1].folder))
        except TeamError as error:
            print("\n".join(error.diagnostics), file=sys.stderr)
            print(f"xabsl tournament: {error}", file=sys.stderr)
            return 1
        sources: runners.Sources = (None, None)
        record_dir = None
        if args.record is not None:
            record_dir = _record_dir(args.record, args.ray)
            sources = (_sources(sides[0].folder, programs[0]), _sources(sides[1].folder, programs[1]))
    specs = match.plan(
        args.matches, args.seed, args.duration, players=args.players, timeout_s=args.timeout, record_dir=record_dir
    )
    results: list[dict[str, Any]] = []
    interrupted = False
    start = time.perf_counter()
    backend = f"ray {args.ray}" if args.ray else "local pool"
    with _progress(len(specs), quiet=args.json) as on_result:

        def collect(result: dict[str, Any]) -> None:
            results.append(result)
            on_result(result)

        try:
            if args.ray:
                jobs = runners.run_ray(specs, programs, args.ray, args.jobs, collect, sources)
            else:
                runners.run_local(specs, programs, jobs, collect, sources)
        except KeyboardInterrupt:
            interrupted = True
    wall = time.perf_counter() - start
    summary = report.summarize(
        results,
        home=args.home,
        away=args.away,
        planned=len(specs),
        wall_seconds=wall,
        jobs=jobs,
        backend=backend,
        interrupted=interrupted,
    )
    if args.html:
        try:
            page = report.html_report(summary, os.path.dirname(os.path.abspath(args.html)))
            write_atomically(args.html, page.encode("utf-8"))
        except OSError as error:
            raise UsageError(f"cannot write {args.html}: {error.strerror}") from error
    if args.json:
        sys.stdout.buffer.write(orjson.dumps(summary) + b"\n")
        sys.stdout.flush()
    else:
        report.print_report(summary)
    if interrupted:
        return 130
    return 1 if summary["failed"] else 0


def _record_dir(folder: str, ray: str | None) -> str:
    """The absolute folder ``--record`` writes to, created; a cluster of other machines is refused."""
    if ray is not None and ray != "local":
        # a match's recording is written by the process that plays it: on a cluster, another machine's disk
        raise UsageError("--record writes where each match runs: use it with the process pool or --ray local")
    path = Path(folder).expanduser().resolve()
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UsageError(f"--record {folder}: {error.strerror}") from None
    if not os.access(path, os.W_OK):
        raise UsageError(f"--record {folder}: not writable")
    return str(path)


def _sources(folder: Path, program: Program) -> dict[str, Any]:
    """A version's source files, for its recordings (forks re-simulate with them)."""
    from xabsl_studio.engine.record.sources import program_sources

    return program_sources(folder / "agents.xabsl", program.files)


class _progress:
    """A rich progress bar on stderr (only on a terminal): matches done, score so far, failures."""

    def __init__(self, total: int, quiet: bool) -> None:
        from rich.console import Console
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

        console = Console(stderr=True)
        self.bar = Progress(
            TextColumn("[bold]matches"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[tally]}"),
            TimeElapsedColumn(),
            console=console,
            transient=True,
            disable=not console.is_terminal,
        )
        self.task = self.bar.add_task("matches", total=total, tally="")
        self.tally = {"win": 0, "draw": 0, "loss": 0, "failed": 0}

    def __enter__(self) -> Any:
        self.bar.__enter__()
        return self.update

    def __exit__(self, *exc: object) -> None:
        self.bar.__exit__(*exc)  # type: ignore[arg-type]

    def update(self, result: dict[str, Any]) -> None:
        if result["ok"]:
            h, a = result["score"]["home"], result["score"]["away"]
            self.tally["win" if h > a else "loss" if h < a else "draw"] += 1
        else:
            self.tally["failed"] += 1
            self.bar.console.print(
                f"match {result['index']} (seed {result['seed']}) failed: {result['error']}", markup=False
            )
        t = self.tally
        self.bar.update(
            self.task,
            advance=1,
            tally=f"HOME W {t['win']} D {t['draw']} L {t['loss']}" + (f"  failed {t['failed']}" if t["failed"] else ""),
        )
