"""How long does the HTML documentation of a large behavior set take, next to compiling it?

Generates the seeded behavior set of ``benchmarks/compile_speed.py`` with 180 options (the size
of a real robot soccer set), compiles it, writes its documentation (``xabsl_studio.engine.docs.generate``:
Graphviz for the option graphs and state machines, then the pages, then the files) and prints
both times side by side, with the documentation's stages. The goal is under 10 s for the docs.

Run::

    .venv/bin/python benchmarks/docs_speed.py                 # 180 options, best of 3
    .venv/bin/python benchmarks/docs_speed.py --options 400 --jobs 1

Never run from the test suite.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks.compile_speed import DEFAULT_SEED, generate_behavior_set, measure, source_size  # noqa: E402
from xabsl_studio.engine.docs import generate  # noqa: E402

GOAL_SECONDS = 10.0
DEFAULT_OPTIONS = 180


def main(argv: list[str] | None = None) -> int:
    """Print compile and documentation times of one generated set."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--options", type=int, default=DEFAULT_OPTIONS)
    parser.add_argument("--seed", type=int, default=DEFAULT_SEED)
    parser.add_argument("--runs", type=int, default=3, help="generate this many times, keep the best")
    parser.add_argument("--jobs", type=int, default=None, help="dot processes (default: one per core)")
    args = parser.parse_args(argv)

    with tempfile.TemporaryDirectory(prefix="xabsl-docs-bench-") as folder:
        (Path(folder) / "set").mkdir()
        agents = generate_behavior_set(Path(folder) / "set", args.seed, args.options)
        best_compile, compilation = measure(agents, args.runs)
        program = compilation.program
        assert program is not None
        states = sum(len(o.states) for o in program.options.values())
        print(
            f"behavior set: {len(program.options)} options, {states} states, {len(program.agents)} agents, "
            f"{source_size(agents.parent) / 1024:.0f} KB (seed {args.seed}), best of {args.runs} runs, "
            f"{args.jobs or os.cpu_count()} dot jobs"
        )
        best: dict[str, float] = {}
        pages = 0
        for run in range(args.runs):
            started = time.perf_counter()
            result = generate(program, Path(folder) / f"docs{run}", args.jobs)
            total = time.perf_counter() - started
            pages = len(result.pages)
            for stage, seconds in (*result.timings.items(), ("total", total)):
                best[stage] = min(best.get(stage, float("inf")), seconds)
        print(f"  compile (parse + check + emit IC) {best_compile['total'] * 1000:8.1f} ms")
        print(
            f"  docs ({pages} pages)                {best['total'] * 1000:8.1f} ms   "
            f"(goal < {GOAL_SECONDS:.0f} s: {'met' if best['total'] < GOAL_SECONDS else 'MISSED'}; "
            f"{best['total'] / best_compile['total']:.0f}x the compile)"
        )
        for stage in ("graphs", "pages", "write"):
            print(f"    {stage:<8} {best[stage] * 1000:8.1f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
