"""``xabsl attach naoth://`` end to end: the test robot (tests/naoth/robot.py) as its own process
speaking NaoTH's debug port, the studio as its own process (the real command line), read through
``/api/status``, ``/api/log``, ``/api/command`` and ``/api/files`` as a user's tools would.

The robot advances three frames per answer up to frame 300 (``--step 3 --frames 300``): the
studio must show each of the 100 frames it was sent, exactly as the robot's engine had it, and
count the 198 frames it was not sent.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from xabsl_studio.engine.emit.ic import emit_ic
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.record import Recording

from ..attach.test_attached import Studio

HERE = Path(__file__).resolve().parent
ROBOT = HERE / "robot.py"
BEHAVIOR = HERE / "behavior"


class Robot:
    """``tests/naoth/robot.py serve`` in a process of its own."""

    def __init__(self, tmp: Path, *args: str) -> None:
        self.config = tmp / "Config"
        self.truth = tmp / "truth.jsonl"
        self.process = subprocess.Popen(
            [sys.executable, str(ROBOT), "serve", "--config", str(self.config), "--truth", str(self.truth), *args],
            stdout=subprocess.PIPE,
            text=True,
        )
        assert self.process.stdout is not None
        line = self.process.stdout.readline()
        assert line.startswith("listening on "), line
        self.port = int(line.split()[-1])

    def frames(self) -> list[dict[str, Any]]:
        return [json.loads(line) for line in self.truth.read_text().splitlines()]

    def stop(self) -> None:
        self.process.terminate()
        self.process.communicate(timeout=10)


@pytest.fixture
def behavior(tmp_path: Path) -> Path:
    """A copy of the test behavior (the studio edits it)."""
    folder = tmp_path / "behavior"
    shutil.copytree(BEHAVIOR, folder)
    return folder


@pytest.fixture
def robot(tmp_path: Path) -> Iterator[Robot]:
    robot = Robot(tmp_path, "--step", "3", "--frames", "300")
    yield robot
    robot.stop()


def expected(frame: dict[str, Any], enums: dict[str, tuple[str, ...]]) -> dict[str, Any]:
    """A truth frame as ``/api/log`` shows it: enums as element indices, decimals to 3 digits."""

    def value(v: Any) -> Any:
        if isinstance(v, float):
            return round(v, 3)
        if isinstance(v, str):
            return enums[v.rsplit(".", 1)[0]].index(v)
        return v

    return {
        "path": [
            {
                "depth": n[1],
                "option": n[2],
                "state": n[3],
                "option_time": n[4],
                "state_time": n[5],
                "params": [value(v) for v in n[6]],
            }
            if n[0] == "option"
            else {"depth": n[1], "behavior": n[2], "time": n[3], "params": [value(v) for v in n[4]]}
            for n in frame["path"]
        ],
        "inputs": {k: value(v) for k, v in frame["inputs"].items()},
        "outputs": {k: value(v) for k, v in frame["outputs"].items()},
    }


def shown(robot: dict[str, Any]) -> dict[str, Any]:
    """A robot of an ``/api/log`` line, in the shape of :func:`expected`."""
    path = []
    for node in robot["path"]:
        if "option" in node:
            path.append(
                {k: node[k] for k in ("depth", "option", "state", "option_time", "state_time")}
                | {"params": list(node["params"].values())}
            )
        else:
            path.append({k: node[k] for k in ("depth", "behavior", "time", "params")})
    return {"path": path, "inputs": robot["inputs"], "outputs": robot["outputs"]}


def test_every_frame_the_robot_answers_shows_as_it_ran_and_the_rest_are_counted(
    robot: Robot, behavior: Path, tmp_path: Path
) -> None:
    program = compile_file(str(behavior / "agents.xabsl")).program
    assert program is not None
    enums = {name: e.elements for name, e in program.enums.items()}
    studio = Studio(
        f"naoth://127.0.0.1:{robot.port}", "--behavior", str(behavior), "--record-dir", str(tmp_path / "rec")
    )
    try:
        status = studio.until(lambda s: s["attached"][0]["received"] == 100)
        host = status["attached"][0]
        assert host["connected"] and host["kind"] == "naoth" and host["missed"] == 198
        assert host["agents"] == ["soccer", "looker"] and host["agent"] == "soccer" and host["mismatches"] == []
        assert host["capabilities"]["force"] is False and host["capabilities"]["reload"] is True
        ticks = [line["robots"][0] for line in studio.get("/api/log?t0=0") if line["robots"][0]["path"]]
        frames = robot.frames()
        assert len(ticks) == len(frames) == 100
        for tick, frame in zip(ticks, frames, strict=True):
            assert shown(tick) == expected(frame, enums)
        # what the robot cannot do is refused with the reason, not dropped
        code, reply = studio.command(op="force_option", robot=0, option="look_around", params={"turn": 5})
        assert not reply["ok"] and "a NaoTH robot cannot force an option" in reply["error"], (code, reply)
        code, reply = studio.command(op="override_input", robot=0, symbol="ball.distance", value=5.0)
        assert not reply["ok"] and "cannot override an input symbol" in reply["error"]
        code, reply = studio.command(op="pause")
        assert not reply["ok"] and "cannot pause" in reply["error"]
    finally:
        output = studio.stop()
    files = list((tmp_path / "rec").glob("*.mcap"))
    assert len(files) == 1, (sorted(p.name for p in (tmp_path / "rec").iterdir()), output[-4000:])
    with Recording(files[0]) as recording:
        paths = [t.agents[next(iter(t.agents))].path for t in recording.ticks()]
    assert sum(1 for p in paths if p) == 100


def test_switching_agents_and_uploading_an_edited_behavior_reach_the_robot(robot: Robot, behavior: Path) -> None:
    studio = Studio(f"naoth://127.0.0.1:{robot.port}", "--behavior", str(behavior), "--no-record")
    try:
        studio.until(lambda s: s["attached"][0]["received"] == 100)
        code, reply = studio.command(op="select_agent", robot=0, agent="looker")
        assert code == 200 and reply["ok"], reply
        studio.until(lambda s: s["attached"][0]["received"] == 200 and s["attached"][0]["agent"] == "looker")
        last = studio.get("/api/log?t0=0")[-1]["robots"][0]
        assert last["path"][0]["option"] == "look_around" and robot.frames()[-1]["agent"] == "looker"
        code, reply = studio.command(op="select_agent", robot=0, agent="nobody")
        assert not reply["ok"]

        # upload + reload: our compiler's IC is what the robot reads, and its frames show the edit
        path = "options/look_around.xabsl"
        current = studio.get(f"/api/files/{path}")
        text = current["text"].replace("motion.walk_speed.x = 0;", "motion.walk_speed.x = 5;")
        code, saved = studio.send("PUT", f"/api/files/{path}", {"text": text}, {"If-Match": f'"{current["version"]}"'})
        assert code == 200 and saved["ok"], saved
        edited = compile_file(str(behavior / "agents.xabsl")).program
        assert edited is not None
        assert (robot.config / "behavior-ic.dat").read_bytes() == emit_ic(edited).encode("latin-1")
        status = studio.until(lambda s: s["attached"][0]["received"] >= 300)
        assert status["attached"][0]["mismatches"] == []
        last = studio.get("/api/log?t0=0")[-1]["robots"][0]
        assert last["outputs"]["motion.walk_speed.x"] == 5.0 == robot.frames()[-1]["outputs"]["motion.walk_speed.x"]
    finally:
        studio.stop()


def test_sources_that_differ_from_the_robots_behavior_are_named(robot: Robot, behavior: Path) -> None:
    option = behavior / "options" / "go_to_ball.xabsl"
    option.write_text(
        option.read_text().replace("target state kick", "target state shoot").replace("goto kick", "goto shoot")
    )
    studio = Studio(f"naoth://127.0.0.1:{robot.port}", "--behavior", str(behavior), "--no-record")
    try:
        status = studio.until(lambda s: s["attached"][0]["received"] == 100)
        mismatches = status["attached"][0]["mismatches"]
        assert "option 'go_to_ball': state 'kick' is on the robot, not in the sources" in mismatches
        assert "option 'go_to_ball': state 'shoot' is in the sources, not on the robot" in mismatches
        assert "the robot runs other sources" in (status["programs"]["behavior"]["error"] or "")
        ticks = [line["robots"][0] for line in studio.get("/api/log?t0=0")]
        # a frame in the state our sources do not have shows go_to_ball's caller only, never "shoot"
        assert not any(n.get("state") == "shoot" for t in ticks for n in t["path"])
        assert status["attached"][0]["unplaced"] > 0
    finally:
        studio.stop()


def test_a_shared_slot_serves_a_second_studio_through_the_first(tmp_path: Path, behavior: Path) -> None:
    from ..attach.test_attached import free_port

    robot = Robot(tmp_path, "--step", "3", "--frames", "30")  # 10 frames, 10 more per agent switch
    port = free_port()
    first = Studio(f"naoth://127.0.0.1:{robot.port}", "--behavior", str(behavior), "--no-record", "--share", str(port))
    try:
        first.until(lambda s: s["attached"][0]["seq"] == 30)
        second = Studio(f"naoth://127.0.0.1:{port}", "--behavior", str(behavior), "--no-record")
        try:
            second.until(lambda s: s["attached"][0]["seq"] == 30 and s["attached"][0]["agents"] == ["soccer", "looker"])
            # the second studio switches the agent through the first; the robot runs 10 more frames
            code, reply = second.command(op="select_agent", robot=0, agent="looker")
            assert code == 200 and reply["ok"], reply
            second.until(lambda s: s["attached"][0]["seq"] == 60)
            first.until(lambda s: s["attached"][0]["seq"] == 60 and s["attached"][0]["agent"] == "looker")
            a, b = first.status()["attached"][0], second.status()["attached"][0]
            # each new frame went to the one studio that asked; the last of each grant, repeated, to both
            assert 20 <= a["received"] + b["received"] <= 22 and b["mismatches"] == []
            program = compile_file(str(behavior / "agents.xabsl")).program
            assert program is not None
            enums = {name: e.elements for name, e in program.enums.items()}
            truth = [expected(f, enums) for f in robot.frames()]
            ticks = [line["robots"][0] for line in second.get("/api/log?t0=0") if line["robots"][0]["path"]]
            assert len(ticks) == b["received"] >= 2
            assert all(shown(tick) in truth for tick in ticks)
            assert shown(ticks[-1]) == truth[-1] and ticks[-1]["path"][0]["option"] == "look_around"
        finally:
            second.stop()
    finally:
        first.stop()
        robot.stop()


def test_a_naoth_robot_needs_the_sources(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "attach", "naoth://127.0.0.1:5401"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 2 and "needs --behavior" in done.stderr


def test_a_port_that_answers_what_no_robot_would_is_left_and_tried_again(behavior: Path) -> None:
    import socket
    import struct
    import threading

    server = socket.create_server(("127.0.0.1", 0))
    connections: list[bytes] = []

    def serve() -> None:  # answers the first command with an answer of 100 MB, never sent
        while True:
            try:
                client, _ = server.accept()
            except OSError:
                return
            with client:
                head = client.recv(8)
                connections.append(head)
                if len(head) == 8:
                    client.sendall(struct.pack("<iI", struct.unpack("<i", head[:4])[0], 100 * 1024 * 1024))
                    client.recv(1)

    threading.Thread(target=serve, daemon=True).start()
    studio = Studio(f"naoth://127.0.0.1:{server.getsockname()[1]}", "--behavior", str(behavior), "--no-record")
    try:
        studio.until(lambda s: len(connections) >= 2)  # left, and tried again
        status = studio.status()
        assert not status["attached"][0]["connected"] and status["attached"][0]["received"] == 0
        assert struct.unpack("<i", connections[0][:4])[0] == 1  # ids start at 1
    finally:
        studio.stop()
        server.close()
