"""What does "Run from here" cost? A fork re-simulates from the seed to the tick (no snapshots).

Question (issue 12 item 4): a fork rebuilds the world from its seed and replays the session log
up to the tick, so its cost is the headless tick cost times the ticks since the last reset. Runs
``xabsl_studio.server.simulation.worker.Simulation`` with the server's ring
(``xabsl_studio.server.session.frames``) in one process on the soccer example, 5 vs 5:
``--ticks`` live ticks (sampled and recorded as the studio does, a force and an override on the
way), then a fork at the newest tick. Printed: the live ticks' wall time,
the fork's ticks and milliseconds, and ms per re-simulated tick.

    .venv/bin/python benchmarks/live_fork_cost.py [--ticks 4800]
"""

from __future__ import annotations

import argparse
from pathlib import Path
from time import perf_counter

from xabsl_studio.examples.soccer.studio import SoccerExample
from xabsl_studio.server.protocol.commands import ForceOption, OverrideInput, Release
from xabsl_studio.server.protocol.host import FromWorker, NewGeneration, Sample
from xabsl_studio.server.session.frames import FrameRecorder, Generation, Ring
from xabsl_studio.server.session.live import Session, fork_request
from xabsl_studio.server.simulation.worker import Simulation, WorkerConfig

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    """Run the live ticks, fork at the newest one, print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=4800, help="live ticks before the fork (4800: the 120 s ring)")
    args = parser.parse_args()
    example = SoccerExample(ROOT / "examples" / "soccer", players_per_team=5)
    session = Session(example, seed=1)  # compiles; its process is never started
    programs = {k: (s.running, s.running_json) for k, s in session.programs.items()}
    sim = Simulation(WorkerConfig(example, seed=1, programs=programs, history_ticks=args.ticks + 10))  # type: ignore[arg-type]
    ring = Ring((args.ticks + 10) / sim.behavior_hz, sim.behavior_hz)
    recorder = FrameRecorder(ring)
    generation: list[Generation] = []

    def emit(message: FromWorker, droppable: bool = False) -> bool:
        if isinstance(message, NewGeneration):
            generation[:] = [Generation.from_message(message)]
        elif isinstance(message, Sample):
            recorder.record(generation[0], message)
        return True

    sim.emit = emit
    emit(sim.generation("connect"))
    emit(sim.sample())
    started = perf_counter()
    for i in range(args.ticks):
        if i == args.ticks // 3:
            sim.execute(ForceOption(op="force_option", robot=0, option="search_ball"))
            sim.execute(OverrideInput(op="override_input", robot=1, symbol="ball.seen", value=False))
        if i == args.ticks // 2:
            sim.execute(Release(op="release", robot=0))
        emit(sim.tick())
    live = perf_counter() - started
    latest = ring.latest
    assert latest is not None
    result = sim.execute(fork_request(ring, latest.seq))
    print(f"live: {args.ticks} ticks (10 robots, sampled and recorded) in {live:.2f} s")
    print(
        f"fork at the newest tick: {result['ticks']} ticks re-simulated and checked in {result['ms']:.0f} ms "
        f"({result['ms'] / max(1, result['ticks']):.3f} ms per tick)"
    )


if __name__ == "__main__":
    main()
