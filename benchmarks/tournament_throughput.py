"""Does a tournament on Ray keep up with the local process pool? Matches per core-hour, side by side.

The same matches (the soccer example against itself, ``--matches`` of ``--duration`` simulated
seconds each, 5 vs 5) are played by the two runners of ``xabsl tournament``: the process pool
(``-j``) and a Ray instance started in this process (``--ray local``, the same number of CPUs).
Both count from the first match handed out to the last result, runner start-up included (that
is what a user waits for). Printed: wall seconds, matches per core-hour, and Ray's ratio to the
pool (goal: >= 0.8). ``--address HOST:PORT`` adds a run on a cluster started with ``ray start``.

Usage: ``.venv/bin/python benchmarks/tournament_throughput.py [--matches 16] [--duration 60] [--jobs 2]``
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path
from typing import Any

from xabsl_studio.engine.lang import compile_file
from xabsl_studio.examples.soccer.tournament.match import MatchSpec
from xabsl_studio.examples.soccer.tournament.runners import run_local, run_ray

SOCCER = Path(__file__).resolve().parents[1] / "examples" / "soccer" / "behavior" / "agents.xabsl"


def timed(label: str, run: Any, matches: int, cores: int) -> float:
    results: list[dict[str, Any]] = []
    start = time.perf_counter()
    run(results.append)
    wall = time.perf_counter() - start
    failed = [r for r in results if not r.get("ok")]
    rate = matches / (wall * cores / 3600)
    print(f"{label:<22} {wall:7.2f} s wall  {rate:8.0f} matches per core-hour  ({len(failed)} failed)")
    return rate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--matches", type=int, default=16)
    parser.add_argument("--duration", type=float, default=60.0, help="simulated seconds per match")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--address", default=None, help="also a cluster started with `ray start`")
    args = parser.parse_args()
    program = compile_file(SOCCER).program
    programs = (program, program)
    specs = [
        MatchSpec(index=i, seed=1 + i // 2, home_blue=i % 2 == 0, half_duration_s=args.duration / 2, players=5)
        for i in range(args.matches)
    ]
    print(f"{args.matches} matches of {args.duration:g} s, 5 vs 5, {args.jobs} cores")
    pool = timed("process pool", lambda on: run_local(specs, programs, args.jobs, on), args.matches, args.jobs)
    ray = timed("ray local", lambda on: run_ray(specs, programs, "local", args.jobs, on), args.matches, args.jobs)
    print(f"ray local / pool: {ray / pool:.2f}x (goal >= 0.8)")
    if args.address:
        joined = timed(
            f"ray {args.address}", lambda on: run_ray(specs, programs, args.address, None, on), args.matches, args.jobs
        )
        print(f"ray {args.address} / pool: {joined / pool:.2f}x")


if __name__ == "__main__":
    main()
