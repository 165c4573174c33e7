"""What does a fork cost, and why is it re-simulation rather than restoring a copied pymunk space?

Question (issue 12, "Fork: run from here"): a fork restarts a recorded world at tick ``k`` with
the current behavior. ``xabsl_studio.engine.record.fork.resimulate`` gets there exactly by re-running ticks
``0 .. k - 1`` from the recorded seed; world snapshots would bound that cost if a copied world
continued exactly like the original.

Runs, in one process: one recorded 5 vs 5 soccer match of ``--seconds`` simulated seconds
(example team vs chase team), then forks at a quarter, half and the end of it, each timed (the
re-simulation and its check against the recording) and printed against the simulated time it
re-runs (how many times faster than real time a fork gets there) and against the plain match's
own wall time for the same ticks (ratio ~1: re-simulation costs what the match cost). Then the
snapshot question: at ``--copies`` ticks of the same match, the soccer world's pymunk space is
copied (``Space.copy()``) and both spaces coast ``--coast`` physics steps side by side with the
same inputs (none); printed is how many copies ended bit-identical to their originals, and the
largest position difference. A copy that drifts is not a snapshot a fork can start from.

    .venv/bin/python benchmarks/fork_cost.py [--seconds 600] [--copies 20] [--coast 600]
"""

from __future__ import annotations

import argparse
import random
import tempfile
import time
from pathlib import Path

import pymunk
import record_cost  # benchmarks/ is the script's folder: the same recorded match as the cost benchmark

from xabsl_studio.engine.host import DEFAULT_BEHAVIOR_HZ, DEFAULT_PHYSICS_HZ, BehaviorLoop
from xabsl_studio.engine.record import Recording
from xabsl_studio.engine.record.fork import resimulate
from xabsl_studio.examples.soccer.run import DEFAULT_AWAY, DEFAULT_HOME, build_world, load_team


def record(path: Path, seconds: float, seed: int, programs: tuple[object, object]) -> float:
    """Record the match; returns the plain (unrecorded) match's wall time for the same ticks."""
    wall, _cpu, _scene = record_cost.plain(seconds, seed, programs)
    record_cost.recorded(seconds, seed, programs, path, background=False)
    return wall


def coast(space: pymunk.Space, steps: int, dt: float) -> list[tuple[float, float]]:
    for _ in range(steps):
        space.step(dt)
    return [tuple(body.position) for body in space.bodies]  # type: ignore[misc]


def contacts(space: pymunk.Space) -> int:
    """How many colliding shape pairs the space holds (its arbiters, seen from each body)."""
    seen: list[pymunk.Arbiter] = []
    for body in space.bodies:
        body.each_arbiter(seen.append)
    return len(seen)


def copies_exact(
    seconds: float, seed: int, programs: tuple[object, object], n: int, steps: int
) -> tuple[int, float, int, int]:
    """Of ``n`` space copies: how many coast exactly like their originals, the largest drift (m),
    how many were taken while no two shapes touched, and how many of those were exact."""
    world = build_world(seed, *programs, players=5)  # type: ignore[arg-type]
    loop = BehaviorLoop(world, DEFAULT_PHYSICS_HZ, DEFAULT_BEHAVIOR_HZ)
    total = int(seconds * DEFAULT_BEHAVIOR_HZ)
    at = sorted(random.Random(seed).sample(range(1, total), n))
    exact, drift, done, untouched, exact_untouched = 0, 0.0, 0, 0, 0
    for tick in at:
        while done < tick:
            loop.tick()
            done += 1
        space = world.physics.space
        touching = contacts(space)
        copied = coast(space.copy(), steps, 1 / DEFAULT_PHYSICS_HZ)
        live = coast(space, steps, 1 / DEFAULT_PHYSICS_HZ)  # the match then goes on from the coasted state
        exact += copied == live
        exact_untouched += copied == live and not touching
        untouched += not touching
        drift = max(drift, *(abs(a - b) for p, q in zip(live, copied, strict=True) for a, b in zip(p, q, strict=True)))
    return exact, drift, untouched, exact_untouched


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=600.0, help="simulated seconds recorded (default 600)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--copies", type=int, default=20, help="space copies checked (default 20)")
    parser.add_argument("--coast", type=int, default=600, help="physics steps each copy coasts (default 600)")
    args = parser.parse_args()

    programs = (load_team(DEFAULT_HOME), load_team(DEFAULT_AWAY))
    path = Path(tempfile.mkdtemp(prefix="fork_cost_")) / "match.mcap"
    plain = record(path, args.seconds, args.seed, programs)
    with Recording(path) as recording:
        ticks = len(recording)
        print(f"soccer 5 vs 5, {args.seconds:.0f} simulated s recorded ({ticks} ticks), seed {args.seed}")
        print(f"  the plain match: {plain:.2f} s wall")
        for share in (0.25, 0.5, 1.0):
            at = max(1, min(ticks - 1, int(share * ticks)))
            started = time.perf_counter()
            loop = resimulate(recording, lambda seed: build_world(seed, *programs, players=5), at)
            spent = time.perf_counter() - started
            loop.tick()
            simulated = at / DEFAULT_BEHAVIOR_HZ
            print(
                f"  fork at tick {at:6d} ({simulated:6.1f} s): {spent:5.2f} s wall, "
                f"{simulated / spent:5.0f}x real time, {spent / (plain * at / ticks):4.2f}x the plain match's time"
            )
    exact, drift, untouched, exact_untouched = copies_exact(args.seconds, args.seed, programs, args.copies, args.coast)
    print(
        f"  Space.copy() of the soccer world at {args.copies} random ticks, coasting {args.coast} physics steps: "
        f"{exact} of {args.copies} bit-identical to the original, largest drift {drift:.3g} m; "
        f"taken while nothing touched: {untouched}, of them exact: {exact_untouched}"
    )


if __name__ == "__main__":
    main()
