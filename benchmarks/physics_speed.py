"""How fast does the soccer world run without behaviors? 10 simulated minutes of 5 vs 5, headless.

The controllers are the scripted placeholder (``xabsl_studio.examples.soccer.scripted``), so the "engine"
share here is only that placeholder; what this measures is the world's own cost (physics,
perception, actuation). The product goal is a whole match *with XABSL behaviors* at >= 100x real
time on a 2-core machine, so the world must leave most of that budget to the engine.

Usage: ``.venv/bin/python benchmarks/physics_speed.py [--seconds 600] [--seed 1] [--players 5]``
"""

from __future__ import annotations

import argparse
import time

from _report import print_run  # benchmarks/ is the script's folder

from xabsl_studio.engine.host import DEFAULT_BEHAVIOR_HZ, DEFAULT_PHYSICS_HZ, run_headless
from xabsl_studio.examples.soccer.scripted import plug_scripted_team
from xabsl_studio.examples.soccer.world import build_world


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=600.0, help="simulated seconds (default 600)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--players", type=int, default=5, help="players per team (1..7)")
    parser.add_argument("--physics-hz", type=int, default=DEFAULT_PHYSICS_HZ)
    parser.add_argument("--behavior-hz", type=int, default=DEFAULT_BEHAVIOR_HZ)
    args = parser.parse_args()

    # Halves long enough that the match does not end before the simulated time does.
    world = build_world(args.seed, players_per_team=args.players, half_duration_s=args.seconds / 2)
    plug_scripted_team(world)
    cpu_start = time.process_time()
    stats = run_headless(
        world, args.seconds, physics_hz=args.physics_hz, behavior_hz=args.behavior_hz, stop_when_finished=False
    )
    cpu = time.process_time() - cpu_start

    agent_ticks = stats.ticks * len(world.agents)
    phases = stats.phases
    print_run(
        f"soccer world, {args.players} vs {args.players}, seed {args.seed}",
        stats,
        cpu,
        args.physics_hz,
        args.behavior_hz,
        [
            ("physics", phases.physics),
            ("perception", phases.perception),
            ("controller (scripted)", phases.engine),
            ("actuation", phases.actuation),
        ],
    )
    per_agent_us = 1e6 * (phases.perception + phases.actuation) / agent_ticks
    print(
        f"world cost per agent tick (perception + actuation): {per_agent_us:.1f} us; "
        f"physics per step: {1e6 * phases.physics / stats.physics_steps:.1f} us"
    )
    budget = args.seconds / 100.0 - (phases.physics + phases.perception + phases.actuation)
    print(
        f"left for the XABSL engine at 100x real time: {budget:.2f} s "
        f"= {1e6 * budget / agent_ticks:.1f} us per agent tick"
    )
    status = world.status()
    print(
        f"score {status['teams'][0]} {status['score'][0]} : {status['score'][1]} {status['teams'][1]}, "
        f"outs {status['outs']}, state {status['game_state']}"
    )


if __name__ == "__main__":
    main()
