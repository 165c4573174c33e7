"""The simulation in its own process: crashes, restarts, shutdown, the non-blocking pipe."""

from __future__ import annotations

import os
import signal
import socket
import time
from pathlib import Path
from typing import Any

import httpx2 as httpx

from tests.server.conftest import LiveServer
from tests.server.worlds import CrashingDemo
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.protocol.channel import Channel
from xabsl_studio.server.session.live import Session


def test_the_simulation_runs_in_another_process_and_stops_without_a_zombie(
    live_demo: LiveServer, client_for: Any
) -> None:
    client = client_for(live_demo)
    client.frame_after()
    status = client.command("status")["result"]
    pid = status["simulation"]["pid"]
    assert status["simulation"]["running"] is True and pid != os.getpid()
    assert status["simulation"]["pipe"]["sent"] > 0 and status["simulation"]["pipe"]["dropped"] == 0
    assert status["timing"]["ticks"] > 0 and status["timing"]["cpu_seconds"] > 0
    process = live_demo.session._process
    live_demo.__exit__(None, None, None)
    assert not process.is_alive() and process.exitcode == 0, "stopped on request"
    assert not Path(f"/proc/{pid}").exists(), "joined: no zombie left"


def test_a_crash_in_the_world_is_reported_and_reset_restarts_it(
    demo_dir: Path, tmp_path: Path, client_for: Any
) -> None:
    trigger = tmp_path / "crash-now"
    session = Session(CrashingDemo(demo_dir, trigger), seed=7, speed=5.0)
    with LiveServer(session) as server, httpx.Client(base_url=server.url) as http:
        client = client_for(server)
        first = client.wait_hello("connect")
        client.wait_frame(lambda f: f["t"] > 500)
        trigger.touch()
        event = client.until(lambda m: m["type"] == "event" and m["event"] == "crash")
        assert "the ball fell off the world" in event["message"]
        status = http.get("/api/status").json()
        assert status["simulation"]["running"] is False
        assert "RuntimeError" in status["simulation"]["crash"]["message"]
        assert status["simulation"]["crash"]["exit_code"] == 1
        refused = client.command("pause")
        assert refused["ok"] is False and "reset starts it again" in refused["error"]
        # The ring is still there for the timeline.
        assert client.command("history", t0=0, t1=400)["ok"]
        last_seq = status["seq"]
        trigger.unlink()
        assert client.command("reset")["result"] == {"seed": 7}
        hello = client.wait_hello("reset")
        assert hello["generation"] > first["generation"] and hello["session"]["seed"] == 7
        frame = client.wait_frame(lambda f: f["gen"] == hello["generation"])
        assert frame["seq"] > last_seq, "seq goes on across the restart"
        status = http.get("/api/status").json()
        assert status["simulation"]["running"] is True and status["simulation"]["restarts"] == 1
        assert status["simulation"]["crash"] is None
        assert client.command("pause")["ok"]


def test_a_killed_simulation_is_reported_and_reset_restarts_it(live_demo: LiveServer, client_for: Any) -> None:
    client = client_for(live_demo)
    client.frame_after()
    os.kill(live_demo.session.pid, signal.SIGKILL)
    event = client.until(lambda m: m["type"] == "event" and m["event"] == "crash")
    assert "exit code -9" in event["message"]
    assert client.command("step")["ok"] is False
    assert client.command("reset", seed=9)["result"] == {"seed": 9}
    hello = client.wait_hello("reset")
    client.wait_frame(lambda f: f["gen"] == hello["generation"] and f["t"] > 100)


def test_the_channel_drops_samples_instead_of_blocking_and_keeps_the_rest_in_order() -> None:
    a, b = socket.socketpair()
    sender, receiver = Channel(a), Channel(b)
    payload = b"x" * 8000
    sent = []
    started = time.perf_counter()
    for i in range(2000):  # about 16 MB, far beyond the socket buffers: nobody reads meanwhile
        if sender.send(("s", i, payload), droppable=True):
            sent.append(i)
    assert time.perf_counter() - started < 2.0, "never blocks"
    assert sender.dropped > 0 and len(sent) + sender.dropped == 2000
    sender.send(("r", "must arrive"))  # not droppable: queued behind the backlog
    received = []
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        sender.flush()
        received.extend(receiver.receive())
        if received and received[-1][0] == "r":
            break
    assert [m[1] for m in received[:-1]] == sent and received[-1] == ("r", "must arrive")
    sender.close()
    receiver.close()


def test_a_number_beyond_a_decimal_is_a_command_error_even_past_the_edge(demo_dir: Path) -> None:
    """Issue 18 item 3 in the simulation itself: no ``internal error: OverflowError``."""
    import pytest

    from xabsl_studio.server.protocol.commands import ForceBehavior, OverrideInput
    from xabsl_studio.server.simulation.worker import CommandError, Simulation, WorkerConfig

    session = Session(BenchExample(demo_dir), seed=4)  # compiles; its process is never started
    programs = {k: (s.running, s.running_json) for k, s in session.programs.items()}
    sim = Simulation(WorkerConfig(session.example, seed=4, programs=programs))  # type: ignore[arg-type]
    sim.generation("connect")
    with pytest.raises(CommandError, match="out of the range of a decimal"):
        sim.execute(OverrideInput(op="override_input", robot=0, symbol="ball.distance", value=10**400))
    with pytest.raises(CommandError, match="out of the range of a decimal"):
        sim.execute(ForceBehavior(op="force_behavior", robot=0, behavior="walk", params={"speed": -(10**400)}))
    assert sim.execute(OverrideInput(op="override_input", robot=0, symbol="ball.distance", value=2**63 - 1)) is None
