"""``xabsl run`` records unless told not to: into the folder the studio lists, capped, in a fresh process."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import orjson
import pytest

from xabsl_studio.engine.record import Recording
from xabsl_studio.engine.record.folder import default_folder, new_recording, prune
from xabsl_studio.examples.soccer.studio import SoccerExample

REPO = Path(__file__).resolve().parents[2]
SOCCER = REPO / "examples" / "soccer"


def _xabsl_run(cache: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """``xabsl run ARGS`` as a user types it, with its own cache folder."""
    command = [sys.executable, "-m", "xabsl_studio.engine.cli", "run", *args]
    env = {"PYTHONPATH": str(REPO), "PATH": "/usr/bin:/bin", "XDG_CACHE_HOME": str(cache), "HOME": str(cache)}
    return subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=300, env=env)


def test_a_match_is_recorded_into_the_folder_the_studio_lists_for_its_behaviors(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    done = _xabsl_run(tmp_path, "examples/soccer", "--duration", "3", "--players", "1", "--json")
    assert done.returncode == 0, done.stderr
    report = orjson.loads(done.stdout)
    path = Path(report["recording"])
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    studio = SoccerExample(SOCCER, players_per_team=1)
    assert path.parent == default_folder([s.agents_file for s in studio.sources])  # what `xabsl serve` lists
    assert path.name.startswith("soccer-") and not path.with_name(path.name + ".part").exists()
    with Recording(path) as recording:
        assert recording.header["example"] == "soccer" and len(recording.agents) == 2
        assert len(recording) == round(report["sim_seconds"] * recording.behavior_hz)  # every tick
    text = _xabsl_run(tmp_path, "examples/soccer", "--duration", "1", "--players", "1")
    assert text.returncode == 0 and f"recorded to {path.parent}" in text.stdout


def test_no_record_writes_nothing_and_record_writes_the_file_named(tmp_path: Path) -> None:
    done = _xabsl_run(tmp_path, "examples/soccer", "--duration", "1", "--players", "1", "--no-record", "--json")
    assert done.returncode == 0, done.stderr
    assert orjson.loads(done.stdout)["recording"] is None
    assert not (tmp_path / "xabsl-studio").exists()
    named = tmp_path / "mine.mcap"
    done = _xabsl_run(tmp_path, "examples/errands", "--duration", "2", "--record", str(named), "--json")
    assert done.returncode == 0, done.stderr
    assert orjson.loads(done.stdout)["recording"] == str(named) and named.is_file()
    assert not (tmp_path / "xabsl-studio").exists()  # a named file only


def test_errands_are_recorded_by_default_too(tmp_path: Path) -> None:
    done = _xabsl_run(tmp_path, "examples/errands", "--duration", "2", "--json")
    assert done.returncode == 0, done.stderr
    path = Path(orjson.loads(done.stdout)["recording"])
    assert path.is_relative_to(tmp_path / "xabsl-studio" / "recordings") and path.name.startswith("errands-")
    with Recording(path) as recording:
        assert len(recording) == 2 * recording.behavior_hz


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--no-record", "--record", "x.mcap"], "--record and --no-record contradict each other"),
        (["--record-cap-mb", "0"], "--record-cap-mb must be a positive number"),
        (["--record-cap-mb", "nan"], "--record-cap-mb must be a positive number"),
    ],
)
def test_bad_recording_flags_are_usage_errors(tmp_path: Path, flags: list[str], message: str) -> None:
    done = _xabsl_run(tmp_path, "examples/soccer", "--duration", "1", "--players", "1", *flags)
    assert done.returncode == 2 and message in done.stderr
    assert not (tmp_path / "xabsl-studio").exists()


def test_the_cap_removes_the_oldest_runs_never_the_new_one(tmp_path: Path) -> None:
    first = _xabsl_run(tmp_path, "examples/soccer", "--duration", "2", "--players", "1", "--json")
    second = _xabsl_run(tmp_path, "examples/soccer", "--duration", "2", "--players", "1", "--json")
    old, new = (Path(orjson.loads(r.stdout)["recording"]) for r in (first, second))
    assert old != new and old.is_file() and new.is_file()
    size = new.stat().st_size
    third = _xabsl_run(
        tmp_path, "examples/soccer", "--duration", "2", "--players", "1", "--json", "--record-cap-mb", str(size / 1e6)
    )
    assert third.returncode == 0, third.stderr
    newest = Path(orjson.loads(third.stdout)["recording"])
    assert newest.is_file() and not old.exists() and not new.exists()  # a file of this size alone fits the cap


def test_names_are_never_used_twice_and_pruning_keeps_the_newest(tmp_path: Path) -> None:
    first = new_recording(tmp_path, "a b/c")
    assert first.name.startswith("a_b_c-") and first.suffix == ".mcap"
    first.write_bytes(b"x" * 10)
    second = new_recording(tmp_path, "a b/c")
    second.with_name(second.name + ".part").write_bytes(b"")  # a killed run's file holds its name too
    third = new_recording(tmp_path, "a b/c")
    assert len({first, second, third}) == 3
    third.write_bytes(b"y" * 10)
    os.utime(first, (0, 0))
    assert prune(tmp_path, 5) == [first] and third.is_file()  # oldest by name; the newest stays over the cap
