"""``/foxglove``: the Foxglove WebSocket protocol against a real uvicorn, met by a client of the spec.

The viewer is ``foxglove_client.py`` beside this file, run as its own process: written from the
protocol's specification with the ``websockets`` library and ``jsonschema``, importing nothing
of the studio. It validates every message payload against the JSON Schema its channel
advertised. The handshake checks (both subprotocol names, the token off loopback, Origin) and the
studio's side of playback use ``websockets`` and ``httpx`` here directly.
"""

from __future__ import annotations

import json
import struct
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest
from mcap.reader import make_reader
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import connect

from tests.server.conftest import LiveServer, WsClient
from xabsl_studio.engine.cli import main as xabsl
from xabsl_studio.engine.record import Recording
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.examples.soccer.studio import SoccerExample
from xabsl_studio.server.api.foxglove import MAX_QUEUED_FRAMES, FoxgloveClient
from xabsl_studio.server.api.security import SecurityPolicy
from xabsl_studio.server.session.live import Session
from xabsl_studio.server.session.replay import ReplaySession

REPO = Path(__file__).resolve().parents[3]
CLIENT = Path(__file__).with_name("foxglove_client.py")
TOKEN = "f" * 32
NEW, OLD = "foxglove.sdk.v1", "foxglove.websocket.v1"
LAYOUT = REPO / "docs" / "foxglove-layout.json"


def viewer(url: str, *args: str) -> dict[str, Any]:
    """Run the spec client against ``url``; its report."""
    done = subprocess.run(
        [sys.executable, str(CLIENT), url, *args], capture_output=True, text=True, timeout=180, cwd=REPO
    )
    assert done.returncode == 0, done.stderr[:3000] + " ... " + done.stderr[-1000:]
    report: dict[str, Any] = json.loads(done.stdout)
    return report


def layout_references() -> tuple[set[str], list[tuple[str, list[str]]]]:
    """The topics the layout file shows, and its message paths as (topic, field names)."""
    layout = json.loads(LAYOUT.read_text())
    topics: set[str] = set()
    paths: list[tuple[str, list[str]]] = []
    for config in layout["configById"].values():
        topics.update(config.get("topics", {}))
        if "topicPath" in config:
            topics.add(config["topicPath"])
        for item in config.get("paths", []):
            topic, _, fields = item["value"].partition(".")  # the studio's topic names hold no dot
            topics.add(topic)
            paths.append((topic, fields.split(".")))
    return topics, paths


def flatten(tree: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested symbol values (``{"ball": {"x": 1}}``) -> XABSL names (``ball.x``); ``=`` is the namespace's own."""
    flat: dict[str, Any] = {}
    for key, value in tree.items():
        name = prefix[:-1] if key == "=" else prefix + key
        if isinstance(value, dict):
            flat.update(flatten(value, name + "."))
        else:
            flat[name] = value
    return flat


def options_of(first: dict[str, Any]) -> dict[str, Any]:
    """The behavior description of the first ``/xabsl/program`` message a viewer received."""
    program: dict[str, Any] = first["/xabsl/program"]["payload"]["program"]
    return program


def fox_url(server: LiveServer, prefix: str = "") -> str:
    return server.url.replace("http://", "ws://") + prefix + "/foxglove"


def tick_ns(seq: int, hz: int = 40) -> int:
    """A recording's timestamp of tick ``seq`` (docs/recordings.md "Time"), computed here on its own."""
    return (seq * 1_000_000_000 + hz // 2) // hz


@pytest.fixture
def soccer(soccer_dir: Path) -> Iterator[LiveServer]:
    session = Session(SoccerExample(soccer_dir, players_per_team=1), seed=4, speed=2.0)
    with LiveServer(session) as server:
        yield server
    session.stop()


@pytest.fixture(scope="module")
def match(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A short recorded soccer match (2 s, one player a side)."""
    path = tmp_path_factory.mktemp("foxglove") / "m.mcap"
    soccer = str(REPO / "examples" / "soccer")
    assert xabsl(["run", soccer, "--duration", "2", "--players", "1", "--record", str(path)]) == 0
    return path


@pytest.mark.parametrize("subprotocol", [NEW, OLD])
def test_a_live_session_streams_messages_that_validate_against_their_schemas(
    soccer: LiveServer, subprotocol: str
) -> None:
    report = viewer(
        fox_url(soccer),
        "--subprotocol",
        subprotocol,
        "--messages",
        "8",
        "--wait",
        "/xabsl/agents/",
        "--wait",
        "/foxglove/scene",
        "--wait",
        "/world/scene",
    )
    assert report["subprotocol"] == subprotocol
    info = report["server_info"]
    assert "time" in info["capabilities"] and "services" in info["capabilities"]
    assert "rangedPlayback" not in info["capabilities"] and "dataStartTime" not in info
    assert report["invalid"] == []
    topics = {c["topic"]: c["schemaName"] for c in report["channels"]}
    robots = [r["name"] for r in soccer.studio.session.generation.structure["robots"]]
    for name in robots:
        assert topics[f"/xabsl/agents/{name}"] == "xabsl.AgentTick"
        assert report["counts"][f"/xabsl/agents/{name}"] >= 8
    assert topics["/foxglove/scene"] == topics["/foxglove/field"] == "foxglove.SceneUpdate"
    # what is not sent every tick reaches a subscriber at once: the programs, the scene's field
    first = report["first_messages"]
    assert first["/xabsl/program"]["payload"]["program"]["options"]
    assert first["/foxglove/field"]["payload"]["entities"]
    tick = first[f"/xabsl/agents/{robots[0]}"]
    payload = tick["payload"]
    assert tick["time"] == tick_ns(payload["seq"]), "timestamps are the recording's: seq x the tick period"
    assert payload["key"] is True and payload["path"] and payload["inputs"]
    options = first["/xabsl/program"]["payload"]["program"]["options"]
    assert all(node[2] < len(options) for node in payload["path"] if node[0] == 0)
    assert report["times"] == sorted(report["times"]) and report["times"]
    # the values are the studio's own at that tick (its /api/log, enums there as element indices)
    log = httpx.get(f"{soccer.url}/api/log", params={"t0": payload["t"], "t1": payload["t"]}, timeout=30)
    line = next(json.loads(x) for x in log.text.splitlines() if json.loads(x)["seq"] == payload["seq"])
    studio = next(r for r in line["robots"] if r["name"] == robots[0])
    enums = {e["name"]: e["elements"] for e in options_of(first)["enums"]}
    kinds = {s["name"]: s for s in options_of(first)["inputs"]}
    shown = flatten(payload["inputs"])
    assert set(shown) == set(studio["inputs"]) and shown
    for name, value in studio["inputs"].items():
        kind = kinds[name]
        assert shown[name] == (enums[kind["enum"]][value] if kind["type"] == "enum" else value), name
    # docs/foxglove-layout.json works on the live session: its topics exist, its paths hold values
    shown, paths = layout_references()
    assert shown <= set(topics), shown - set(topics)
    for topic, fields in paths:
        value = first[topic]["payload"]
        for field in fields:
            value = value[field]
        assert isinstance(value, int | float | str), (topic, fields, value)


def test_a_viewer_offering_both_names_gets_the_new_one_and_one_offering_neither_a_400(live_demo: LiveServer) -> None:
    with connect(fox_url(live_demo), subprotocols=[OLD, NEW]) as ws:  # type: ignore[list-item]
        assert ws.subprotocol == NEW
        assert json.loads(ws.recv(timeout=10))["op"] == "serverInfo"
    with pytest.raises(InvalidStatus) as refused, connect(fox_url(live_demo), subprotocols=["other.v1"]):  # type: ignore[list-item]
        pass
    assert refused.value.response.status_code == 400
    assert b"foxglove.sdk.v1" in refused.value.response.body


def test_off_loopback_the_token_and_the_origin_are_checked(demo_dir: Path) -> None:
    session = Session(BenchExample(demo_dir), seed=2, speed=2.0)
    try:
        guarded(session)
    finally:
        session.stop()


def guarded(session: Session) -> None:
    """The checks of :func:`test_off_loopback_the_token_and_the_origin_are_checked` on a served ``session``."""
    with LiveServer(session, SecurityPolicy(token=TOKEN, loopback=False)) as server:
        url = fox_url(server)
        for headers in ({}, {"Authorization": "Bearer " + "x" * 32}):
            with pytest.raises(InvalidStatus) as refused, connect(url, subprotocols=[NEW], additional_headers=headers):  # type: ignore[list-item]
                pass
            assert refused.value.response.status_code == 403
        stranger = {"Authorization": f"Bearer {TOKEN}", "Origin": "http://evil.example"}
        with pytest.raises(InvalidStatus), connect(url, subprotocols=[NEW], additional_headers=stranger):  # type: ignore[list-item]
            pass
        done = subprocess.run(
            [sys.executable, str(CLIENT), url, "--subprotocol", OLD, "--messages", "2"],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert done.returncode != 0 and "403" in done.stderr
        report = viewer(url, "--subprotocol", OLD, "--token", TOKEN, "--messages", "2", "--wait", "/xabsl/agents/")
        assert report["invalid"] == [] and report["counts"]


def test_services_force_and_release_with_the_studios_checks(live_demo: LiveServer) -> None:
    report = viewer(
        fox_url(live_demo),
        "--subprotocol",
        NEW,
        "--topic",
        "/xabsl/program",
        "--topic",
        "/xabsl/events",
        "--wait",
        "/xabsl/program",
        "--messages",
        "1",
        "--call",
        "/xabsl/force_option",
        '{"robot": 0, "option": "search_ball"}',
        "--call",
        "/xabsl/force_option",
        '{"robot": 0, "option": "no_such_option"}',
        "--call",
        "/xabsl/override_input",
        '{"robot": 0, "symbol": "ball.seen", "value": "yes", "extra": 1}',
        "--call",
        "/xabsl/release",
        '{"robot": 0}',
    )
    assert set(report["services"]) >= {"/xabsl/force_option", "/xabsl/release", "/xabsl/override_input"}
    answered = {r["call"]: r for r in report["responses"]}
    failed = {f["callId"]: f["message"] for f in report["failures"]}
    assert answered[7000]["payload"]["ok"] is True and answered[7000]["encoding"] == "json"
    assert "no_such_option" in failed[7001]
    assert "extra" in failed[7002]
    assert answered[7003]["payload"]["ok"] is True
    event = report["first_messages"]["/xabsl/events"]["payload"]  # the call is a session event
    assert event["kind"] == "force" and event["data"]["option"] == "search_ball"
    # the advertised request schemas agree with the server on what is well formed
    assert [c["request_valid"] for c in report["calls"]] == [True, True, False, True]
    assert report["invalid"] == [], "responses and messages validate against their schemas"
    status = httpx.get(f"{live_demo.url}/api/status").json()
    assert status["programs"], "the studio still runs"


def test_the_studios_commands_and_reloads_reach_the_viewer_as_events(live_demo: LiveServer) -> None:
    with connect(fox_url(live_demo), subprotocols=[NEW], max_size=None) as ws:  # type: ignore[list-item]
        channels: dict[str, int] = {}
        while "/xabsl/events" not in channels or "/xabsl/program" not in channels:
            data = ws.recv(timeout=10)
            if isinstance(data, str) and json.loads(data)["op"] == "advertise":
                channels.update({c["topic"]: c["id"] for c in json.loads(data)["channels"]})
        subscriptions = [
            {"id": 1, "channelId": channels["/xabsl/events"]},
            {"id": 2, "channelId": channels["/xabsl/program"]},
        ]
        ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))

        def next_message(subscription: int, predicate: Any) -> dict[str, Any]:
            for _ in range(5000):  # time frames come meanwhile: a bound, not a clock
                data = ws.recv(timeout=20)
                if isinstance(data, bytes) and data[0] == 1 and struct.unpack_from("<I", data, 1)[0] == subscription:
                    payload: dict[str, Any] = json.loads(data[13:])
                    if predicate(payload):
                        return payload
            raise AssertionError(f"no such message on subscription {subscription}")

        started = next_message(2, lambda p: True)
        assert started["reason"] == "start" and started["program"]["options"]
        forced = httpx.post(
            f"{live_demo.url}/api/command", json={"op": "force_option", "robot": 0, "option": "search_ball"}
        )
        assert forced.status_code == 200, forced.text
        event = next_message(1, lambda p: p["kind"] == "force")
        robot = live_demo.studio.session.generation.structure["robots"][0]["name"]
        assert event["agent"] == robot and event["data"]["option"] == "search_ball"
        path = "options/search_ball.xabsl"
        current = httpx.get(f"{live_demo.url}/api/files/{path}").json()
        edited = current["text"].replace("turn(rate = 45)", "turn(rate = 40)")
        saved = httpx.put(f"{live_demo.url}/api/files/{path}", json={"text": edited, "version": current["version"]})
        assert saved.status_code == 200, saved.text
        reloaded = next_message(2, lambda p: p["reason"] == "reload")
        assert reloaded["gen"] > started["gen"] and path in reloaded["changed_files"]
        event = next_message(1, lambda p: p["kind"] == "reload")
        assert event["data"]["gen"] == reloaded["gen"] and path in event["data"]["changed_files"]


def test_a_replay_declares_its_range_and_a_seek_moves_the_studios_timeline(match: Path) -> None:
    session = ReplaySession(match)
    try:
        drive_replay(session, match)
    finally:
        session.stop()


def drive_replay(session: ReplaySession, match: Path) -> None:
    """Foxglove's timeline drives the replay, then the studio's timeline drives Foxglove's."""
    first, end = session.source.first, session.source.end
    target = first + (end - first) // 2
    with LiveServer(session) as server:
        report = viewer(
            fox_url(server),
            "--subprotocol",
            NEW,
            "--topic",
            "/xabsl/agents/",
            "--topic",
            "/world/",
            "--messages",
            "1",
            "--seek-ns",
            str(tick_ns(target) - 3),  # between two ticks: the seek goes to the later one
        )
        info = report["server_info"]
        assert {"rangedPlayback", "playbackControl", "time"} <= set(info["capabilities"])
        assert "services" not in info["capabilities"]
        start, stop = info["dataStartTime"], info["dataEndTime"]
        assert start["sec"] * 10**9 + start["nsec"] == tick_ns(first)
        assert stop["sec"] * 10**9 + stop["nsec"] == tick_ns(end - 1)
        assert report["invalid"] == []
        # the layout's topics are the recording's own (so it works on the file and on the replay)
        with match.open("rb") as stream:
            recorded = {channel.topic for channel in make_reader(stream).get_summary().channels.values()}
        shown, _ = layout_references()
        assert shown <= recorded | {"/xabsl/events"}, shown - recorded
        answer = next(p for p in report["playback"] if p["request_id"] == "seek-1")
        assert answer["did_seek"] and answer["status"] == 1 and answer["time"] == tick_ns(target)
        ticks = [m for m in report["after_seek"] if m["topic"].startswith("/xabsl/agents/")]
        assert ticks and all(m["payload"]["seq"] == target and m["time"] == tick_ns(target) for m in ticks)
        # the values are the recording's at that tick (read back by the recording's own reader)
        with Recording(match) as recording:
            view = recording.tick(target)
            for message in ticks:
                if message["topic"].endswith("/fault"):
                    continue
                recorded = view.agents[message["topic"].rsplit("/", 1)[1]]
                shown = flatten(message["payload"]["inputs"])
                assert shown == {k: v for k, v in recorded.inputs.items() if k in shown}
                assert len(shown) == len(recorded.inputs) and shown
                # the path: the same nodes; parameters are the studio's display values (3 decimals)
                shown_path, recorded_path = message["payload"]["path"], recorded.path
                assert [n[:-1] for n in shown_path] == [n[:-1] for n in recorded_path]
                for node, exact in zip(shown_path, recorded_path, strict=True):
                    assert node[-1] == pytest.approx(exact[-1], abs=0.0005)
        played = next(p for p in report["playback"] if p["request_id"] == "play-1")
        assert played["status"] in (0, 3) and played["speed"] == 2.0
        status = httpx.get(f"{server.url}/api/status").json()
        assert status["replay"]["position"] >= target and status["speed"] == 2.0

        # the other way: the studio's page seeks, the viewer follows
        with connect(fox_url(server), subprotocols=[OLD]) as ws:  # type: ignore[list-item]
            assert json.loads(ws.recv(timeout=10))["op"] == "serverInfo"
            pause = httpx.post(f"{server.url}/api/command", json={"op": "pause"})
            assert pause.status_code == 200
            back = first + 3
            seek = httpx.post(f"{server.url}/api/command", json={"op": "seek", "seq": back})
            assert seek.status_code == 200, seek.text
            seen = []
            while True:
                data = ws.recv(timeout=20)
                if isinstance(data, bytes) and data[0] == 5:
                    status_, current, _speed, did_seek, _n = struct.unpack_from("<BQfBI", data, 1)
                    seen.append((status_, current, did_seek))
                    if current == tick_ns(back):
                        break
            assert seen[-1] == (1, tick_ns(back), 1)


def test_an_oversized_message_closes_with_1009_and_bad_requests_get_a_status(live_demo: LiveServer) -> None:
    with connect(fox_url(live_demo), subprotocols=[NEW]) as ws:  # type: ignore[list-item]
        info = json.loads(ws.recv(timeout=10))
        assert info["op"] == "serverInfo"
        ws.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 1, "channelId": 99999}]}))
        ws.send(b"\x01\x00\x00\x00\x00{}")  # client publishing: not offered
        statuses = []
        while len(statuses) < 2:
            data = ws.recv(timeout=10)
            if isinstance(data, str) and json.loads(data)["op"] == "status":
                statuses.append(json.loads(data))
        assert "no channel 99999" in statuses[0]["message"] and statuses[0]["level"] == 2
        assert "clientPublish" in statuses[1]["message"]
        viewers = httpx.get(f"{live_demo.url}/api/status").json()["foxglove"]
        assert viewers["clients"] == 1 and list(viewers["dropped"].values()) == [0]
        ws.send("x" * (65 * 1024))
        with pytest.raises(ConnectionClosed):
            while True:
                ws.recv(timeout=10)
        assert ws.close_code == 1009


def test_a_viewer_that_stops_reading_loses_its_oldest_frames_and_stops_nothing(live_demo: LiveServer) -> None:
    assert httpx.post(f"{live_demo.url}/api/command", json={"op": "speed", "speed": 20}).status_code == 200
    with connect(fox_url(live_demo), subprotocols=[NEW], max_queue=1) as slow:  # type: ignore[list-item]
        channels: list[int] = []
        while not channels:
            data = slow.recv(timeout=10)
            if isinstance(data, str) and json.loads(data)["op"] == "advertise":
                channels = [c["id"] for c in json.loads(data)["channels"]]
        slow.send(
            json.dumps(
                {"op": "subscribe", "subscriptions": [{"id": i, "channelId": c} for i, c in enumerate(channels)]}
            )
        )
        # from here on the viewer reads nothing: its socket fills, then its queue
        viewers: dict[str, Any] = {}
        for _ in range(600):
            viewers = httpx.get(f"{live_demo.url}/api/status").json()["foxglove"]
            if any(viewers["dropped"].values()):
                break
            time.sleep(0.2)
        assert any(viewers["dropped"].values()), viewers
        assert all(queued <= MAX_QUEUED_FRAMES for queued in viewers["queued"].values())
        before = httpx.get(f"{live_demo.url}/api/status").json()["seq"]
        with connect(live_demo.ws_url) as ws:  # the studio's own page is served as ever
            page = WsClient(ws)
            page.wait_hello("connect")
            frame = page.frame_after(lambda f: f["seq"] > before)
        assert frame["seq"] > before, "the session went on"


def test_a_slow_viewers_queue_drops_its_oldest_frames() -> None:
    client = FoxgloveClient(None, 1, None)  # type: ignore[arg-type]
    for i in range(MAX_QUEUED_FRAMES + 10):
        client.binary(struct.pack("<I", i))
    assert len(client.frames) == MAX_QUEUED_FRAMES and client.dropped == 10
    assert struct.unpack("<I", client.frames[0])[0] == 10, "the oldest went"
