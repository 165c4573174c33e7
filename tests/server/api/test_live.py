"""The studio against a real uvicorn on a loopback port, with real websocket clients.

Most tests run the demo behavior in the small kinematic world at 5x (fast, no pymunk); the
first ones run the soccer example (2 vs 2, both XABSL teams) to prove the product's default.
"""

from __future__ import annotations

import itertools
import logging
import time
from pathlib import Path
from typing import Any

import httpx2 as httpx
import orjson
import pytest

from tests.server.conftest import LiveServer, WsClient
from xabsl_studio.server.session.live import Session


def _names(client: WsClient, agent: int) -> list[str]:
    """The option / basic behavior names of an agent's path in the latest frame."""
    program = client.program(agent)
    options = {o["id"]: o["name"] for o in program["options"]}
    behaviors = {b["id"]: b["name"] for b in program["behaviors"]}
    assert client.frame is not None
    return [options[n[2]] if n[0] == 0 else behaviors[n[2]] for n in client.frame["robots"][agent]["path"]]


# -- soccer ---------------------------------------------------------------------------------------


def test_soccer_hello_and_frames_for_all_agents(soccer_session: Session, client_for: Any) -> None:
    with LiveServer(soccer_session) as server:
        client = client_for(server)
        hello = client.until(lambda m: m["type"] == "hello")
        assert hello["version"] == 1 and hello["reason"] == "connect"
        agents = hello["structure"]["robots"]
        assert [(a["team"], a["number"]) for a in agents] == [("blue", 1), ("blue", 2), ("red", 1), ("red", 2)]
        assert {a["program"] for a in agents} == {"behavior", "chase"}
        assert set(hello["structure"]["programs"]) == {"behavior", "chase"}
        assert hello["scene"]["kind"] == "soccer"
        first = client.frame_after()
        assert first["full"] is True
        for _ in range(10):
            frame = client.frame_after()
        assert [a["id"] for a in frame["robots"]] == [0, 1, 2, 3]
        for agent in frame["robots"]:
            assert agent["path"], "every XABSL agent has an activation path"
        assert _names(client, 0)[0] == "play_soccer"
        assert len(frame["scene"]["robots"]) == 4
        # Symbol values merged from deltas equal the server's current full values at some frame.
        assert client.values[0]["inputs"] and client.values[2]["outputs"] is not None


def test_soccer_frames_are_compact(soccer_session: Session, client_for: Any) -> None:
    with LiveServer(soccer_session) as server:
        client = client_for(server)
        for _ in range(40):
            client.frame_after()
        deltas = sorted(client.sizes[1:])
        # 4 agents here; the benchmark measures 10 (goal: < 4 KB there).
        assert deltas[len(deltas) // 2] < 2000, deltas


# -- frames, subscription, resync -----------------------------------------------------------------


def test_subscribe_rate_and_agent_filter(live_demo: LiveServer, client_for: Any) -> None:
    client = client_for(live_demo)
    client.frame_after()
    client.send({"type": "subscribe", "rate": 5, "robots": [1], "id": "s"})
    assert client.until(lambda m: m["type"] == "reply" and m["id"] == "s")["ok"] is True
    frame = client.frame_after()
    assert frame["full"] is True, "a new subscription starts with a full frame"
    assert "inputs" not in frame["robots"][0] and "inputs" in frame["robots"][1]
    started = time.monotonic()
    seqs = [client.frame_after()["seq"] for _ in range(5)]
    elapsed = time.monotonic() - started
    # 5 Hz wanted while the session ticks 200 times a second (40 Hz x 5): about 40 ticks apart.
    gaps = [b - a for a, b in itertools.pairwise(seqs)]
    assert min(gaps) >= 30, gaps
    assert elapsed > 0.6


def test_delta_values_converge_to_exact_values(live_demo: LiveServer, client_for: Any) -> None:
    slow = client_for(live_demo)
    slow.send({"type": "subscribe", "rate": 3})
    for _ in range(6):
        slow.frame_after()
    # Pause, then compare what the skipping client merged with a fresh full frame.
    slow.command("pause")
    latest = live_demo.session.ring.latest
    assert latest is not None
    slow.send({"type": "resync"})
    slow.wait_hello("resync")
    frame = slow.frame_after()
    assert frame["full"] is True and frame["seq"] == latest.seq
    # The full frame's values equal the latest tick's values the server sampled.
    gen = latest.gen
    assert latest.inputs is not None
    for i, agent in enumerate(frame["robots"]):
        expected = {str(k): v for k, v in zip(gen.input_ids[i], latest.inputs[i], strict=True)}
        assert agent["inputs"] == expected


def test_skipping_client_merges_to_the_same_values_as_a_fast_one(live_demo: LiveServer, client_for: Any) -> None:
    fast, slow = client_for(live_demo), client_for(live_demo)
    fast.send({"type": "subscribe", "rate": 60})
    slow.send({"type": "subscribe", "rate": 2})
    for _ in range(4):
        slow.frame_after()
    fast.command("pause")
    # Drain both until each has the last frame before the pause.
    target = live_demo.session.ring.latest.seq  # type: ignore[union-attr]
    fast.command("step")
    target += 1
    for c in (fast, slow):
        if c.frame is None or c.frame["seq"] != target:
            c.wait_frame(lambda f, t=target: f["seq"] == t, timeout=10)
    assert fast.frames > slow.frames + 5
    assert fast.values == slow.values


def test_resync_sends_hello_and_full_frame(live_demo: LiveServer, client_for: Any) -> None:
    client = client_for(live_demo)
    client.frame_after()
    client.send({"type": "resync"})
    client.wait_hello("resync")
    assert client.frame_after()["full"] is True


# -- commands ------------------------------------------------------------------------------------------


def test_pause_step_resume_speed(live_demo: LiveServer, client_for: Any) -> None:
    client = client_for(live_demo)
    client.frame_after()
    assert client.command("pause")["result"] == {"paused": True}
    time.sleep(0.1)
    seq = live_demo.session.ring.latest.seq  # type: ignore[union-attr]
    time.sleep(0.3)
    assert live_demo.session.ring.latest.seq == seq, "paused: no ticks"  # type: ignore[union-attr]
    stepped = client.command("step", ticks=3)["result"]
    assert stepped["seq"] == seq + 3
    assert client.wait_frame(lambda f: f["seq"] == seq + 3)["t"] == stepped["t"]
    refused = client.command("step", ticks=0)
    assert refused["ok"] is False and "ticks" in refused["error"]
    assert client.command("speed", speed=2.5)["result"] == {"speed": 2.5}
    assert client.command("speed", speed=50)["ok"] is False
    assert client.command("resume")["result"] == {"paused": False}
    client.wait_frame(lambda f: f["seq"] > seq + 10)
    status = client.command("status")["result"]
    assert status["speed"] == 2.5 and status["paused"] is False


def test_reset_with_seed_sends_hello_and_restarts_time(live_demo: LiveServer, client_for: Any) -> None:
    client = client_for(live_demo)
    client.wait_frame(lambda f: f["t"] > 1000)
    assert client.command("reset", seed=11)["result"] == {"seed": 11}
    hello = client.wait_hello("reset")
    assert hello["session"]["seed"] == 11
    client.wait_frame(lambda f: f["gen"] == hello["generation"])
    first = next(f for f in client.log if f["gen"] == hello["generation"])
    assert first["full"] is True and first["t"] < 1000
    assert client.command("reset", seed="x")["ok"] is False


def test_force_option_with_parameters_then_release(live_demo: LiveServer, client_for: Any) -> None:
    client = client_for(live_demo)
    client.frame_after()
    approach = client.option_id("approach_ball")
    reply = client.command("force_option", robot=1, option="approach_ball", params={"stop_at": 123})
    assert reply["ok"], reply
    frame = client.wait_frame(lambda f: f["robots"][1]["path"] and f["robots"][1]["path"][0][2] == approach)
    root = frame["robots"][1]["path"][0]
    assert root[:2] == [0, 0] and root[8] == [123.0]
    assert frame["robots"][1]["forced"] == [0, approach]
    assert _names(client, 0)[0] == "play", "the other agent is not forced"
    assert client.command("release", robot=1)["ok"]
    play = client.option_id("play")
    frame = client.wait_frame(lambda f: f["robots"][1]["path"][0][2] == play)
    assert "forced" not in frame["robots"][1]


def test_force_behavior_by_id_and_bad_forces(live_demo: LiveServer, client_for: Any) -> None:
    client = client_for(live_demo)
    client.frame_after()
    walk = next(b["id"] for b in client.program()["behaviors"] if b["name"] == "walk")
    assert client.command("force_behavior", robot=0, behavior=walk, params={"speed": 100, "direction": -20})["ok"]
    frame = client.wait_frame(lambda f: f["robots"][0]["path"][0][0] == 1)
    assert frame["robots"][0]["path"][0] == [1, 0, walk, frame["robots"][0]["path"][0][3], [100.0, -20.0]]
    for args, message in [
        ({"robot": 0, "option": "nope"}, "unknown option"),
        ({"robot": 9, "option": "play"}, "robot"),
        ({"robot": 0, "option": "approach_ball", "params": {"nope": 1}}, "no parameter"),
        ({"robot": 0, "option": "approach_ball", "params": {"stop_at": True}}, "decimal"),
        ({"robot": 0, "option": 9999}, "unknown option id"),
    ]:
        reply = client.command("force_option", **args)
        assert reply["ok"] is False and message in reply["error"], reply
    assert client.command("release", robot=0)["ok"]


def test_override_input_changes_a_decision_and_release(live_demo: LiveServer, client_for: Any) -> None:
    client = client_for(live_demo)
    client.wait_frame(lambda f: f["t"] > 600)  # the demo's game is playing after 500 ms
    seen = client.symbol_id("inputs", "ball.seen")
    chase = client.state_id("play", "chase")
    assert client.command("override_input", robot=0, symbol="ball.seen", value=True)["ok"]
    frame = client.wait_frame(lambda f: f["robots"][0]["path"][0][3] == chase and "overrides" in f["robots"][0])
    assert frame["robots"][0]["overrides"] == {str(seen): True}
    assert client.values[0]["inputs"][str(seen)] is True
    explained = client.command("explain", robot=0, option="play")["result"]
    assert explained["target_name"] == "chase" or explained["decided_in_name"] == "chase"
    assert all({"text", "value", "branch", "span"} <= set(c) for c in explained["conditions"])
    game_state = client.symbol_id("inputs", "game.state")
    # An enum value by element index: game.state.init (0) makes the common decision go to wait.
    assert client.command("override_input", robot=0, symbol=game_state, value=0)["ok"]
    wait = client.state_id("play", "wait")
    client.wait_frame(lambda f: f["robots"][0]["path"][0][3] == wait)
    assert client.command("release_input", robot=0)["ok"]
    frame = client.wait_frame(lambda f: f["robots"][0]["path"][0][3] != wait)
    assert "overrides" not in frame["robots"][0]
    assert client.command("override_input", robot=0, symbol="nope", value=1)["ok"] is False
    assert client.command("override_input", robot=0, symbol="ball.seen")["ok"] is False


def test_explain_history_select_agent_reset_agent_reload(live_demo: LiveServer, client_for: Any) -> None:
    client = client_for(live_demo)
    client.wait_frame(lambda f: f["t"] > 1200)
    explained = client.command("explain", robot=0, option="play")["result"]
    assert explained["option_name"] == "play" and explained["conditions"][0]["text"] == "game.state != playing"
    assert client.command("explain", robot=0, option="nope")["ok"] is False

    reply = client.command("history", t0=200, t1=800)
    assert reply["ok"], reply
    assert reply["result"]["frames"] > 10
    chunks = []
    while True:
        message = client.until(lambda m: m["type"] == "history")
        chunks.append(message)
        if message["last"]:
            break
    frames = [f for c in chunks for f in c["frames"]]
    assert len(frames) == reply["result"]["frames"]
    assert frames[0]["full"] is True and all(f["full"] is False for f in frames[1:])
    assert frames[0]["t"] >= 200 and frames[-1]["t"] <= 800
    assert [f["seq"] for f in frames] == list(range(frames[0]["seq"], frames[0]["seq"] + len(frames)))

    assert client.command("select_agent", robot=0, agent="searcher")["ok"]
    search = client.option_id("search_ball")
    client.wait_frame(lambda f: f["robots"][0]["path"][0][2] == search)
    assert client.command("select_agent", robot=0, agent="nobody")["ok"] is False
    assert client.command("reset_agent", robot=0)["ok"]
    reloaded = client.command("reload")
    assert reloaded["ok"] and reloaded["result"]["programs"]["demo"]["ok"]
    client.wait_hello("reload")
    assert client.command("reload", program="nope")["ok"] is False


def test_bad_messages_get_error_replies_and_the_connection_stays(live_demo: LiveServer, client_for: Any) -> None:
    client = client_for(live_demo)
    client.ws.send("{not json")
    assert client.until(lambda m: m["type"] == "reply")["error"].startswith("bad JSON")
    client.send({"type": "command", "id": 5, "op": "fly"})
    assert "unknown op" in client.until(lambda m: m["type"] == "reply" and m["id"] == 5)["error"]
    client.send({"type": "teleport", "id": 6})
    assert "unknown message type" in client.until(lambda m: m["type"] == "reply" and m["id"] == 6)["error"]
    client.send({"type": "subscribe", "rate": 1000, "id": 7})
    assert client.until(lambda m: m["type"] == "reply" and m["id"] == 7)["ok"] is False
    client.ws.send("[1, 2]")
    assert client.until(lambda m: m["type"] == "reply" and m["id"] is None)["ok"] is False
    assert client.command("status")["ok"] is True
    client.frame_after()


def test_forces_are_released_when_the_forcing_client_disconnects(live_demo: LiveServer, client_for: Any) -> None:
    forcing, watching = client_for(live_demo), client_for(live_demo)
    forcing.frame_after()
    kick = next(b["id"] for b in forcing.program()["behaviors"] if b["name"] == "kick")
    assert forcing.command("force_behavior", robot=0, behavior="kick", params={"strength": 0.5})["ok"]
    assert forcing.command("override_input", robot=1, symbol="ball.seen", value=True)["ok"]
    watching.wait_frame(lambda f: f["robots"][0]["path"][0][:3] == [1, 0, kick])
    forcing.ws.close()
    frame = watching.wait_frame(lambda f: f["robots"][0]["path"][0][0] == 0, timeout=10)
    assert "forced" not in frame["robots"][0]
    watching.wait_frame(lambda f: "overrides" not in f["robots"][1])


def test_a_force_taken_over_by_another_client_survives_the_first_ones_disconnect(
    live_demo: LiveServer, client_for: Any
) -> None:
    first, second = client_for(live_demo), client_for(live_demo)
    assert first.command("force_option", robot=0, option="search_ball")["ok"]
    assert second.command("force_option", robot=0, option="approach_ball")["ok"]
    first.ws.close()
    approach = second.option_id("approach_ball")
    second.wait_frame(lambda f: f["robots"][0]["path"][0][2] == approach)
    time.sleep(0.3)
    frame = second.frame_after()
    assert frame["robots"][0]["forced"] == [0, approach]


# -- behavior files and hot reload ---------------------------------------------------------------------


PLAY_WITH_SPIN = """/** Root option, edited by a test: spins while the game runs. */
option play {
  common decision {
    if (game.state != playing) goto wait;
    else if (game.state == playing) goto spin;
  }
  initial state wait {
    decision {
      else if (ball.seen) goto chase;
      else goto search;
    }
    action {
      activity = waiting;
      stand();
    }
  }
  state chase {
    decision {
      else stay;
    }
    action {
      approach_ball(stop_at = kick_distance);
    }
  }
  state search {
    decision {
      else stay;
    }
    action {
      search_ball();
    }
  }
  state spin {
    decision {
      else stay;
    }
    action {
      activity = searching;
      turn(rate = 90);
    }
  }
}
"""


def test_broken_file_is_saved_with_422_and_the_old_behavior_keeps_running(
    live_demo: LiveServer, client_for: Any, demo_dir: Path
) -> None:
    client = client_for(live_demo)
    client.frame_after()
    generation = client.hello["generation"]  # type: ignore[index]
    with httpx.Client(base_url=live_demo.url) as http:
        current = http.get("/api/files/options/play.xabsl").json()
        broken = current["text"].replace("goto search;", "goto serch;", 1)
        response = http.put(
            "/api/files/options/play.xabsl", json={"text": broken}, headers={"If-Match": f'"{current["version"]}"'}
        )
        assert response.status_code == 422, response.text
        body = response.json()
        assert body["saved"] is True and body["ok"] is False and body["reloaded"] == []
        errors = [d for d in body["diagnostics"] if d["severity"] == "error"]
        assert errors and errors[0]["file"] == "options/play.xabsl" and "serch" in errors[0]["message"]
        assert errors[0]["span"]["start"] < errors[0]["span"]["end"]
        assert (demo_dir / "options" / "play.xabsl").read_text() == broken, "the user's text is saved"
        # The old behavior still runs: after the compile event, frames flow in the same generation.
        event = client.until(lambda m: m.get("event") == "compile")
        assert event["ok"] is False and event["program"] == "demo"
        seq = client.frame_after()["seq"]
        frame = client.wait_frame(lambda f: f["seq"] > seq + 20)
        assert frame["gen"] == generation and _names(client, 0)[0] == "play"
        file_event = (
            client.until(lambda m: m.get("event") == "file")
            if not any(m.get("event") == "file" for m in client.other)
            else None
        )
        assert file_event is None or file_event["path"] == "options/play.xabsl"
        status = http.get("/api/status").json()
        assert status["programs"]["demo"]["ok"] is False and status["programs"]["demo"]["running"] is True


def test_good_edit_sends_hello_and_the_new_state_shows(live_demo: LiveServer, client_for: Any) -> None:
    client = client_for(live_demo)
    client.wait_frame(lambda f: f["t"] > 600)
    with httpx.Client(base_url=live_demo.url) as http:
        version = http.get("/api/files/options/play.xabsl").headers["etag"]
        response = http.put(
            "/api/files/options/play.xabsl", json={"text": PLAY_WITH_SPIN}, headers={"If-Match": version}
        )
        assert response.status_code == 200, response.text
        assert response.json()["reloaded"] == ["demo"]
    hello = client.wait_hello("reload")
    play = next(o for o in hello["structure"]["programs"]["demo"]["options"] if o["name"] == "play")
    spin = next(s["id"] for s in play["states"] if s["name"] == "spin")
    frame = client.wait_frame(lambda f: f["robots"][0]["path"][0][3] == spin)
    assert frame["full"] is True or client.frames > 1
    assert _names(client, 0)[:2] == ["play", "turn"]


def test_conflicting_write_gets_409(live_demo: LiveServer) -> None:
    with httpx.Client(base_url=live_demo.url) as http:
        old = http.get("/api/files/options/search_ball.xabsl").json()
        first = http.put(
            "/api/files/options/search_ball.xabsl", json={"text": old["text"] + "\n", "version": old["version"]}
        )
        assert first.status_code == 200
        second = http.put(
            "/api/files/options/search_ball.xabsl",
            json={"text": old["text"] + "// mine\n"},
            headers={"If-Match": old["version"]},
        )
        assert second.status_code == 409
        assert second.json()["version"] == first.json()["version"]
        assert http.put("/api/files/options/search_ball.xabsl", json={"text": "x"}).status_code == 428


# -- security ---------------------------------------------------------------------------------------------


def test_token_is_required_off_loopback(demo_session: Session, client_for: Any) -> None:
    from xabsl_studio.server.api.security import SecurityPolicy

    policy = SecurityPolicy.for_host("0.0.0.0", None)
    assert policy.token and not policy.loopback
    with LiveServer(demo_session, policy) as server, httpx.Client(base_url=server.url) as http:
        assert http.get("/api/status").status_code == 401
        assert http.put("/api/files/options/play.xabsl", json={"text": "x"}).status_code == 401
        assert http.get("/api/status", headers={"Authorization": f"Bearer {policy.token}"}).status_code == 200
        assert http.get(f"/api/status?token={policy.token}").status_code == 200
        assert http.get("/api/openapi.json").status_code == 200
        from websockets.exceptions import InvalidStatus

        with pytest.raises(InvalidStatus) as refused:
            client_for(server)
        assert refused.value.response.status_code == 403
        with pytest.raises(InvalidStatus):
            client_for(server, "?token=wrong")
        client = client_for(server, f"?token={policy.token}")
        assert client.until(lambda m: m["type"] == "hello")["session"]["token_required"] is True
        header_client = client_for(server, additional_headers={"X-Xabsl-Token": policy.token})
        header_client.until(lambda m: m["type"] == "hello")


def test_websocket_origin_is_checked(live_demo: LiveServer, client_for: Any) -> None:
    from websockets.exceptions import InvalidStatus

    with pytest.raises(InvalidStatus) as refused:
        client_for(live_demo, origin="http://evil.example")
    assert refused.value.response.status_code == 403
    same = client_for(live_demo, origin=f"http://127.0.0.1:{live_demo.port}")
    same.until(lambda m: m["type"] == "hello")
    with pytest.raises(InvalidStatus):
        client_for(live_demo, origin=f"http://127.0.0.1:{live_demo.port + 1}")


def test_oversized_and_binary_messages_close_the_connection(live_demo: LiveServer, client_for: Any) -> None:
    from websockets.exceptions import ConnectionClosed

    client = client_for(live_demo)
    client.frame_after()
    client.ws.send("x" * (70 * 1024))
    with pytest.raises(ConnectionClosed) as closed:
        while True:
            client.receive(timeout=10)
    assert closed.value.rcvd is not None and closed.value.rcvd.code == 1009
    binary = client_for(live_demo)
    binary.frame_after()
    binary.ws.send(b"\x00\x01")
    with pytest.raises(ConnectionClosed) as closed:
        while True:
            binary.receive(timeout=10)
    assert closed.value.rcvd is not None and closed.value.rcvd.code == 1003
    # The server is fine: a new client gets a hello.
    client_for(live_demo).until(lambda m: m["type"] == "hello")


def _rss_mb() -> float:
    with open("/proc/self/statm") as handle:
        pages = int(handle.read().split()[1])
    import os

    return pages * os.sysconf("SC_PAGE_SIZE") / 1e6


def test_a_client_that_never_reads_does_not_slow_the_simulation_or_grow_memory(
    live_demo: LiveServer, client_for: Any
) -> None:
    import socket as socket_module

    from websockets.sync.client import connect

    session = live_demo.session
    # A real websocket whose socket buffers are tiny and which never reads a byte after the handshake.
    raw = socket_module.socket()
    raw.setsockopt(socket_module.SOL_SOCKET, socket_module.SO_RCVBUF, 4096)
    raw.connect(("127.0.0.1", live_demo.port))
    with connect(live_demo.ws_url, sock=raw, max_size=None) as stuck:
        stuck.send(orjson.dumps({"type": "subscribe", "rate": 60}).decode())
        hub = live_demo.studio.hub
        time.sleep(1.0)
        stuck_client = next(c for c in hub.clients.values() if c.frames_sent > 0)
        rss0 = _rss_mb()
        seq0, t0 = session.ring.latest.seq, time.monotonic()
        sent0 = stuck_client.frames_sent
        for _ in range(20):  # requests it never reads the replies of
            stuck.send(orjson.dumps({"type": "command", "id": 1, "op": "status"}).decode())
        time.sleep(3.0)
        seq1, t1 = session.ring.latest.seq, time.monotonic()
        rate = (seq1 - seq0) / (t1 - t0)
        expected = session.behavior_hz * session.speed
        print(
            f"ticks/s {rate:.1f} of {expected}, frames sent to the stuck client {stuck_client.frames_sent}, "
            f"pending {len(stuck_client.control)}, rss +{_rss_mb() - rss0:.1f} MB"
        )
        assert rate > 0.8 * expected, "the stuck client slowed the simulation"
        assert stuck_client.frames_sent - sent0 < 0.5 * (seq1 - seq0), "frames are not being skipped"
        assert len(stuck_client.control) <= 20
        assert _rss_mb() - rss0 < 40
        # Other clients are served normally meanwhile.
        other = client_for(live_demo)
        other.frame_after()
        other.frame_after()


def test_rapid_connect_and_disconnect_logs_no_send_after_close(
    live_demo: LiveServer, client_for: Any, caplog: pytest.LogCaptureFixture
) -> None:
    """Issue 18 item 7: a peer gone before its hello was sent logged ``RuntimeError: Unexpected ASGI
    message 'websocket.send', after sending 'websocket.close'`` (the sender task sent on a closed socket)."""
    import base64
    import os
    import socket
    import struct

    caplog.set_level(logging.DEBUG, logger="xabsl.server")
    request = (
        "GET /ws HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        "Sec-WebSocket-Key: %s\r\nSec-WebSocket-Version: 13\r\n\r\n"
    )
    for i in range(150):
        with socket.create_connection(("127.0.0.1", live_demo.port)) as s:
            key = base64.b64encode(os.urandom(16)).decode()
            s.sendall((request % (live_demo.port, key)).encode())
            if i % 2:
                s.recv(256)
                # A frame a client must not send (unmasked): uvicorn answers with a close of its
                # own, and every send of ours after it used to raise.
                s.sendall(b"\x81\x05hello")
                time.sleep(0.02)
            # An abortive close (RST): the server finds out while it sends the hello and frames.
            s.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    time.sleep(1.0)
    client = client_for(live_demo)
    client.frame_after()
    assert client.command("status")["ok"]
    problems = [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]
    assert not [p for p in problems if "Unexpected ASGI message" in p or "RuntimeError" in p], problems[:3]
    deadline = time.monotonic() + 10
    while len(live_demo.studio.hub.clients) > 1 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert len(live_demo.studio.hub.clients) == 1, "every aborted connection was cleaned up"
