"""How fast does a whole XABSL match run? 10 simulated minutes of 5 vs 5, headless.

Both teams are XABSL behaviors run by the engine: the example team (31 options) at home, the
chase team (2 options) away, as ``xabsl run examples/soccer`` plays them but without statistics
or activation recording. Prints wall and CPU time, the real-time factor (goal: >= 100x on a
2-core machine), the share of each phase of the host loop (``run_headless``'s phase times), and
the engine's cost per agent tick split by team. ``--profile`` adds a cProfile of the engine phase
alone (the functions where the engine's ticks spend their time).

``--whole N`` instead measures the whole process the issue's goal is about: ``xabsl run
examples/soccer --duration 300 --json`` (interpreter start-up, imports, compiling both teams,
the match with statistics and activation recording, the JSON), N times as a user runs it (which
records the match into the cache: a temporary one here) and N times with ``--no-record``,
alternating, and prints the best and median wall and CPU time (user + system of the child, from
``resource.getrusage``) and the real-time factor against the 300 s of play (goal: >= 150x) of
each. CPU time is the figure to trust on the shared development machine: other jobs inflate wall
time.

Usage: ``.venv/bin/python benchmarks/match_speed.py [--seconds 600] [--seed 1] [--profile] [--whole 5]``
"""

from __future__ import annotations

import argparse
import cProfile
import os
import pstats
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _report import print_run  # benchmarks/ is the script's folder

from xabsl_studio.engine.host import DEFAULT_BEHAVIOR_HZ, DEFAULT_PHYSICS_HZ, BehaviorLoop, run_headless
from xabsl_studio.examples.soccer.run import build_world


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=600.0, help="simulated seconds (default 600)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--profile", action="store_true", help="also profile the engine phase (slower run)")
    parser.add_argument("--whole", metavar="N", type=int, help="time N whole `xabsl run` processes instead")
    args = parser.parse_args()
    if args.whole:
        whole_process(args.whole, args.seed)
        return

    # Halves long enough that the match does not end before the simulated time does.
    world = build_world(args.seed, half_duration_s=args.seconds / 2)
    cpu_start = time.process_time()
    stats = run_headless(world, args.seconds, stop_when_finished=False)
    cpu = time.process_time() - cpu_start

    agent_ticks = stats.ticks * len(world.agents)
    phases = stats.phases
    print_run(
        f"XABSL match, 5 vs 5 (example team vs chase), seed {args.seed}",
        stats,
        cpu,
        DEFAULT_PHYSICS_HZ,
        DEFAULT_BEHAVIOR_HZ,
        [
            ("engine (XABSL)", phases.engine),
            ("physics", phases.physics),
            ("perception", phases.perception),
            ("actuation", phases.actuation),
        ],
    )
    print(f"engine per agent tick: {1e6 * phases.engine / agent_ticks:.1f} us (both teams)")
    status = world.status()
    print(f"score {status['teams'][0]} {status['score'][0]} : {status['score'][1]} {status['teams'][1]}")

    # Engine cost per team: tick each team's controllers alone for a while on a fresh match.
    world = build_world(args.seed, half_duration_s=args.seconds / 2)
    loop = BehaviorLoop(world)
    for _ in range(40 * 30):  # into PLAYING
        loop.tick()
    per_team = [0.0, 0.0]
    ticks = 40 * 60
    for _ in range(ticks):
        now = loop.now_ms
        for agent in world.agents:
            agent.sense(now)
        for team in (0, 1):
            t0 = time.perf_counter()
            for agent in world.agents[5 * team : 5 * team + 5]:
                agent.controller.execute(now)
            per_team[team] += time.perf_counter() - t0
        for agent in world.agents:
            agent.act(now)
        for _ in range(DEFAULT_PHYSICS_HZ // DEFAULT_BEHAVIOR_HZ):
            world.step(1 / DEFAULT_PHYSICS_HZ)
        loop.ticks += 1
    for team, name in ((0, "example team (31 options)"), (1, "chase team (2 options)")):
        print(f"  {name:<28} {1e6 * per_team[team] / (5 * ticks):5.1f} us per agent tick")

    if args.profile:
        profiler = cProfile.Profile()
        for _ in range(ticks):
            now = loop.now_ms
            for agent in world.agents:
                agent.sense(now)
            profiler.enable()
            for agent in world.agents:
                agent.controller.execute(now)
            profiler.disable()
            for agent in world.agents:
                agent.act(now)
            for _ in range(DEFAULT_PHYSICS_HZ // DEFAULT_BEHAVIOR_HZ):
                world.step(1 / DEFAULT_PHYSICS_HZ)
            loop.ticks += 1
        pstats.Stats(profiler).sort_stats("tottime").print_stats(25)


def whole_process(runs: int, seed: int, play_s: float = 300.0) -> None:
    """Time ``xabsl run examples/soccer --duration 300 --json``, recorded and not, ``runs`` times each."""
    root = Path(__file__).resolve().parents[1]
    xabsl = Path(sys.executable).with_name("xabsl")
    command = [str(xabsl), "run", "examples/soccer", "--duration", str(play_s), "--seed", str(seed), "--json"]
    with tempfile.TemporaryDirectory(prefix="match-speed-") as cache:
        # the default run records into the cache: a temporary one, not the user's
        env = {**os.environ, "PYTHONPATH": str(root), "XDG_CACHE_HOME": cache}
        variants = {"recorded (the default)": command, "--no-record": [*command, "--no-record"]}
        times: dict[str, tuple[list[float], list[float]]] = {name: ([], []) for name in variants}
        for _ in range(runs):
            for name, argv in variants.items():  # alternating: drift of a shared machine hits both
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                start = time.perf_counter()
                subprocess.run(argv, cwd=root, env=env, check=True, stdout=subprocess.DEVNULL)
                times[name][0].append(time.perf_counter() - start)
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
                times[name][1].append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    print(f"whole process: {' '.join(command[1:])}, {runs} runs each")
    for name, (walls, cpus) in times.items():
        print(f"  {name}")
        for label, values in (("wall", walls), ("cpu", cpus)):
            best, median = min(values), statistics.median(values)
            print(
                f"    {label:<4} best {best:.2f} s ({play_s / best:.0f}x real time), "
                f"median {median:.2f} s ({play_s / median:.0f}x)"
            )


if __name__ == "__main__":
    main()
