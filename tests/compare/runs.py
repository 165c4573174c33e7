"""Two soccer runs of one seed that differ by one known edit, recorded by the real ``xabsl run``.

The edit: ``approach_ball`` goes from ``far`` to ``near`` below 600 mm instead of 900 mm. The
edited copy keeps the folder name ``behavior`` (the program key), so the original's recording can
also be forked into it (``xabsl run --fork``).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SOCCER = REPO / "examples" / "soccer"
#: the condition edited, before and after
ORIGINAL, EDITED = "if (ball.distance < 900)", "if (ball.distance < 600)"
SEED, PLAYERS, DURATION = 4, 3, "20"


@dataclass(frozen=True)
class Runs:
    original: Path
    edited: Path
    #: the original re-simulated to tick ``fork_at`` and gone on with the edited behavior
    fork: Path
    fork_at: int
    edited_behavior: Path


def xabsl(*args: str) -> subprocess.CompletedProcess[str]:
    """The ``xabsl`` command line, run as its own process."""
    return subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", *args], capture_output=True, text=True, timeout=300
    )


def record_runs(folder: Path, fork_at: int = 800) -> Runs:
    """Record the original, the edited behavior and a fork of the original into the edit."""
    edited = folder / "edited" / "behavior"
    shutil.copytree(SOCCER / "behavior", edited)
    option = edited / "options" / "approach_ball.xabsl"
    text = option.read_text(encoding="utf-8")
    assert text.count(ORIGINAL) == 1
    option.write_text(text.replace(ORIGINAL, EDITED), encoding="utf-8")
    common = ("--players", str(PLAYERS), "--seed", str(SEED))
    runs = Runs(folder / "original.mcap", folder / "edited.mcap", folder / "fork.mcap", fork_at, edited)
    for args in (
        ("run", str(SOCCER), *common, "--duration", DURATION, "--record", str(runs.original)),
        ("run", str(SOCCER), "--home", str(edited), *common, "--duration", DURATION, "--record", str(runs.edited)),
        (
            "run",
            str(SOCCER),
            "--home",
            str(edited),
            *common,
            "--fork",
            str(runs.original),
            "--at",
            str(fork_at),
            "--duration",
            "10",
            "--record",
            str(runs.fork),
        ),
    ):
        done = xabsl(*args)
        assert done.returncode == 0, done.stderr
    return runs
