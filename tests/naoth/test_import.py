"""``xabsl import naoth``: game logs written by the test robot (its own writer, its own engine indices)
imported into recordings, read back with the recordings' reader and profiled, against the truth
the robot's engine had in every frame.
"""

from __future__ import annotations

import itertools
import json
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from xabsl_studio.engine.record import Recording

HERE = Path(__file__).resolve().parent
ROBOT = HERE / "robot.py"
BEHAVIOR = HERE / "behavior"


def xabsl(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", *args], capture_output=True, text=True, cwd=cwd, timeout=300
    )


def write_log(tmp: Path, *args: str) -> tuple[Path, list[dict[str, Any]]]:
    log, truth = tmp / "game.log", tmp / "truth.jsonl"
    subprocess.run([sys.executable, str(ROBOT), "log", str(log), "--truth", str(truth), *args], check=True, timeout=300)
    return log, [json.loads(line) for line in truth.read_text().splitlines()]


def shown(value: Any) -> Any:
    """A truth value as a recording holds it: decimals to 3 digits."""
    return round(value, 3) if isinstance(value, float) else value


def nodes(tick: Any) -> list[list[Any]]:
    """A recorded tick's path with names, as the robot's truth has it."""
    out: list[list[Any]] = []
    description = tick.program.description
    tables = tick.program.tables
    for node in tick.path:
        if node[0] == 0:
            option = description["options"][node[2]]
            params = [
                tables["enums"][p["enum"]][str(v)] if p["type"] == "enum" else shown(v)
                for p, v in zip(option["params"], node[8], strict=True)
            ]
            out.append(["option", node[1], option["name"], option["states"][node[3]]["name"], node[4], node[5], params])
        else:
            behavior = description["behaviors"][node[2]]
            params = [
                tables["enums"][p["enum"]][str(v)] if p["type"] == "enum" else shown(v)
                for p, v in zip(behavior["params"], node[4], strict=True)
            ]
            out.append(["behavior", node[1], behavior["name"], node[3], params])
    return out


def test_every_frame_of_a_log_becomes_a_tick_with_the_robots_tree_and_values(tmp_path: Path) -> None:
    log, truth = write_log(tmp_path, "--frames", "240", "--gap", "50", "--agent-switch", "180")
    out = tmp_path / "game.mcap"
    done = xabsl("import", "naoth", str(log), "--behavior", str(BEHAVIOR), "-o", str(out))
    assert done.returncode == 0, done.stderr
    assert "240 frames, 4 frames missing in the log" in done.stdout
    recording = Recording(out)
    ticks = list(recording.ticks())
    assert len(ticks) == len(truth) == 240
    for tick, frame in zip(ticks, truth, strict=True):
        agent = tick.agents["robot"]
        assert agent.tick == frame["frame"]
        assert tick.t == frame["frame"] * 33
        for node, expected in zip(nodes(agent), frame["path"], strict=True):
            assert node == [shown(x) if not isinstance(x, list) else [shown(v) for v in x] for x in expected]
        assert len(nodes(agent)) == len(frame["path"])
        assert agent.inputs == {k: shown(v) for k, v in frame["inputs"].items()}
        assert agent.outputs == {k: shown(v) for k, v in frame["outputs"].items()}
    switched = [t for t in ticks if t.agents["robot"].path and t.agents["robot"].roots[0].name == "look_around"]
    assert switched and switched[0].agents["robot"].tick == truth[180]["frame"]
    assert [e["data"] for e in recording.events if e["kind"] == "select_agent"] == [{"name": "looker"}]
    recording.close()


def test_decisions_the_structure_makes_certain_are_counted_by_the_profiler(tmp_path: Path) -> None:
    log, truth = write_log(tmp_path, "--frames", "200")
    out = tmp_path / "game.mcap"
    assert xabsl("import", "naoth", str(log), "--behavior", str(BEHAVIOR), "-o", str(out)).returncode == 0
    changes = sum(
        1
        for before, after in itertools.pairwise(truth)
        for a in after["path"]
        for b in before["path"]
        if a[0] == b[0] == "option" and a[2] == b[2] and a[3] != b[3]
    )
    assert changes > 5
    profile = xabsl("profile", str(out), "--json")
    assert profile.returncode == 0, profile.stderr
    options = json.loads(profile.stdout)["agents"]["robot"]["options"]
    counted = sum(t["count"] for option in options.values() for t in option["transitions"])
    # every state change between consecutive frames has one leaf leading there in this behavior
    assert counted == changes


def test_a_log_of_other_sources_is_refused_with_what_differs(tmp_path: Path) -> None:
    log, _ = write_log(tmp_path, "--frames", "130")  # frames 80..119 look around
    changed = tmp_path / "changed"
    shutil.copytree(BEHAVIOR, changed)
    option = changed / "options" / "look_around.xabsl"
    option.write_text(option.read_text().replace("initial state turn", "initial state spin"))
    out = tmp_path / "game.mcap"
    done = xabsl("import", "naoth", str(log), "--behavior", str(changed), "-o", str(out))
    assert done.returncode == 1
    assert "option 'look_around': state 'turn' is on the robot, not in the sources" in done.stderr
    assert "option 'look_around': state 'spin' is in the sources, not on the robot" in done.stderr
    assert not out.exists() and not out.with_name(out.name + ".part").exists()
    forced = xabsl("import", "naoth", str(log), "--behavior", str(changed), "-o", str(out), "--allow-mismatch")
    assert forced.returncode == 0 and "mismatch: option 'look_around'" in forced.stdout
    assert "40 actions of the log match nothing in the sources (left out)" in forced.stdout
    # the frames of the state our sources do not have are left out, never shown as something else
    recording = Recording(out)
    look_around = next(
        o["id"] for o in recording.program("robot", 0).description["options"] if o["name"] == "look_around"
    )
    assert all(n[0] != 0 or n[2] != look_around for t in recording.ticks() for n in t.agents["robot"].path)
    recording.close()


def test_a_cut_off_log_imports_its_whole_records_and_a_foreign_file_is_refused(tmp_path: Path) -> None:
    log, _ = write_log(tmp_path, "--frames", "30")
    data = log.read_bytes()
    log.write_bytes(data[: len(data) - 7])
    out = tmp_path / "game.mcap"
    done = xabsl("import", "naoth", str(log), "--behavior", str(BEHAVIOR), "-o", str(out))
    assert done.returncode == 0, done.stderr
    assert "29 frames" in done.stdout and "incomplete record at byte" in done.stdout
    foreign = tmp_path / "image.log"
    foreign.write_bytes(b"\x01\x00\x00\x00" + b"x" * 300)
    bad = xabsl("import", "naoth", str(foreign), "--behavior", str(BEHAVIOR), "-o", str(out))
    assert bad.returncode == 2 and "record name longer than 256 bytes" in bad.stderr


@pytest.mark.parametrize("missing", ["log", "behavior"])
def test_missing_files_are_usage_errors(tmp_path: Path, missing: str) -> None:
    log, _ = write_log(tmp_path, "--frames", "3") if missing == "behavior" else (tmp_path / "none.log", [])
    behavior = tmp_path / "nowhere" if missing == "behavior" else BEHAVIOR
    done = xabsl("import", "naoth", str(log), "--behavior", str(behavior), "-o", str(tmp_path / "x.mcap"))
    assert done.returncode == 2 and ("no agents file" in done.stderr or "no such file" in done.stderr)
