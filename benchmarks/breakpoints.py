"""What do breakpoints cost per tick? The studio's simulation tick with none, and with several set.

Question (issue 13, "Cheap: compiled like the behavior, measured in a benchmark"): with no
breakpoint enabled the tick path must not pay for them (one attribute read per tick); with
breakpoints set, each costs one generated function call per robot and tick.

Runs ``xabsl_studio.server.simulation.worker.Simulation`` (the simulation process's tick: world, engines, sampling) on
the soccer example, 5 vs 5, ``--ticks`` ticks per run, alternating so that drift of a shared
machine hits all sides alike (``--repeat`` rounds): (a) no breakpoints, (b) breakpoints set but
all disabled, (c) one breakpoint of each kind for any robot (six per robot of the example team,
chosen so that they rarely or never hit: a hit only pauses, which the benchmark ignores). Printed:
ms per tick of each (median over rounds), the overhead of (b) and (c) over (a), and the cost per
breakpoint and robot check in microseconds.

    .venv/bin/python benchmarks/breakpoints.py [--ticks 2000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from xabsl_studio.engine.runtime.breakpoints import Breakpoint
from xabsl_studio.examples.soccer.studio import SoccerExample
from xabsl_studio.server.session.live import Session
from xabsl_studio.server.simulation.worker import Simulation, WorkerConfig

ROOT = Path(__file__).resolve().parents[1]

POINTS = (
    Breakpoint(1, "enter_option", option="game_finished"),
    Breakpoint(2, "leave_option", option="game_finished"),
    Breakpoint(3, "enter_state", option="play_soccer", state="finished"),
    Breakpoint(4, "leave_state", option="play_soccer", state="finished"),
    Breakpoint(5, "leaf", option="play_soccer", state="finished", leaf=0),
    Breakpoint(6, "condition", condition="ball.distance < 0 && game.state == game.state.playing"),
)


def simulation(session: Session, points: tuple[Breakpoint, ...]) -> Simulation:
    config = WorkerConfig(
        example=session.example,
        seed=1,
        programs={
            key: (state.running, state.running_json)
            for key, state in session.programs.items()
            if state.running is not None and state.running_json is not None
        },
        breakpoints={"behavior": points},
    )
    sim = Simulation(config)
    sim.generation("connect")
    return sim


def run(session: Session, points: tuple[Breakpoint, ...], ticks: int) -> tuple[float, int]:
    sim = simulation(session, points)
    for _ in range(40):  # warm up: first ticks compile the checks
        sim.tick()
    hits = 0
    started = time.perf_counter()
    for _ in range(ticks):
        sim.tick()
        hits += len(sim.take_hits())
    return (time.perf_counter() - started) * 1000 / ticks, hits


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--ticks", type=int, default=2000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    example = SoccerExample(ROOT / "examples" / "soccer", players_per_team=5, half_duration_s=600)
    session = Session(example, state_dir=Path("/nonexistent-breakpoints-benchmark"))
    disabled = tuple(Breakpoint(p.id, p.kind, p.option, p.state, p.leaf, p.condition, enabled=False) for p in POINTS)
    sides = {"none": (), "disabled": disabled, "six": POINTS}
    times: dict[str, list[float]] = {name: [] for name in sides}
    hits: dict[str, int] = dict.fromkeys(sides, 0)
    for _ in range(args.repeat):
        for name, points in sides.items():
            ms, hit = run(session, points, args.ticks)
            times[name].append(ms)
            hits[name] += hit
    base = statistics.median(times["none"])
    robots = 5  # the example team runs the breakpoints' behavior
    print(f"{args.ticks} ticks x {args.repeat} rounds, soccer 5 vs 5 (median ms per simulation tick)")
    for name in sides:
        ms = statistics.median(times[name])
        print(f"  {name:9s} {ms:7.3f} ms/tick  {100 * (ms - base) / base:+6.2f} %  hits {hits[name]}")
    six = statistics.median(times["six"])
    per_check = (six - base) * 1000 / (len(POINTS) * robots)
    print(f"  per breakpoint and robot: {per_check:.2f} us per tick")


if __name__ == "__main__":
    main()
