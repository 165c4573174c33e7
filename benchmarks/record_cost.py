"""What does recording cost? The same headless 5 vs 5 match with and without ``--record``, in one run.

Question (issue 12, "Cost"): recording should add under 10 % to a headless match's wall time, a
10-minute 5 vs 5 match should be at most 50 MB, and sampling the engines (one mechanism for the
studio and for recordings) should cost at most 0.2 ms per tick for 10 agents.

Runs, alternating so that drift of a shared machine hits both sides alike (``--repeat`` pairs):
``--seconds`` simulated seconds of the soccer example (example team vs chase team, seed
``--seed``) without recording, then the same match recorded with ``xabsl_studio.engine.record.Recorder``
(exactly what ``xabsl run examples/soccer --record FILE.mcap`` does), inline and with the writer
process. Printed: wall and CPU time of each, the overhead in percent; then where the time goes,
per tick of 10 agents in CPU time and as a ratio of the plain tick: sampling the engines for a
recording and for the studio (the same sampler; measured in a run that samples and discards),
the world's ``dynamic_scene()``, and the encoder fed the operations a recorder captured (with the
Foxglove scene's and the MCAP writer's shares); the file size and its extrapolation to 10
simulated minutes, and how long seeking a random tick of the file takes. ``--full`` adds one
run of 600 simulated seconds recorded inline and prints its real size and seek times.

    .venv/bin/python benchmarks/record_cost.py [--seconds 120] [--repeat 2] [--full]
"""

from __future__ import annotations

import argparse
import os
import random
import statistics
import tempfile
import time
from pathlib import Path
from unittest.mock import patch

import orjson

from xabsl_studio.engine.host import DEFAULT_BEHAVIOR_HZ, DEFAULT_PHYSICS_HZ, run_headless
from xabsl_studio.engine.record import AgentSampler, Recorder, RecorderStats, Recording, engines_of
from xabsl_studio.engine.record.encoder import RecordingEncoder
from xabsl_studio.engine.record.mcapfile import McapWriter
from xabsl_studio.examples.soccer.run import DEFAULT_AWAY, DEFAULT_HOME, build_world, load_team

TEN_MINUTES_TICKS = 600 * DEFAULT_BEHAVIOR_HZ
MB = 1024 * 1024


def plain(seconds: float, seed: int, programs: tuple[object, object]) -> tuple[float, float, object]:
    world = build_world(seed, *programs, players=5)  # type: ignore[arg-type]
    cpu = time.process_time()
    wall = time.perf_counter()
    run_headless(world, duration_s=seconds)
    return time.perf_counter() - wall, time.process_time() - cpu, world.dynamic_scene()


def recorded(
    seconds: float, seed: int, programs: tuple[object, object], path: Path, background: bool
) -> tuple[float, float, object, RecorderStats]:
    world = build_world(seed, *programs, players=5)  # type: ignore[arg-type]
    cpu = time.process_time()
    wall = time.perf_counter()
    recorder = Recorder.for_world(
        path,
        world,
        lambda agent: ("behavior", "chase")[agent.team_index],  # type: ignore[attr-defined]
        example="soccer",
        behavior_hz=DEFAULT_BEHAVIOR_HZ,
        physics_hz=DEFAULT_PHYSICS_HZ,
        background=background,
    )
    run_headless(world, duration_s=seconds, on_tick=recorder.on_tick)
    stats = recorder.close()
    return time.perf_counter() - wall, time.process_time() - cpu, world.dynamic_scene(), stats


class Discard:
    """Stands in for the encoder: the recorder samples and captures every tick, nothing is encoded."""

    def __init__(self, **_options: object) -> None:
        self.path = ""

    def handle(self, op: tuple[object, ...]) -> None:
        """Drop the operation."""

    def close(self) -> tuple[str, int, int, int]:
        """No file."""
        return self.path, 0, 0, 0


def sampling_costs(seconds: float, seed: int, programs: tuple[object, object]) -> dict[str, float]:
    """CPU seconds per tick of the tick-path parts of recording and of the studio, in one match.

    Each tick: the project's one sampler for all agents as the recorder calls it
    (``AgentSampler.sample``), as the studio's simulation process calls it (``FrameSampler``:
    path as JSON bytes, extras, raw input and output values, the decisions' reads as JSON, exactly what
    ``xabsl_studio.server.simulation.worker.Simulation.sample`` does per robot), and the world's ``dynamic_scene()``.
    """
    # the studio's side (imports the server: here, not at the top, for the headless parts' start-up)
    from xabsl_studio.server.simulation.sampling import FrameSampler, ProgramCodec

    world = build_world(seed, *programs, players=5)  # type: ignore[arg-type]
    engines = [e for e in engines_of(world) if e is not None]
    recorder = [AgentSampler(e) for e in engines]
    codecs: dict[int, ProgramCodec] = {}
    studio = []
    for index, engine in enumerate(engines):
        codec = codecs.setdefault(id(engine.program), ProgramCodec.build(str(index), engine.program, engine))
        studio.append(FrameSampler(index, engine, codec))
    spent = {"recorder": 0.0, "studio": 0.0, "scene": 0.0}
    ticks = 0
    clock = time.thread_time  # CPU time: on a shared machine wall time also counts other processes
    dumps = orjson.dumps

    def on_tick(_now: int) -> None:
        nonlocal ticks
        started = clock()
        for sampler in recorder:
            sampler.sample()
        sampled = clock()
        for frame in studio:
            dumps(frame.path())
            frame.extras()
            frame.inputs()
            frame.outputs()
            frame.reads()
        framed = clock()
        world.dynamic_scene()
        spent["recorder"] += sampled - started
        spent["studio"] += framed - sampled
        spent["scene"] += clock() - framed
        ticks += 1

    run_headless(world, duration_s=seconds, on_tick=on_tick)
    return {key: value / ticks for key, value in spent.items()}


def encoder_costs(seconds: float, seed: int, programs: tuple[object, object], folder: Path) -> dict[str, float]:
    """CPU seconds per tick of the encoding half, fed the operations a recorder captured (best of 3).

    ``encoder``: the whole :class:`RecordingEncoder` (symbols and paths to JSON, the Foxglove
    scene, the stored columns, MCAP records and zstd); ``no foxglove``: the same without the
    Foxglove scene channels; ``no columns``: without the columns stored for queries;
    ``mcap``: only writing the recording's messages (already JSON) with the MCAP writer.
    """
    world = build_world(seed, *programs, players=5)  # type: ignore[arg-type]
    ops: list[tuple[object, ...]] = []

    class Capture:  # stands in for the encoder: keeps the operations
        def __init__(self, **_options: object) -> None:
            pass

        def handle(self, op: tuple[object, ...]) -> None:
            ops.append(op)

        def abort(self) -> None:
            pass

    with patch("xabsl_studio.engine.record.writer.RecordingEncoder", Capture):
        recorder = Recorder.for_world(
            folder / "capture.mcap",
            world,
            lambda agent: ("behavior", "chase")[agent.team_index],  # type: ignore[attr-defined]
            example="soccer",
            behavior_hz=DEFAULT_BEHAVIOR_HZ,
            physics_hz=DEFAULT_PHYSICS_HZ,
        )
        run_headless(world, duration_s=seconds, on_tick=recorder.on_tick)
        recorder.abort()
    ticks = sum(1 for op in ops if op[0] == "tick")
    messages: list[tuple[int, int, bytes, int, int]] = []

    class Keep(McapWriter):
        def add_message(self, channel: int, log_time: int, data: bytes, publish_time: int, sequence: int = 0) -> None:
            messages.append((channel, log_time, data, publish_time, sequence))
            super().add_message(channel, log_time, data, publish_time, sequence)

    def encode(foxglove_scene: bool, columns: bool = True) -> float:
        encoder = RecordingEncoder(
            folder / "encoded.mcap", DEFAULT_BEHAVIOR_HZ, foxglove_scene=foxglove_scene, columns=columns
        )
        started = time.process_time()
        for op in ops:
            encoder.handle(op)
        encoder.close()
        return time.process_time() - started

    def write() -> float:
        with open(folder / "written.mcap", "wb") as stream:
            writer = McapWriter(stream)
            writer.start()
            for topic in range(max(m[0] for m in messages) + 1):
                writer.register_channel(f"/{topic}", "json", 0)
            started = time.process_time()
            for message in messages:
                writer.add_message(*message)
            writer.finish()
            return time.process_time() - started

    with patch("xabsl_studio.engine.record.encoder.McapWriter", Keep):
        encode(True)  # collect the messages once
    costs = {
        "encoder": min(encode(True) for _ in range(3)),
        "no foxglove": min(encode(False) for _ in range(3)),
        "no columns": min(encode(True, columns=False) for _ in range(3)),
        "mcap": min(write() for _ in range(3)),
    }
    return {key: value / ticks for key, value in costs.items()}


def seek_times(path: Path, n: int, seed: int) -> list[float]:
    with Recording(path) as recording:
        rng = random.Random(seed)
        times = []
        for _ in range(n):
            seq = rng.randrange(len(recording))
            started = time.perf_counter()
            view = recording.tick(seq)
            for agent in view.agents.values():
                agent.tree()
            times.append(time.perf_counter() - started)
        return times


def _spread(seconds: list[float]) -> str:
    return f"median {1e3 * statistics.median(seconds):.1f} ms, max {1e3 * max(seconds):.1f} ms"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=120.0, help="simulated seconds per run (default 120)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--repeat", type=int, default=2, help="pairs of runs without/with recording (default 2)")
    parser.add_argument("--full", action="store_true", help="also record 600 simulated seconds once")
    parser.add_argument("--keep", metavar="DIR", help="keep the recordings in DIR")
    args = parser.parse_args()

    programs = (load_team(DEFAULT_HOME), load_team(DEFAULT_AWAY))
    folder = Path(args.keep or tempfile.mkdtemp(prefix="record_cost_"))
    folder.mkdir(parents=True, exist_ok=True)
    plain(5.0, args.seed, programs)  # warm up: imports, code generation caches
    runs: dict[str, list[tuple[float, float]]] = {
        "without recording": [],
        "recorded inline": [],
        "recorded, writer process": [],
        "captured only (no encoder)": [],
    }
    stats = None
    path = folder / f"match_{args.seconds:.0f}s.mcap"
    for _ in range(args.repeat):
        wall, cpu, scene_plain = plain(args.seconds, args.seed, programs)
        runs["without recording"].append((wall, cpu))
        for label, background in (("recorded inline", False), ("recorded, writer process", True)):
            wall, cpu, scene_recorded, stats = recorded(args.seconds, args.seed, programs, path, background)
            runs[label].append((wall, cpu))
            if scene_plain != scene_recorded:
                raise SystemExit("recording changed the match: the final scenes differ")
        with patch("xabsl_studio.engine.record.writer.RecordingEncoder", Discard):
            wall, cpu, _, _ = recorded(args.seconds, args.seed, programs, folder / "discarded.mcap", False)
        runs["captured only (no encoder)"].append((wall, cpu))
    assert stats is not None
    ticks = stats.ticks
    size = path.stat().st_size
    sampling = sampling_costs(args.seconds, args.seed, programs)
    encoding = encoder_costs(args.seconds, args.seed, programs, folder)

    print(
        f"soccer 5 vs 5, {args.seconds:.0f} simulated s ({ticks} ticks), seed {args.seed}, "
        f"median of {args.repeat} runs each (cpu: this process only)"
    )
    base_wall = statistics.median(w for w, _ in runs["without recording"])
    base_cpu = statistics.median(c for _, c in runs["without recording"])
    for label, values in runs.items():
        wall = statistics.median(w for w, _ in values)
        cpu = statistics.median(c for _, c in values)
        line = f"  {label:<27} {wall:7.2f} s wall {cpu:7.2f} s cpu  {1e3 * wall / ticks:.3f} ms/tick"
        if label != "without recording":
            line += f"  overhead {100 * (wall / base_wall - 1):4.0f} % wall, {100 * (cpu / base_cpu - 1):4.0f} % cpu"
        print(line)
    print("  (goal: overhead < 10 %)")
    tick = base_cpu / ticks

    def part(label: str, seconds: float, goal: str = "") -> None:
        print(f"    {label:<58} {1e3 * seconds:6.3f} ms  {seconds / tick:5.2f} x the plain tick {goal}")

    print(f"  per tick, 10 agents (the plain tick: {1e3 * tick:.3f} ms cpu):")
    part("sampling for a recording (AgentSampler.sample)", sampling["recorder"], "(goal <= 0.2 ms)")
    part("sampling for the studio (FrameSampler; the server converts)", sampling["studio"], "(goal <= 0.2 ms)")
    part("the world's dynamic_scene()", sampling["scene"])
    part("encoding (RecordingEncoder, cpu, best of 3)", encoding["encoder"])
    part("  of which the Foxglove scene", encoding["encoder"] - encoding["no foxglove"])
    part("  of which the columns stored for queries", encoding["encoder"] - encoding["no columns"])
    part("  of which MCAP records, indexes and zstd", encoding["mcap"])
    part(
        "  the rest: paths and symbol changes to JSON",
        encoding["no columns"] - (encoding["encoder"] - encoding["no foxglove"]) - encoding["mcap"],
    )
    per_tick = size / ticks
    print(
        f"  file: {size / MB:.2f} MB, {stats.messages} messages, {per_tick:.0f} B per tick; "
        f"10 minutes extrapolated: {per_tick * TEN_MINUTES_TICKS / MB:.1f} MB (goal <= 50 MB)"
    )
    seeks = seek_times(path, 30, args.seed)
    print(f"  seek a random tick + rebuild 10 trees: {_spread(seeks)}")

    if args.full:
        full = folder / "match_600s.mcap"
        wall, cpu, _, stats = recorded(600.0, args.seed, programs, full, False)  # inline, as the command line
        size = full.stat().st_size
        seeks = seek_times(full, 50, args.seed)
        print(
            f"full 10 minutes recorded inline ({stats.ticks} ticks): {wall:.1f} s wall, {cpu:.1f} s cpu, "
            f"{size / MB:.1f} MB (goal <= 50 MB)"
        )
        print(f"  seek a random tick + rebuild 10 trees: {_spread(seeks)} (goal < 100 ms)")
    if not args.keep:
        for file in folder.glob("*.mcap"):
            file.unlink()
        os.rmdir(folder)


if __name__ == "__main__":
    main()
