"""``xabsl attach`` end to end: robot processes of their own, the studio as its own process, faults.

The robots are ``examples/attach/robot.py`` processes; the studio is the real command line
(``xabsl attach``) served over HTTP, read through ``/api/status``, ``/api/log`` and
``/api/command`` as a user's tools would.
"""

from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from xabsl_studio.examples.attach.robot import DEMO, GAME_STATES
from xabsl_studio.server.protocol.attach import HEARTBEAT_TIMEOUT, Welcome
from xabsl_studio.server.protocol.host import Sample

from .peer import REPO, Peer, start_robot, stop_robot

TOKEN = "attach-test-token-0123456789"


def free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Studio:
    """``xabsl attach ...`` as a subprocess on a free port."""

    def __init__(self, *args: str) -> None:
        self.port = free_port()
        command = [sys.executable, "-m", "xabsl_studio.engine.cli", "attach", *args, "--port", str(self.port)]
        self.process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=REPO)
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(self.process.communicate()[0])
            try:
                self.status()
                return
            except (urllib.error.URLError, ConnectionError):
                time.sleep(0.2)
        raise RuntimeError("xabsl attach did not start")

    def get(self, path: str) -> Any:
        with urllib.request.urlopen(f"http://127.0.0.1:{self.port}{path}", timeout=10) as response:
            body = response.read()
        return json.loads(body) if not path.startswith("/api/log") else [json.loads(x) for x in body.splitlines()]

    def status(self) -> dict[str, Any]:
        return self.get("/api/status")  # type: ignore[no-any-return]

    def send(self, method: str, path: str, body: dict[str, Any], headers: dict[str, str] | None = None) -> Any:
        request = urllib.request.Request(
            f"http://127.0.0.1:{self.port}{path}",
            data=json.dumps(body).encode(),
            method=method,
            headers={"content-type": "application/json", **(headers or {})},
        )
        try:
            with urllib.request.urlopen(request, timeout=30) as response:
                return response.status, json.loads(response.read())
        except urllib.error.HTTPError as error:
            return error.code, json.loads(error.read())

    def command(self, **body: Any) -> Any:
        return self.send("POST", "/api/command", body)

    def until(self, predicate: Any, timeout: float = 20.0) -> dict[str, Any]:
        deadline = time.monotonic() + timeout
        status = self.status()
        while time.monotonic() < deadline:
            if predicate(status):
                return status
            time.sleep(0.1)
            status = self.status()
        raise AssertionError(f"not within {timeout} s: {status.get('attached')}")

    def stop(self) -> str:
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGCONT)
            self.process.terminate()
        try:
            return self.process.communicate(timeout=15)[0]
        except subprocess.TimeoutExpired:
            self.process.kill()  # uvicorn waits for lingering connections: the test is over
            return self.process.communicate(timeout=15)[0]


@pytest.fixture
def robot() -> Iterator[tuple[subprocess.Popen[str], int]]:
    process, port = start_robot("--hz", "100")
    yield process, port
    stop_robot(process)


def test_every_tick_of_the_host_arrives_and_forcing_shows_on_the_next(robot: tuple[Any, int]) -> None:
    studio = Studio(f"127.0.0.1:{robot[1]}", "--behavior", str(DEMO), "--no-record")
    try:
        status = studio.until(lambda s: s["attached"][0]["received"] > 200)
        host = status["attached"][0]
        assert host["connected"] and host["missed"] == 0 and host["controlled_here"]
        code, reply = studio.command(op="force_option", robot=0, option="approach_ball", params={"stop_at": 100})
        assert code == 200 and reply["ok"], reply
        at = studio.status()["seq"]
        studio.until(lambda s: s["seq"] > at + 5)
        ticks = [line for line in studio.get("/api/log?t0=0") if line["seq"] > at]
        assert ticks and all(t["robots"][0]["path"][0]["option"] == "approach_ball" for t in ticks)
        assert ticks[0]["robots"][0]["path"][0]["params"] == {"approach_ball.stop_at": 100.0}
        assert studio.status()["attached"][0]["missed"] == 0
    finally:
        studio.stop()


def test_the_studio_network_going_away_releases_the_robot(robot: tuple[Any, int]) -> None:
    studio = Studio(f"127.0.0.1:{robot[1]}", "--no-record")
    watcher = Peer(robot[1], studio="watcher", control=False)
    try:
        assert isinstance(watcher.welcome(), Welcome)
        studio.until(lambda s: s["attached"][0]["connected"])
        code, reply = studio.command(op="force_option", robot=0, option="search_ball", params={})
        assert code == 200 and reply["ok"], reply
        watcher.until(lambda m: isinstance(m, Sample) and b'"forced"' in m.extras[0])
        # The laptop freezes (its process stops: no close, no heartbeat, the socket stays open).
        studio.process.send_signal(signal.SIGSTOP)
        deadline = time.monotonic() + HEARTBEAT_TIMEOUT + 5.0
        released = False
        while time.monotonic() < deadline and not released:
            released = any(isinstance(m, Sample) and m.extras[0] == b"" for m in watcher.read(0.5))
            watcher.heartbeat()
        assert released, "the robot kept running the forced option"
    finally:
        watcher.close()
        studio.stop()


def test_a_host_killed_mid_session_is_marked_and_reattaches() -> None:
    process, port = start_robot("--hz", "100")
    studio = Studio(f"127.0.0.1:{port}", "--no-record")
    try:
        studio.until(lambda s: s["attached"][0]["received"] > 50)
        process.kill()
        stop_robot(process)
        status = studio.until(lambda s: s["attached"][0]["gone"])
        assert not status["attached"][0]["connected"] and status["ring"]["frames"] > 50  # the history stays
        structure = studio.get("/api/structure")
        assert structure["robots"][0]["gone"] is True
        process, _ = start_robot("--hz", "100", "--port", str(port))
        status = studio.until(lambda s: s["attached"][0]["connected"] and not s["attached"][0]["gone"])
        assert studio.get("/api/structure")["robots"][0]["gone"] is False
    finally:
        studio.stop()
        stop_robot(process)


def test_a_wrong_token_is_refused_and_shown() -> None:
    process, port = start_robot("--token", TOKEN)
    studio = Studio(f"127.0.0.1:{port}", "--token", "not-the-token-0123456789", "--no-record")
    try:
        status = studio.until(lambda s: s["attached"][0]["refused"] is not None)
        assert "token" in status["attached"][0]["refused"] and not status["attached"][0]["connected"]
    finally:
        studio.stop()
        stop_robot(process)


def test_a_save_that_fails_on_the_host_answers_its_error_and_the_robot_runs_on(tmp_path: Path) -> None:
    demo = tmp_path / "demo"
    shutil.copytree(DEMO.parent, demo)
    process, port = start_robot("--hz", "100", "--behavior", str(demo / "agents.xabsl"))
    studio = Studio(f"127.0.0.1:{port}", "--behavior", str(demo), "--no-record")
    try:
        studio.until(lambda s: s["attached"][0]["received"] > 20)
        files = {f["path"]: f for f in studio.get("/api/files")["files"]}
        behaviors = next(p for p in files if p.endswith("basic_behaviors.xabsl"))
        search = next(p for p in files if p.endswith("search_ball.xabsl"))
        text = (demo / "basic_behaviors.xabsl").read_text()
        code, _ = studio.send(
            "PUT",
            f"/api/files/{behaviors}",
            {
                "text": text.rstrip().rstrip("}") + "\n  behavior dance { float style; }\n}\n",
                "version": files[behaviors]["version"],
            },
        )
        assert code == 200
        original = text = (demo / "options" / "search_ball.xabsl").read_text()
        code, body = studio.send(
            "PUT",
            f"/api/files/{search}",
            {"text": text.replace("turn(rate = 45);", "dance(style = 1);"), "version": files[search]["version"]},
        )
        assert code == 422 and "does not run on this host" in body["detail"] and "dance" in body["detail"], body
        gen = studio.status()["generation"]
        at = studio.status()["seq"]
        studio.until(lambda s: s["seq"] > at + 10)
        assert studio.status()["generation"] == gen
        assert studio.status()["attached"][0]["connected"]
        # A clean save reloads into the robot between two ticks.
        code, body = studio.send(
            "PUT",
            f"/api/files/{search}",
            {"text": original.replace("4000", "1500"), "version": studio.get(f"/api/files/{search}")["version"]},
        )
        assert code == 200 and body["reloaded"] == ["demo"], body
        studio.until(lambda s: s["generation"] > gen)
    finally:
        studio.stop()
        stop_robot(process)


def test_five_robot_processes_in_one_session() -> None:
    robots = [start_robot("--hz", "50", "--seed", str(i), "--name", f"robot{i}") for i in range(1, 6)]
    studio = Studio(*(f"127.0.0.1:{port}" for _, port in robots), "--no-record")
    try:
        status = studio.until(lambda s: all(h["received"] > 20 for h in s["attached"]))
        assert [h["robots"] for h in status["attached"]] == [[f"robot{i}"] for i in range(1, 6)]
        assert all(h["missed"] == 0 for h in status["attached"])
        names = [r["name"] for r in studio.get("/api/structure")["robots"]]
        assert names == [f"robot{i}" for i in range(1, 6)]
        code, reply = studio.command(op="force_option", robot=3, option="search_ball", params={})
        assert code == 200 and reply["ok"], reply
        at = studio.status()["seq"]
        studio.until(lambda s: s["seq"] > at + 20)
        last = studio.get("/api/log?t0=0")[-1]["robots"]
        assert last[3]["path"][0]["option"] == "search_ball" and "forced" in last[3]
        assert all("forced" not in r for i, r in enumerate(last) if i != 3)
    finally:
        studio.stop()
        for process, _ in robots:
            stop_robot(process)


def _agrees(value: Any, logged: Any, symbol: str) -> bool:
    """A value the decision read (exact) against the tick's logged display value (rounded, enums as indices)."""
    if symbol == "game.state":
        return value == GAME_STATES[logged]
    if isinstance(logged, bool) or isinstance(value, bool):
        return value is logged
    return abs(float(value) - float(logged)) <= 1e-3


def test_why_shows_the_values_the_robot_decision_read_and_works_with_the_host_gone(robot: tuple[Any, int]) -> None:
    process, port = robot
    studio = Studio(f"127.0.0.1:{port}", "--no-record")
    try:
        studio.until(lambda s: s["attached"][0]["received"] > 300)
        ticks = {t["seq"]: t for t in studio.get("/api/log?t0=0")}
        checked = 0
        answers: dict[int, Any] = {}
        for seq in sorted(ticks)[5::10]:
            inputs = ticks[seq]["robots"][0]["inputs"]
            code, reply = studio.command(op="explain", robot=0, option="play", seq=seq)
            assert code == 200 and reply["ok"], reply
            why = reply["result"]
            assert why["recorded"] and why["seq"] == seq
            assert why["decided_in_name"] == ticks[seq]["robots"][0]["path"][0]["decided_in"]
            answers[seq] = why
            for condition in why["conditions"]:
                if condition["source"] in inputs:  # a bare boolean input: its value is the condition's
                    assert condition["value"] is inputs[condition["source"]], (seq, condition)
                    checked += 1
                for comparison in condition["comparisons"]:
                    if comparison["left"] in inputs:
                        left = comparison["left"]
                        assert _agrees(comparison["left_value"], inputs[left], left), (seq, comparison, inputs)
                        checked += 1
        assert checked >= 20
        # The live why is the latest tick's decision, from what it read (recorded=False: "the last tick").
        code, reply = studio.command(op="explain", robot=0, option="play")
        assert code == 200 and reply["ok"] and reply["result"]["recorded"] is False, reply
        assert reply["result"]["seq"] is not None and all(c["value"] is not None for c in reply["result"]["conditions"])
        # The host goes away: why at the same ticks answers the same, from the studio's history alone.
        process.kill()
        studio.until(lambda s: s["attached"][0]["gone"])
        for seq, why in answers.items():
            code, reply = studio.command(op="explain", robot=0, option="play", seq=seq)
            assert code == 200 and reply["ok"], reply
            assert reply["result"]["conditions"] == why["conditions"]
    finally:
        studio.stop()


def test_attach_host_adds_a_robot_process_and_refuses_what_is_not_an_address(robot: tuple[Any, int]) -> None:
    studio = Studio(f"127.0.0.1:{robot[1]}", "--no-record")
    other, port = start_robot("--hz", "50", "--name", "robot9")
    try:
        studio.until(lambda s: s["attached"][0]["connected"])
        code, reply = studio.command(op="attach_host", address="not an address")
        assert code == 400 and "address" in json.dumps(reply), reply
        code, reply = studio.command(op="attach_host", address=f"127.0.0.1:{port}")
        assert code == 200 and reply["ok"] and reply["result"]["connected"], reply
        assert reply["result"]["robots"] == ["robot9"]
        status = studio.until(lambda s: len(s["attached"]) == 2 and s["attached"][1]["received"] > 10)
        assert status["attached"][1]["missed"] == 0
        assert [r["name"] for r in studio.get("/api/structure")["robots"]] == ["robot1", "robot9"]
        code, reply = studio.command(op="force_option", robot=1, option="search_ball", params={})
        assert code == 200 and reply["ok"], reply
    finally:
        studio.stop()
        stop_robot(other)


def test_attach_host_is_refused_when_the_studio_does_not_allow_it(robot: tuple[Any, int]) -> None:
    studio = Studio(f"127.0.0.1:{robot[1]}", "--no-record", "--no-connect")
    try:
        studio.until(lambda s: s["attached"][0]["connected"])
        code, reply = studio.command(op="attach_host", address="127.0.0.1:9")
        assert not reply.get("ok") and "--no-connect" in json.dumps(reply), (code, reply)
        assert len(studio.status()["attached"]) == 1
    finally:
        studio.stop()
