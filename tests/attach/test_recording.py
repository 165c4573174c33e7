"""Recordings of an attached session: made without --behavior (the hosts send what they need),
replayed with the same "why", forked into the bench world on the recorded inputs.

The robot is an ``examples/attach/robot.py`` process; the studios are the real command lines
(``xabsl attach``, then ``xabsl serve --replay``) read over HTTP; the file is read with the
recording reader.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any

from xabsl_studio.engine.record import Recording

from .peer import REPO, start_robot, stop_robot
from .test_attached import Studio, free_port


class Replay(Studio):
    """``xabsl serve --replay FILE`` as a subprocess on a free port."""

    def __init__(self, path: Path) -> None:
        self.port = free_port()
        command = [sys.executable, "-m", "xabsl_studio.engine.cli", "serve", "--replay", str(path)]
        self.process = subprocess.Popen(
            [*command, "--port", str(self.port)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=REPO
        )
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(self.process.communicate()[0])
            try:
                self.status()
                return
            except (urllib.error.URLError, ConnectionError):
                time.sleep(0.2)
        raise RuntimeError("xabsl serve --replay did not start")


def test_an_attached_session_records_without_its_behavior_replays_and_forks_into_the_bench(tmp_path: Path) -> None:
    process, port = start_robot("--hz", "100")
    studio = Studio(f"127.0.0.1:{port}", "--record-dir", str(tmp_path))
    try:
        studio.until(lambda s: s["attached"][0]["received"] > 300 and s["recording"]["ticks"] > 300)
        log = {t["t"]: t for t in studio.get("/api/log?t0=0")}
        asked = sorted(log)[20::40]
        answers = {}
        for t in asked:
            code, reply = studio.command(op="explain", robot=0, option="play", seq=log[t]["seq"])
            assert code == 200 and reply["ok"], reply
            answers[t] = reply["result"]
    finally:
        said = studio.stop()
        stop_robot(process)
    files = sorted(tmp_path.glob("*.mcap"))
    assert len(files) == 1, (list(tmp_path.iterdir()), said)
    with Recording(files[0]) as recording:
        assert [a["name"] for a in recording.header["agents"]] == ["robot1"]
        views = list(recording.programs.values())
        # The host sent its program: IC (replay, why) and sources (a fork runs them again).
        assert views and all(v.ic and v.sources and v.sources["agents"] == "agents.xabsl" for v in views)
        by_t = {view.t: view for view in recording.ticks()}
        seq_of = {t: view.seq for t, view in by_t.items()}
        compared = 0
        unread: list[int] = []
        read: list[int] = []
        for t, logged in log.items():
            if t not in by_t:
                continue
            tick = by_t[t].agents["robot1"]
            inputs = logged["robots"][0]["inputs"]
            if inputs["game.state"] is None:  # the session's tick before the host's first sample
                assert all(v is None for v in tick.inputs.values())
                continue
            # enums: the session logs element indices, the recording names them (the host's whole enum)
            assert (
                tick.inputs["game.state"]
                == "game.state." + ("init", "ready", "set", "playing", "finished")[inputs["game.state"]]
            )
            assert {k: v for k, v in tick.inputs.items() if k != "game.state"} == {
                k: v for k, v in inputs.items() if k != "game.state"
            }
            (read if tick.reads else unread).append(t)
            compared += 1
        assert compared > 250
        # The decisions' reads are recorded from the tick after the studio attached on.
        assert read and len(unread) <= 2 and all(t < min(read) for t in unread), unread
    replay = Replay(files[0])
    try:
        for t, why in answers.items():
            code, reply = replay.command(op="explain", robot=0, option="play", seq=seq_of[t])
            assert code == 200 and reply["ok"], reply
            assert reply["result"]["conditions"] == why["conditions"], t
            assert reply["result"]["decided_in_name"] == why["decided_in_name"]
        # Run from here: the bench world runs the recorded behavior on robot1's recorded inputs.
        at = seq_of[asked[2]]
        code, opened = replay.send("POST", "/api/fork", {"seq": at, "robot": 0})
        assert code == 200, opened
        fork = opened["url"].rstrip("/")
        with Recording(files[0]) as recording:
            expected = recording.tick(at).agents["robot1"].inputs

        def forked_inputs() -> dict[str, Any]:
            with urllib.request.urlopen(f"http://127.0.0.1:{replay.port}{fork}/api/log?t0=0", timeout=10) as answer:
                ticks = [json.loads(line) for line in answer.read().splitlines()]
            ran = [t for t in ticks if t["robots"][0]["path"]]  # the sample before the first tick has none
            return ran[0]["robots"][0]["inputs"] if ran else {}

        deadline = time.monotonic() + 30
        while not forked_inputs() and time.monotonic() < deadline:
            time.sleep(0.2)
        first = forked_inputs()
        assert first["game.state"] == ("init", "ready", "set", "playing", "finished").index(
            str(expected["game.state"]).rsplit(".", 1)[1]
        )
        assert {k: v for k, v in first.items() if k != "game.state"} == {
            k: v for k, v in expected.items() if k != "game.state"
        }
        structure = replay.get(f"{fork}/api/structure")
        assert [o["name"] for o in structure["programs"][structure["robots"][0]["program"]]["options"]] == [
            "approach_ball",
            "play",
            "search_ball",
        ]
    finally:
        replay.stop()
