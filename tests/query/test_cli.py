"""``xabsl query`` run as its own process: the printed intervals, JSON, exit statuses."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from xabsl_studio.engine.query import query_recording

ROOT = Path(__file__).resolve().parents[2]


def xabsl(*args: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "query", *args],
        capture_output=True,
        text=True,
        env=env,
        cwd=ROOT,
        timeout=300,
    )


def test_prints_every_interval(match: Path) -> None:
    condition = "striker.state == shoot"
    done = xabsl(str(match), condition)
    assert done.returncode == 0, done.stderr
    expected = query_recording(match, condition)
    assert expected.intervals
    lines = done.stdout.splitlines()
    assert lines[0] == f"{match}: {condition}"
    assert f"{expected.matched} of {expected.ticks} robot ticks match" in lines[1]
    rows = [line.split() for line in lines[3 : 3 + len(expected.intervals)]]
    assert [(r[0], int(r[1]), int(r[2])) for r in rows] == [
        (i.robot, i.first_seq, i.last_seq) for i in expected.intervals
    ]
    first = expected.intervals[0]
    assert rows[0][3] == f"{first.first_t_ms / 1000:.3f}" and rows[0][5] == f"{first.last_t_ms / 1000:.3f}"
    assert any(line.startswith("not evaluated for red1, red2: chase: 1:1: ") for line in lines)


def test_json_for_one_robot(match: Path) -> None:
    done = xabsl(str(match), "kick.active || dribble.active", "--robot", "red2", "--json")
    assert done.returncode == 0, done.stderr
    document = json.loads(done.stdout)
    expected = query_recording(match, "kick.active || dribble.active", robot="red2")
    assert document == {"recording": str(match), **expected.to_json()}
    assert document["robots"] == ["red2"] and document["intervals"]


def test_a_bad_condition_exits_1_with_its_position(match: Path) -> None:
    done = xabsl(str(match), "striker.state == kik && ball.seen")
    assert done.returncode == 1
    assert done.stdout == ""
    first, text, caret = done.stderr.splitlines()
    assert first.startswith("<condition>:1:18: option striker has no state 'kik' (states: approach,")
    assert text == "  striker.state == kik && ball.seen"
    assert caret == " " * 19 + "^"


def test_usage_problems_exit_2(match: Path, tmp_path: Path) -> None:
    missing = xabsl(str(tmp_path / "nothing.mcap"), "ball.seen")
    assert missing.returncode == 2 and "no such file" in missing.stderr
    robot = xabsl(str(match), "ball.seen", "--robot", "blue9")
    assert robot.returncode == 2 and "no robot 'blue9'" in robot.stderr
    junk = tmp_path / "junk.mcap"
    junk.write_text("junk")
    assert xabsl(str(junk), "ball.seen").returncode == 2
