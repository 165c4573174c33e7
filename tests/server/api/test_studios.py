"""Recordings opened from the studio (``/replay/ID/``) and "Run from here" forks (``/fork/ID/``).

The live studio lists its record folder and opens a recording as a replay served by the same
server, confined to that folder; a replay of a deterministic recording starts a live session
from any tick whose first ticks are the recording's.
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any

import httpx
import orjson
import pytest
from websockets.sync.client import connect

from tests.server.conftest import LiveServer, WsClient
from xabsl_studio.engine.cli import main
from xabsl_studio.engine.record import Recording
from xabsl_studio.server.api.library import RecordingLibrary
from xabsl_studio.server.api.security import SecurityPolicy
from xabsl_studio.server.session.replay import ReplaySession

ROOT = Path(__file__).resolve().parents[3]
SOCCER = ROOT / "examples" / "soccer"
FORK_AT = 700


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A record folder with two headless 1 v 1 matches (the second 5 s longer) and a stray file."""
    folder = tmp_path_factory.mktemp("recordings")
    for name, seconds in (("first.mcap", "20"), ("second.mcap", "25")):
        assert main(["run", str(SOCCER), "--duration", seconds, "--players", "1", "--record", str(folder / name)]) == 0
        time.sleep(0.02)  # distinct modification times: newest first
    (folder / "notes.txt").write_text("not a recording")
    (folder / "broken.mcap").write_bytes(b"not mcap at all")
    os.utime(folder / "broken.mcap", (1, 1))  # the oldest
    return folder


def _serve(folder: Path, policy: SecurityPolicy | None = None, limit: int = 4) -> LiveServer:
    """A replay of ``first.mcap`` as the main studio, listing ``folder`` (replays open beside it)."""
    server = LiveServer(ReplaySession(folder / "first.mcap"), policy)
    studio = server.studio
    studio.library = RecordingLibrary(folder)
    studio.studios.limits = {"replay": limit, "fork": 1}
    return server


def test_the_studio_lists_its_recordings_newest_first(folder: Path) -> None:
    with _serve(folder) as server:
        listed = httpx.get(f"{server.url}/api/recordings").json()
        assert listed["folder"] == str(folder.resolve())
        names = [r["name"] for r in listed["recordings"]]
        assert names == ["second.mcap", "first.mcap", "broken.mcap"]
        second = listed["recordings"][0]
        with Recording(folder / "second.mcap") as recording:
            assert second["ticks"] == len(recording) and second["seconds"] == len(recording) / 40
        assert second["size"] == (folder / "second.mcap").stat().st_size
        assert second["example"] == "soccer" and second["deterministic"] is True and second["agents"] == 2
        assert "not an MCAP" in listed["recordings"][2]["error"] or listed["recordings"][2]["error"]
        assert listed["open"] == []


def test_a_recording_opens_as_a_replay_under_its_own_prefix(folder: Path) -> None:
    with _serve(folder) as server:
        opened = httpx.post(f"{server.url}/api/recordings/open", json={"name": "second.mcap"}).json()
        assert opened["kind"] == "replay" and opened["url"] == f"/replay/{opened['id']}/"
        again = httpx.post(f"{server.url}/api/recordings/open", json={"name": "second.mcap"}).json()
        assert again["id"] == opened["id"]  # the same file: the same replay
        base = server.url + opened["url"]
        status = httpx.get(base + "api/status").json()
        with Recording(folder / "second.mcap") as recording:
            assert status["replay"]["ticks"] == len(recording)
        assert status["replay"]["file"].endswith("second.mcap")
        inner = httpx.get(base + "api/recordings").json()  # its Recordings dialog lists the same folder
        assert inner["folder"] == str(folder.resolve()) and inner["open"][0]["id"] == opened["id"]
        assert httpx.get(server.url + f"/replay/{opened['id']}", follow_redirects=False).status_code == 307
        # Its websocket is the replay's; the main one stays the main studio's.
        with connect(server.ws_url.replace("/ws", opened["url"] + "ws")) as ws:
            client = WsClient(ws)
            client.frame_after()
            reply = client.command("seek", seq=900)
            assert reply["ok"] and reply["result"]["ticks"] == status["replay"]["ticks"]
        main_status = httpx.get(server.url + "/api/status").json()
        assert main_status["replay"]["file"].endswith("first.mcap")
        listed = httpx.get(f"{server.url}/api/recordings").json()["open"]
        assert [(o["id"], o["file"]) for o in listed] == [(opened["id"], "second.mcap")]
        assert httpx.delete(f"{server.url}/api/recordings/open/{opened['id']}").json() == {"closed": opened["id"]}
        gone = httpx.get(base + "api/status")
        assert gone.status_code == 404 and "no replay" in gone.json()["detail"]
        assert httpx.delete(f"{server.url}/api/recordings/open/{opened['id']}").status_code == 404


@pytest.mark.parametrize(
    "name",
    [
        "../first.mcap",
        "sub/first.mcap",
        "/etc/passwd",
        "..mcap",
        "notes.txt",
        "missing.mcap",
        "outside.mcap",  # a link in the folder to a file outside it
        ".hidden.mcap",
        "first.mcap\x00",
    ],
)
def test_only_files_of_the_record_folder_open(folder: Path, tmp_path: Path, name: str) -> None:
    outside = tmp_path / "elsewhere.mcap"
    outside.write_bytes((folder / "first.mcap").read_bytes())
    link = folder / "outside.mcap"
    link.unlink(missing_ok=True)
    link.symlink_to(outside)
    try:
        with _serve(folder) as server:
            answer = httpx.post(f"{server.url}/api/recordings/open", json={"name": name})
            assert answer.status_code in (404, 422), answer.text
            assert "detail" in answer.json()
            assert httpx.get(f"{server.url}/api/recordings").json()["open"] == []
            assert "outside.mcap" not in [
                r["name"] for r in httpx.get(f"{server.url}/api/recordings").json()["recordings"]
            ]
    finally:
        link.unlink()


def test_a_broken_recording_is_a_422(folder: Path) -> None:
    with _serve(folder) as server:
        answer = httpx.post(f"{server.url}/api/recordings/open", json={"name": "broken.mcap"})
        assert answer.status_code == 422 and "MCAP" in answer.json()["detail"]


def test_replays_are_bounded_and_behind_the_same_token(folder: Path) -> None:
    token = "t" * 30
    auth = {"Authorization": f"Bearer {token}"}
    with _serve(folder, SecurityPolicy(token=token), limit=1) as server:
        assert httpx.get(f"{server.url}/api/recordings").status_code == 401
        first = httpx.post(f"{server.url}/api/recordings/open", json={"name": "first.mcap"}, headers=auth).json()
        assert httpx.get(f"{server.url}{first['url']}api/status").status_code == 401  # the replay's own check
        assert httpx.get(f"{server.url}{first['url']}api/status", headers=auth).status_code == 200
        refused = httpx.post(
            f"{server.url}{first['url']}api/command",
            json={"op": "pause"},
            headers={**auth, "Origin": "http://evil.test"},
        )
        assert refused.status_code == 403
        # The limit: an idle replay makes room for a new one ...
        second = httpx.post(f"{server.url}/api/recordings/open", json={"name": "second.mcap"}, headers=auth).json()
        assert second["id"] != first["id"]
        assert httpx.get(f"{server.url}{first['url']}api/status", headers=auth).status_code == 404
        # ... one with a page on it does not.
        url = server.ws_url.replace("/ws", second["url"] + "ws") + f"?token={token}"
        with connect(url) as ws:
            WsClient(ws).frame_after()
            full = httpx.post(f"{server.url}/api/recordings/open", json={"name": "first.mcap"}, headers=auth)
            assert full.status_code == 409 and "close one first" in full.json()["detail"]


def _names(recording: Recording, name: str, path: list[list[Any]], seq: int) -> list[tuple[Any, ...]]:
    options = recording.tick(seq).agents[name].program.description["options"]
    return [(options[n[2]]["name"], options[n[2]]["states"][n[3]]["name"], n[4], n[5], n[7]) for n in path if n[0] == 0]


def test_run_from_here_starts_a_live_session_that_continues_the_recording(folder: Path) -> None:
    with _serve(folder) as server:
        opened = httpx.post(f"{server.url}/api/recordings/open", json={"name": "second.mcap"}).json()
        forked = httpx.post(f"{server.url}{opened['url']}api/fork", json={"seq": FORK_AT}, timeout=90).json()
        assert forked["kind"] == "fork" and forked["url"] == f"/fork/{forked['id']}/" and forked["seq"] == FORK_AT
        base = server.url + forked["url"]
        deadline = time.monotonic() + 30
        while httpx.get(base + "api/status").json()["seq"] < FORK_AT + 40 and time.monotonic() < deadline:
            time.sleep(0.2)
        httpx.post(base + "api/command", json={"op": "pause"})
        lines = [orjson.loads(line) for line in httpx.get(base + "api/log").text.splitlines()]
        assert lines[0]["seq"] == FORK_AT - 1  # the fork's timeline starts at the fork tick
        # Seqs continue the recording's (a sample the pipe dropped under load is a tick the ring lacks).
        first_ticks = [line for line in lines if line["seq"] <= FORK_AT + 40]
        seqs = [line["seq"] for line in first_ticks]
        assert seqs == sorted(set(seqs)) and set(seqs) <= set(range(FORK_AT - 1, FORK_AT + 41)) and len(seqs) > 30
        with Recording(folder / "second.mcap") as recording:
            for line in first_ticks:
                view = recording.tick(line["seq"])
                assert line["t"] == view.t
                for robot in line["robots"]:
                    recorded = view.agents[robot["name"]]
                    shown = [
                        (n["option"], n["state"], n["option_time"], n["state_time"], n["leaf"])
                        for n in robot["path"]
                        if "option" in n
                    ]
                    assert shown == _names(recording, robot["name"], recorded.path, line["seq"]), (
                        line["seq"],
                        robot["name"],
                    )
                    for symbol, value in robot["inputs"].items():
                        if isinstance(value, float) and symbol in recorded.inputs:
                            assert value == round(float(recorded.inputs[symbol]) * 1000) / 1000, (line["seq"], symbol)
        # One fork at a time here (the limit is 1, and this one has no page: it makes room).
        bad = httpx.post(f"{server.url}{opened['url']}api/fork", json={"seq": 10**9})
        assert bad.status_code == 422 and "outside the recording" in bad.json()["detail"]


def test_run_from_here_refuses_a_live_recording(tmp_path: Path) -> None:
    from xabsl_studio.engine.host import BehaviorLoop
    from xabsl_studio.engine.record import Recorder
    from xabsl_studio.examples.soccer.run import build_world

    path = tmp_path / "live.mcap"
    world = build_world(3, players=1)
    recorder = Recorder.for_world(
        path, world, lambda a: ("behavior", "chase")[a.team_index], example="soccer", behavior_hz=40, physics_hz=120,
        deterministic=False,
    )  # fmt: skip
    loop = BehaviorLoop(world)
    for _ in range(20):
        now = loop.now_ms
        loop.tick()
        recorder.tick(now)
    recorder.close()
    with LiveServer(ReplaySession(path)) as server:
        answer = httpx.post(f"{server.url}/api/fork", json={"seq": 5})
        assert answer.status_code == 422 and "not a recording of a deterministic run" in answer.json()["detail"]


def test_a_live_studio_opens_its_recordings_and_forks_run_its_edited_behavior(folder: Path, soccer_dir: Path) -> None:
    from xabsl_studio.engine.worlds.loader import load_example
    from xabsl_studio.server.session.live import Session

    ball = soccer_dir / "chase" / "chase_ball.xabsl"
    text = ball.read_text()
    assert "go_to_ball(distance = 250" in text
    ball.write_text(text.replace("go_to_ball(distance = 250", "go_to_ball(distance = 400"))
    session = Session(load_example(soccer_dir, "soccer", robots=1), seed=1)
    session.paused = True
    server = LiveServer(session)
    server.studio.library = RecordingLibrary(folder)
    with server:
        assert httpx.post(f"{server.url}/api/fork", json={"seq": FORK_AT}).status_code == 409  # live: nothing to fork
        assert [r["name"] for r in httpx.get(f"{server.url}/api/recordings").json()["recordings"]][:2] == [
            "second.mcap",
            "first.mcap",
        ]
        opened = httpx.post(f"{server.url}/api/recordings/open", json={"name": "second.mcap"}).json()
        forked = httpx.post(f"{server.url}{opened['url']}api/fork", json={"seq": FORK_AT}, timeout=90).json()
        base = server.url + forked["url"]
        deadline = time.monotonic() + 30
        while httpx.get(base + "api/status").json()["seq"] < FORK_AT + 5 and time.monotonic() < deadline:
            time.sleep(0.1)
        lines = [orjson.loads(line) for line in httpx.get(base + "api/log").text.splitlines()]
        with Recording(folder / "second.mcap") as recording:
            # The tick before the fork is the recorded one: options, states and times (the edited
            # behavior has not decided or called anything yet: no leaves, no parameters) ...
            before = lines[0]
            red = next(r for r in before["robots"] if r["name"] == "red1")
            shown = [(n["option"], n["state"], n["option_time"], n["state_time"]) for n in red["path"] if "option" in n]
            recorded_path = recording.tick(FORK_AT - 1).agents["red1"].path
            assert shown == [n[:4] for n in _names(recording, "red1", recorded_path, FORK_AT - 1)]
            # ... and from the fork tick on the chase runs to the ball with the edited distance.
            for line in lines[1:6]:
                red = next(r for r in line["robots"] if r["name"] == "red1")
                recorded = recording.tick(line["seq"]).agents["red1"]
                behaviors = recorded.program.description["behaviors"]
                shown_calls = [(n["behavior"], n["params"][0]) for n in red["path"] if "behavior" in n]
                wanted = [(behaviors[n[2]]["name"], n[4][0]) for n in recorded.path if n[0] == 1]
                assert wanted == [("go_to_ball", 250.0)] and shown_calls == [("go_to_ball", 400.0)], line["seq"]
        assert lines[1]["seq"] == FORK_AT


def test_a_forks_recording_replays_from_its_fork_tick(folder: Path, tmp_path: Path) -> None:
    """``xabsl run --fork --record``'s file opens like any recording: its ticks are the original's seqs."""
    out = tmp_path / "fork.mcap"
    code = main(["run", str(SOCCER), "--fork", str(folder / "second.mcap"), "--at", "720", "--duration", "3"])
    assert code == 0
    assert (
        main(
            [
                "run",
                str(SOCCER),
                "--fork",
                str(folder / "second.mcap"),
                "--at",
                "720",
                "--duration",
                "3",
                "--record",
                str(out),
            ]
        )
        == 0
    )
    with LiveServer(ReplaySession(out)) as server, connect(server.ws_url) as ws:
        client = WsClient(ws)
        assert client.frame_after()["seq"] == 720
        status = client.command("status")["result"]["replay"]
        assert (status["first"], status["ticks"], status["position"]) == (720, 120, 720)
        assert status["header"]["forked_from"] == {"file": "second.mcap", "seq": 720}
        with Recording(folder / "second.mcap") as original:
            for seq in (839, 721, 760):
                assert client.command("seek", seq=seq)["ok"]
                frame = client.wait_frame(lambda f, seq=seq: f["seq"] == seq)
                assert frame["t"] == original.tick(seq).t and frame["scene"] == original.tick(seq).scene
        refused = client.command("seek", seq=719)
        assert not refused["ok"] and "outside the recording (720..839)" in refused["error"]
        answer = httpx.post(f"{server.url}/api/fork", json={"seq": 800})
        assert answer.status_code == 422 and "itself a fork" in answer.json()["detail"]


def test_a_fork_that_does_not_reach_the_recorded_state_is_a_422(tmp_path: Path) -> None:
    """A recording whose world options lie: the simulation cannot re-simulate it and says why."""
    from xabsl_studio.engine.host import BehaviorLoop
    from xabsl_studio.engine.record import Recorder
    from xabsl_studio.examples.soccer.run import build_world

    path = tmp_path / "lying.mcap"
    world = build_world(3, players=1, half_duration_s=600.0)
    recorder = Recorder.for_world(
        path, world, lambda a: ("behavior", "chase")[a.team_index], example="soccer", behavior_hz=40, physics_hz=120,
        world_options={"robots": 2, "half_duration_s": 600.0},
    )  # fmt: skip
    loop = BehaviorLoop(world)
    for _ in range(60):
        now = loop.now_ms
        loop.tick()
        recorder.tick(now)
    recorder.close()
    with LiveServer(ReplaySession(path)) as server:
        answer = httpx.post(f"{server.url}/api/fork", json={"seq": 50}, timeout=90)
        assert answer.status_code == 422, answer.text
        detail = answer.json()["detail"]
        assert detail.startswith("the fork did not start: RecordingError: the rebuilt world has other agents"), detail
        assert httpx.get(f"{server.url}/api/recordings").json()["open"] == []
