"""How long does ``xabsl profile`` take on a 10-minute match of 10 agents? The goal is under 5 s.

Records a 5 vs 5 soccer match of ``--duration`` simulated seconds of play (600: 10 minutes, plus
the pre-game) with ``xabsl run examples/soccer --record``, or reuses the recording of the same
seed and duration from the cache folder (``--cache``, default ``~/.cache/xabsl-studio/
profile_speed``; recording takes a few minutes), then times ``xabsl profile RECORDING --json``
as a user runs it (a new process: start-up, reading, counting, the JSON) and, in this process,
the stages: reading the paths (``Recording.paths``), counting (``xabsl_studio.engine.profile.profile``) and the
HTML report (``--html``, with Graphviz). Prints the figures; best of ``--runs``.

Run::

    .venv/bin/python benchmarks/profile_speed.py
    .venv/bin/python benchmarks/profile_speed.py --duration 60 --runs 5

Never run from the test suite.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from xabsl_studio.engine.profile import profile  # noqa: E402
from xabsl_studio.engine.profile.html import html_report  # noqa: E402
from xabsl_studio.engine.record import Recording  # noqa: E402

GOAL_SECONDS = 5.0
CACHE = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "xabsl-studio" / "profile_speed"


def recording_for(cache: Path, duration: int, seed: int) -> Path:
    """The cached recording of that match, recorded first when missing."""
    path = cache / f"soccer-{duration}s-seed{seed}.mcap"
    if path.is_file():
        return path
    cache.mkdir(parents=True, exist_ok=True)
    print(f"recording {duration} s of 5 vs 5 into {path} (once) ...", flush=True)
    started = time.perf_counter()
    command = [sys.executable, "-m", "xabsl_studio.engine.cli", "run", "examples/soccer", "--duration", str(duration)]
    command += ["--seed", str(seed), "--record", str(path)]
    subprocess.run(command, cwd=ROOT, check=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    print(f"recorded in {time.perf_counter() - started:.0f} s")
    return path


def main(argv: list[str] | None = None) -> int:
    """Print the time of ``xabsl profile`` on one recorded match, and of its stages."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=int, default=600, help="simulated seconds of play (default 600)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--runs", type=int, default=3, help="keep the best of this many runs")
    parser.add_argument("--cache", type=Path, default=CACHE, help="folder of cached recordings")
    args = parser.parse_args(argv)
    path = recording_for(args.cache, args.duration, args.seed)
    with Recording(path) as recording:
        ticks, agents = len(recording), len(recording.agents)
    print(
        f"{path}: {ticks} ticks ({ticks / 40 / 60:.1f} min at 40 Hz), {agents} agents, "
        f"{path.stat().st_size / 1e6:.1f} MB; best of {args.runs} runs; load {os.getloadavg()[0]:.1f}"
    )
    command = [sys.executable, "-m", "xabsl_studio.engine.cli", "profile", str(path), "--json"]
    best_cli = best_paths = best_count = best_html = float("inf")
    with tempfile.TemporaryDirectory(prefix="xabsl-profile-bench-") as folder:
        for _ in range(args.runs):
            started = time.perf_counter()
            subprocess.run(command, check=True, stdout=subprocess.DEVNULL, env={**os.environ, "PYTHONPATH": str(ROOT)})
            best_cli = min(best_cli, time.perf_counter() - started)
            with Recording(path) as recording:
                started = time.perf_counter()
                for _ in recording.paths():
                    pass
                best_paths = min(best_paths, time.perf_counter() - started)
                started = time.perf_counter()
                report = profile(recording)
                best_count = min(best_count, time.perf_counter() - started)
                descriptions = {key: view.description for (key, _gen), view in sorted(recording.programs.items())}
            started = time.perf_counter()
            Path(folder, "report.html").write_text(html_report(report, descriptions))
            best_html = min(best_html, time.perf_counter() - started)
    verdict = "within" if best_cli < GOAL_SECONDS else "OVER"
    print(f"xabsl profile --json (new process): {best_cli:.2f} s ({verdict} the {GOAL_SECONDS:.0f} s goal)")
    print(f"  reading the paths only:   {best_paths:.2f} s")
    print(f"  counting and the report:  {best_count:.2f} s (includes reading)")
    print(f"  HTML report (+ Graphviz): {best_html:.2f} s, {len(report['oscillations'])} oscillations listed")
    return 0 if best_cli < GOAL_SECONDS else 1


if __name__ == "__main__":
    sys.exit(main())
