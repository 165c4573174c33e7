"""Breakpoints and the recorded "why" through the live server: hits pause at the right tick, persist."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx2 as httpx
import orjson
import pytest

from tests.server.conftest import LiveServer
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.session.live import Session


@pytest.fixture
def server(demo_dir: Path, tmp_path: Path) -> Iterator[LiveServer]:
    session = Session(BenchExample(demo_dir), seed=3, speed=5.0, state_dir=tmp_path / "state")
    with LiveServer(session) as live:
        yield live
    session.stop()


def _ticks(server: LiveServer, t0: int, t1: int) -> list[dict[str, Any]]:
    with httpx.Client(base_url=server.url) as http:
        text = http.get("/api/log", params={"t0": t0, "t1": t1}).text
    return [orjson.loads(line) for line in text.splitlines() if line]


def _state(tick: dict[str, Any], robot: int, option: str) -> str | None:
    for node in tick["robots"][robot]["path"]:
        if node.get("option") == option:
            return str(node["state"])
    return None


def _hit(client: Any) -> dict[str, Any]:
    return client.until(lambda m: m["type"] == "event" and m["event"] == "breakpoint", timeout=30)


def test_enter_state_breakpoint_pauses_at_the_tick_the_state_is_entered(server: LiveServer, client_for: Any) -> None:
    client = client_for(server)
    client.wait_hello("connect")
    reply = client.command("set_breakpoint", kind="enter_state", option="play", state="chase")
    assert reply["ok"], reply
    (listed,) = reply["result"]["breakpoints"]
    assert listed["description"] == "enter play.chase" and listed["problem"] is None
    event = _hit(client)
    assert event["description"] == "enter play.chase" and event["program"] == "demo"
    assert client.command("status")["result"]["paused"] is True
    robot, t = event["robot"], event["t"]
    ticks = {tick["seq"]: tick for tick in _ticks(server, t - 200, t)}
    assert _state(ticks[event["seq"]], robot, "play") == "chase"
    assert _state(ticks[event["seq"] - 1], robot, "play") != "chase", "the hit is the tick of the transition"
    # Why at that tick, from the recorded values: the transition into chase with its operand values.
    why = client.command("explain", robot=robot, option="play", seq=event["seq"])["result"]
    assert why["recorded"] is True and why["seq"] == event["seq"]
    assert why["target_name"] == "chase" and not why["stay"]
    compared = [k for c in why["conditions"] for k in c["comparisons"]]
    assert any(k["left"] == "game.state" and k["left_value"] == "playing" for k in compared), compared
    assert why["tree"]["taken"] is True and "if" in why["tree"]
    assert why["last_transition"]["seq"] == event["seq"]


def test_a_condition_breakpoint_checks_symbols_and_hits_when_it_becomes_true(
    server: LiveServer, client_for: Any
) -> None:
    client = client_for(server)
    client.wait_hello("connect")
    bad = client.command("set_breakpoint", kind="condition", condition="ball.seen && ball.distanc < 900")
    assert bad["ok"] is False and "1:14: no matching symbol" in bad["error"] and "ball.distance" in bad["error"]
    checked = client.command("check_condition", condition="ball.distance <")["result"]
    assert checked["ok"] is False and checked["diagnostics"][0]["span"]["col"] == 16
    assert client.command("check_condition", condition="ball.distance < 900")["result"] == {
        "ok": True,
        "diagnostics": [],
    }
    reply = client.command("set_breakpoint", kind="condition", condition="ball.seen && ball.distance < 900", robot=1)
    assert reply["ok"], reply
    event = _hit(client)
    assert event["robot"] == 1
    tick = next(tick for tick in _ticks(server, event["t"], event["t"]) if tick["seq"] == event["seq"])
    inputs = tick["robots"][1]["inputs"]
    assert inputs["ball.seen"] is True and inputs["ball.distance"] < 900


def test_breakpoints_are_listed_disabled_removed_and_persist(
    server: LiveServer, client_for: Any, demo_dir: Path, tmp_path: Path
) -> None:
    client = client_for(server)
    client.wait_hello("connect")
    client.command("pause")
    assert client.command("set_breakpoint", kind="leaf", option="play", state="chase", leaf=7)["ok"] is False
    first = client.command("set_breakpoint", kind="enter_option", option="search_ball", enabled=False)["result"]
    second = client.command("set_breakpoint", kind="leave_state", option="play", state="wait")["result"]
    ids = [b["breakpoint"] for b in second["breakpoints"]]
    assert ids == [1, 2] and first["breakpoints"][0]["enabled"] is False
    toggled = client.command("enable_breakpoint", breakpoint=1, enabled=True)["result"]
    assert toggled["breakpoints"][0]["enabled"] is True
    assert client.command("remove_breakpoint", breakpoint=2)["ok"]
    assert client.command("remove_breakpoint", breakpoint=2)["ok"] is False
    assert [b["breakpoint"] for b in client.command("list_breakpoints")["result"]["breakpoints"]] == [1]
    files = list((tmp_path / "state" / "breakpoints").glob("*.json"))
    assert len(files) == 1 and not list(files[0].parent.glob("*.tmp*"))
    again = Session(BenchExample(demo_dir), state_dir=tmp_path / "state")
    assert [(p.id, p.kind, p.option) for p in again.breakpoints["demo"].values()] == [
        (1, "enter_option", "search_ball")
    ]


def test_why_at_a_past_tick_uses_that_ticks_values(server: LiveServer, client_for: Any) -> None:
    client = client_for(server)
    client.wait_hello("connect")
    frame = client.wait_frame(lambda f: f["t"] > 3000, timeout=30)
    client.command("pause")
    live = client.command("explain", robot=0, option="play")["result"]
    assert live["recorded"] is False and "tree" in live
    # the live why continues its scan of the ring: the same last transition when nothing ran since
    again = client.command("explain", robot=0, option="play")["result"]
    assert again["last_transition"] == live["last_transition"]
    if live["last_transition"] is not None:
        assert live["last_transition"]["target_name"] != live["last_transition"]["decided_in_name"]
    past = frame["seq"] - 40
    why = client.command("explain", robot=0, option="play", seq=past)["result"]
    assert why["seq"] == past and why["recorded"] is True
    tick = next(tick for tick in _ticks(server, 0, why["t"]) if tick["seq"] == past)
    game_states = ["init", "ready", "set", "playing", "finished"]
    compared = [k for c in why["conditions"] for k in c["comparisons"]]
    assert compared
    for k in compared:
        recorded = tick["robots"][0]["inputs"][k["left"]]
        if k["left"] == "game.state":
            assert k["left_value"] == game_states[recorded], (k, recorded)
        else:
            assert float(k["left_value"]) == pytest.approx(recorded, abs=1e-3), (k, recorded)
    gone = client.command("explain", robot=0, option="play", seq=10**9)
    assert gone["ok"] is False and "not in the ring" in gone["error"]
