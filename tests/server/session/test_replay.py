"""``xabsl serve --replay``: a headless recording served through the studio's protocol."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from tests.server.conftest import LiveServer
from xabsl_studio.engine.record import Recording
from xabsl_studio.server.session.replay import ReplaySession

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 2 v 2 soccer match of 20 s recorded headless by the command line."""
    path = tmp_path_factory.mktemp("replay") / "match.mcap"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    command = [
        sys.executable,
        "-m",
        "xabsl_studio.engine.cli",
        "run",
        "examples/soccer",
        "--duration",
        "20",
        "--players",
        "2",
    ]
    subprocess.run([*command, "--record", str(path)], cwd=ROOT, env=env, check=True, capture_output=True)
    return path


@pytest.fixture
def replay(recorded: Path) -> Any:
    session = ReplaySession(recorded)
    with LiveServer(session) as server:
        yield server


def _round3(value: Any) -> Any:
    return round(value * 1000) / 1000 if isinstance(value, float) else value


def _expected(client: Any, view: Any, robot: int, name: str) -> dict[str, Any]:
    """The display values the frame must carry for ``name``'s recorded tick, by symbol id."""
    program = client.program(robot)
    enums = {e["name"]: e["elements"] for e in program["enums"]}
    agent = view.agents[name]
    out: dict[str, Any] = {}
    for kind, values in (("inputs", agent.inputs), ("outputs", agent.outputs)):
        for symbol in program[kind]:
            if symbol.get("params") or symbol["name"] not in values:
                continue
            value = values[symbol["name"]]
            if symbol["type"] == "enum":
                value = enums[symbol["enum"]].index(value)
            elif symbol["type"] == "decimal":
                value = round(value * 1000) / 1000
            out[f"{kind}:{symbol['id']}"] = value
    return out


def test_seek_any_tick_gives_the_recorded_tick(replay: LiveServer, client_for: Any, recorded: Path) -> None:
    client = client_for(replay)
    client.frame_after()
    assert client.hello is not None and client.frame is not None
    assert client.frame["seq"] == 0
    with Recording(recorded) as recording:
        names = [r["name"] for r in client.hello["structure"]["robots"]]
        assert names == [a["name"] for a in recording.header["agents"]]
        for seq in (len(recording) - 1, 17, 900, 901, 40, 0, 1234):
            reply = client.command("seek", seq=seq)
            assert reply["ok"], reply
            assert reply["result"] == {"seq": seq, "ticks": len(recording)}
            frame = client.wait_frame(lambda f, seq=seq: f["seq"] == seq)
            view = recording.tick(seq)
            assert frame["t"] == view.t
            assert frame["scene"] == view.scene
            for robot, name in enumerate(names):
                recorded_path = view.agents[name].path
                path = frame["robots"][robot]["path"]
                assert [n[:-1] for n in path] == [n[:-1] for n in recorded_path]  # all but the parameters
                rounded = [[_round3(v) for v in n[-1]] for n in recorded_path]
                assert [n[-1] for n in path] == rounded
                got = {f"{k}:{i}": v for k in ("inputs", "outputs") for i, v in client.values[robot][k].items()}
                assert got == {k: v for k, v in _expected(client, view, robot, name).items()}, (seq, name)


def test_history_covers_the_whole_recording(replay: LiveServer, client_for: Any, recorded: Path) -> None:
    client = client_for(replay)
    client.frame_after()
    with Recording(recorded) as recording:
        count = len(recording)
        first, last = recording.tick(0).t, recording.tick(count - 1).t
    reply = client.command("history", t0=first, t1=last)
    assert reply["ok"], reply
    assert reply["result"]["frames"] == count  # far more than a live ring's window at the start
    seqs: list[int] = []
    while True:
        chunk = client.until(lambda m: m["type"] == "history")
        seqs.extend(f["seq"] for f in chunk["frames"])
        if chunk["last"]:
            break
    assert seqs == list(range(count))


def test_explain_at_a_past_tick_gives_operand_values(replay: LiveServer, client_for: Any, recorded: Path) -> None:
    client = client_for(replay)
    client.frame_after()
    option = client.option_id("approach_ball", robot=1)
    with Recording(recorded) as recording:
        seq = next(
            v.seq
            for v in recording.ticks(200, len(recording))
            if any(n[0] == 0 and n[2] == option and n[7] >= 0 for n in v.agents["blue2"].path)
        )
        distance = recording.tick(seq).agents["blue2"].inputs["ball.distance"]
        recording_t = recording.tick(seq).t
    client.command("seek", seq=len(recording) - 1)  # explain a tick other than the current one
    reply = client.command("explain", robot=1, option="approach_ball", seq=seq)
    assert reply["ok"], reply
    result = reply["result"]
    assert result["seq"] == seq and result["option_name"] == "approach_ball"
    condition = result["conditions"][0]
    assert condition["text"].startswith("ball.distance")
    comparison = condition["comparisons"][0]
    assert comparison["left"] == "ball.distance" and float(comparison["left_value"]) == distance
    assert comparison["shown"] == f"ball.distance ({comparison['left_value']}) < 900"
    assert result["recorded"] and result["t"] == recording_t
    assert comparison["value"] == condition["branch"] == condition["value"]
    tree = result["tree"]  # the decision tree as the live why draws it, the recorded path taken
    assert tree["if"] == condition["text"] and tree["taken"] and tree["branch"] == condition["branch"]
    assert tree["value"] == condition["value"]
    # Over many ticks and options: what the recording lets compute agrees with the recorded leaves.
    computed = 0
    for at in range(300, len(recording), 97):
        for robot in range(4):
            for name in ("play_soccer", "chase_play", "role_selection", "striker", "chase_ball", "approach_ball"):
                reply = client.command("explain", robot=robot, option=name, seq=at)
                if not reply["ok"]:
                    continue  # that option did not run there (or is not in the robot's behavior)
                for condition in reply["result"]["conditions"]:
                    if condition["value"] is not None:
                        computed += 1
                        assert condition["value"] == condition["branch"], (at, robot, name, condition)
    assert computed > 50


def test_commands_needing_a_world_are_refused(replay: LiveServer, client_for: Any) -> None:
    client = client_for(replay)
    client.frame_after()
    reply = client.command("force_option", robot=0, option="play_soccer")
    assert not reply["ok"] and "replay" in reply["error"]
    reply = client.command("seek", seq=10**9)
    assert not reply["ok"] and "outside the recording" in reply["error"]
    assert client.command("step", ticks=3)["result"]["seq"] == 3
    status = client.command("status")["result"]
    assert status["replay"]["position"] == 3 and status["paused"]


def test_the_live_studio_records_its_session(soccer_session: Any, soccer_dir: Path, client_for: Any) -> None:
    from xabsl_studio.server.session.recording import LiveRecorder

    folder = soccer_dir.parent / "recordings"
    session = soccer_session
    session.live_recorder = LiveRecorder(folder, "soccer", session.behavior_hz, session.physics_hz)
    with LiveServer(session) as server:
        client = client_for(server)
        client.frame_after()
        assert client.command("pause")["ok"]
        assert client.command("step", ticks=5)["ok"]
        assert client.command("resume")["ok"]
        option = soccer_dir / "behavior" / "options" / "approach_ball.xabsl"
        option.write_text(option.read_text().replace("ball.distance < 900", "ball.distance < 950"))
        reply = client.command("reload", program="behavior")
        assert reply["ok"], reply
        client.wait_hello("reload")
        seq = client.frame_after()["seq"]
        client.frame_after(lambda f: f["seq"] > seq + 20)
        recording = client.command("status")["result"]["recording"]
        assert recording["ticks"] > 20 and recording["file"].startswith(str(folder))
        print(f"live recording: {recording['ms_per_tick']} ms per tick in the server process (4 agents)")
    session.stop()
    files = sorted(folder.glob("*.mcap"))
    assert len(files) == 1
    with Recording(files[0]) as recording:
        kinds = [e["kind"] for e in recording.events]
        assert kinds[:3] == ["pause", "step", "resume"] and "reload" in kinds
        assert recording.events[1]["data"] == {"ticks": 5}
        reload = next(e for e in recording.events if e["kind"] == "reload")
        assert reload["data"]["changed_files"] == ["behavior/options/approach_ball.xabsl"]
        assert ("behavior", 1) in recording.programs
        new = recording.programs[("behavior", 1)].description
        approach = next(o for o in new["options"] if o["name"] == "approach_ball")
        assert "950" in str(approach["states"])
        last = recording.tick(len(recording) - 1)
        assert set(last.agents) == {"blue1", "blue2", "red1", "red2"}
        assert last.agents["blue1"].gen == 1 and last.agents["red1"].gen == 0
        reloaded = recording.programs[("behavior", 1)].program()  # the new generation, from its IC
        assert reloaded is not None and "950" in " ".join(str(s) for s in reloaded.options["approach_ball"].states)
        assert last.agents["blue1"].option_names()[0] == "play_soccer"
        assert len(recording) > 30
        assert str(last.agents["blue1"].inputs["game.state"]).startswith("game.state.")  # enums by name
        assert isinstance(last.agents["blue1"].inputs["ball.distance"], float)


def _record_steps(session: Any, client_for: Any, folder: Path, cap_bytes: int, steps: int) -> Any:
    """Record ``steps`` steps of 40 ticks of a paused live session into ``folder`` (a file per step)."""
    from xabsl_studio.server.session.recording import LiveRecorder

    recorder = LiveRecorder(folder, "soccer", session.behavior_hz, session.physics_hz, cap_bytes, roll_ticks=40)
    session.live_recorder = recorder
    with LiveServer(session) as server:
        client = client_for(server)
        client.frame_after()
        assert client.command("pause")["ok"]
        for _ in range(steps):
            assert client.command("step", ticks=40)["ok"]
    session.stop()
    return recorder


def test_live_recordings_roll_and_keep_under_the_cap(soccer_session: Any, soccer_dir: Path, client_for: Any) -> None:

    folder = soccer_dir.parent / "rolling"
    recorder = _record_steps(soccer_session, client_for, folder, 200_000, 8)
    assert len(recorder.files) >= 8  # a new file every 40 ticks
    kept = sorted(folder.glob("*.mcap"))
    assert sum(p.stat().st_size for p in kept) <= 200_000 and len(kept) < len(recorder.files)
    assert len(set(recorder.files)) == len(recorder.files)  # no name used twice
    assert kept == sorted(recorder.files[-len(kept) :])  # the newest survive; names sort in time order
    with Recording(kept[-1]) as recording:  # each file opens on its own
        assert len(recording) >= 1 and recording.tick(0).agents


def test_a_replay_draws_the_recorded_generation_from_its_intermediate_code(replay: LiveServer) -> None:
    """Graphs need the program; a recording carries each generation's IC, so a replay draws it."""
    import urllib.request

    def get(path: str) -> tuple[int, str]:
        with urllib.request.urlopen(replay.url + path, timeout=30) as response:
            return response.status, response.read().decode()

    session = replay.session
    assert isinstance(session, ReplaySession)
    view = session.recording.programs[("behavior", 0)]
    assert view.ic is not None and view.ic.startswith("// ")  # the IC of the recorded generation
    program = view.program()
    assert program is not None
    assert [o["name"] for o in view.description["options"]] == list(program.options)
    status, svg = get("/api/graph/behavior")
    assert status == 200 and "<svg" in svg and "play_soccer" in svg
    status, machine = get("/api/graph/behavior/play_soccer")
    assert status == 200 and "<svg" in machine
    for state in view.description["options"][program.options["play_soccer"].index]["states"]:
        assert state["name"] in machine


def test_select_agent_while_recording_is_an_event_with_the_agents_name(
    soccer_session: Any, soccer_dir: Path, client_for: Any
) -> None:
    """Recording is on by default: picking an agent used to fail with a TypeError (issue 23)."""
    from xabsl_studio.server.session.recording import LiveRecorder

    folder = soccer_dir.parent / "select"
    session = soccer_session
    session.live_recorder = LiveRecorder(folder, "soccer", session.behavior_hz, session.physics_hz)
    with LiveServer(session) as server:
        client = client_for(server)
        client.frame_after()
        reply = client.command("select_agent", robot=1, agent="soccer")
        assert reply["ok"], reply
        client.frame_after()
    session.stop()
    (file,) = sorted(folder.glob("*.mcap"))
    with Recording(file) as recording:
        (event,) = [e for e in recording.events if e["kind"] == "select_agent"]
    assert event["agent"] == "blue2" and event["data"] == {"name": "soccer"}  # docs/recordings.md


def test_the_newest_recording_stays_even_alone_over_the_cap(
    soccer_session: Any, soccer_dir: Path, client_for: Any
) -> None:
    """A cap below one file's size deleted the file just written, so nothing was kept at all."""

    folder = soccer_dir.parent / "tiny"
    recorder = _record_steps(soccer_session, client_for, folder, 1_000, 3)
    assert sorted(folder.glob("*.mcap")) == [recorder.files[-1]]
