"""How fast does one errand run headless? (target: ≥ 200× real time; dual-dynamics.md §4.4, examples/errands)

One errand = GRAPHPLAN from the problem's facts plus 90 simulated seconds of the errands world
with the XABSL plan monitor (the errand itself finishes after about 63 s; the robot then roams
until 90 s), at the §4.1 rates: 50 Hz behavior tick, 2 × 10 ms pymunk steps.

Prints the real-time factor from wall time and from process CPU time (the CPU figure is what a
quiet machine gives; on a shared machine the wall figure drops with the load), best of N runs,
then the share of each part of a tick from one instrumented run: Dual Dynamics, XABSL engine,
physics, fact derivation, sensors and the rest.

Usage: python benchmarks/errands_speed.py [--runs N] [--seconds S]
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from typing import Any

from xabsl_studio.engine.host import run_headless
from xabsl_studio.examples.errands.world import build_world


def one_run(seconds: float) -> tuple[float, float, bool]:
    world = build_world(1)
    cpu, wall = time.process_time(), time.perf_counter()
    run_headless(world, seconds, physics_hz=100, behavior_hz=50, stop_when_finished=False)
    return time.perf_counter() - wall, time.process_time() - cpu, world.completed


def shares(seconds: float) -> tuple[dict[str, float], float]:
    """Seconds per part from one run with timers around each part."""
    world = build_world(1)
    spent: dict[str, float] = {}

    def timed(obj: Any, name: str, key: str) -> None:
        inner: Callable[..., Any] = getattr(obj, name)

        def wrapper(*args: Any, **kwargs: Any) -> Any:
            t = time.perf_counter()
            try:
                return inner(*args, **kwargs)
            finally:
                spent[key] = spent.get(key, 0.0) + time.perf_counter() - t

        setattr(obj, name, wrapper)

    timed(world.dd, "step", "Dual Dynamics (DDSystem.step)")
    timed(world.engine, "execute", "XABSL engine (plan monitor, incl. GRAPHPLAN calls)")
    timed(world.arena, "step", "physics (pymunk + gripper)")
    timed(world.deriver, "update", "fact derivation (FactDeriver.update)")
    timed(world.arena, "sense", "sensors (rays, bearings, detector)")
    wall = time.perf_counter()
    run_headless(world, seconds, physics_hz=100, behavior_hz=50, stop_when_finished=False)
    total = time.perf_counter() - wall
    spent["rest (signals, truth, agreement, bookkeeping, loop, timers)"] = total - sum(spent.values())
    planning = sum(r.seconds for r in world.board.results)
    return spent, planning


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=90.0)
    args = parser.parse_args()

    results = [one_run(args.seconds) for _ in range(args.runs)]
    best_wall = min(r[0] for r in results)
    best_cpu = min(r[1] for r in results)
    print(f"one errand, {args.seconds:g} simulated s, best of {args.runs} (completed: {all(r[2] for r in results)})")
    print(f"  wall {best_wall:.3f} s -> {args.seconds / best_wall:6.0f}x real time")
    print(f"  CPU  {best_cpu:.3f} s -> {args.seconds / best_cpu:6.0f}x real time (target >= 200x)")
    print(f"  {best_cpu / (args.seconds * 50) * 1e6:.0f} us CPU per 20 ms tick")

    spent, planning = shares(args.seconds)
    total = sum(spent.values())
    print("share of the tick (one instrumented run):")
    for key, value in sorted(spent.items(), key=lambda kv: -kv[1]):
        print(f"  {100 * value / total:5.1f}%  {key}")
    print(f"  GRAPHPLAN itself: {planning * 1000:.1f} ms in total (inside the XABSL engine share)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
