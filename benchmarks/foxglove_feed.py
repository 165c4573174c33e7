"""What the Foxglove endpoint costs the server per tick: ring entries -> the recordings' topics.

Records a 5 v 5 soccer match headless (``xabsl run examples/soccer --players 5 --record``;
skipped with ``--file``), puts its ticks one after the other in a replay session's ring (as
playing does) and times :class:`xabsl_studio.server.session.feed.TopicFeed` turning each entry
into messages, once with every topic subscribed and once with one robot's ticks only. This is
the work ``/foxglove`` adds on the server's loop per tick while a viewer is connected (framing and
sending are per viewer and small beside it); the goal is well under the 25 ms tick period.

    .venv/bin/python benchmarks/foxglove_feed.py [--seconds 30] [--file match.mcap]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from xabsl_studio.server.session.feed import TopicFeed  # noqa: E402
from xabsl_studio.server.session.replay import ReplaySession  # noqa: E402


def main() -> int:
    """Record (unless given a file), then time the feed over every tick; print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=30.0, help="simulated seconds to record")
    parser.add_argument("--file", default=None, help="an existing recording (skips recording)")
    args = parser.parse_args()
    path = Path(args.file) if args.file else Path(tempfile.mkdtemp(prefix="foxglove-feed-")) / "match.mcap"
    if not args.file:
        command = [sys.executable, "-m", "xabsl_studio.engine.cli", "run", "examples/soccer", "--players", "5"]
        command += ["--duration", f"{args.seconds:g}", "--record", str(path)]
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        subprocess.run(command, cwd=ROOT, env=env, check=True, capture_output=True)
    session = ReplaySession(path)
    robot = f"/xabsl/agents/{session.source.robots[0]['name']}"
    print(f"{path}: {len(session.source)} ticks, {len(session.source.robots)} robots")
    for label, wanted in (("every topic", None), (f"{robot} only", {robot})):
        feed = TopicFeed(session.behavior_hz)
        times: list[float] = []
        cpu = 0.0
        sizes: list[int] = []
        for seq in range(session.source.first, session.source.end):
            entry = session.seek(seq)  # the ring keeps an entry's values only while it is recent
            started, started_cpu = time.perf_counter(), time.process_time()
            messages = feed.entry(entry, wanted)
            times.append(1000 * (time.perf_counter() - started))
            cpu += time.process_time() - started_cpu
            sizes.append(sum(len(m.data) for m in messages))
        times.sort()
        print(
            f"{label}: median {statistics.median(times):.3f} ms per tick, "
            f"p95 {times[int(0.95 * (len(times) - 1))]:.3f} ms, max {times[-1]:.3f} ms; "
            f"{statistics.mean(sizes) / 1000:.1f} KB per tick; CPU {1000 * cpu / len(times):.3f} ms per tick"
        )
    session.stop()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
