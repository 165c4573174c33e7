"""``xabsl run examples/soccer --fork REC --at SEQ --record OUT``: a recorded match continued headless.

With the unchanged behavior the continuation's per-agent messages are the original's from SEQ on;
with an edited one they differ from SEQ on; bad forks are one clear line (exit 2).
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import orjson
import pytest
from mcap.reader import make_reader

from tests.record.test_recordings import _validate_all
from xabsl_studio.engine.cli import main
from xabsl_studio.engine.host import BehaviorLoop
from xabsl_studio.engine.record import Recorder, Recording
from xabsl_studio.engine.record import schema as S
from xabsl_studio.examples.soccer.run import build_world

ROOT = Path(__file__).resolve().parents[2]
SOCCER = ROOT / "examples" / "soccer"
FORK_AT = 700  # into PLAYING (pre-game is about 16 s = 640 ticks); not a key frame tick
KEY_AT = 720  # a key frame tick: there the files' messages are byte for byte the same


def _messages(path: Path, first: int) -> dict[str, dict[int, bytes]]:
    """Per agent and scene topic, seq -> the message bytes, from ``first`` on (a plain MCAP reader)."""
    out: dict[str, dict[int, bytes]] = {}
    with path.open("rb") as stream:
        for _schema, channel, message in make_reader(stream).iter_messages():
            if channel.topic.startswith("/xabsl/agents/") or channel.topic == S.WORLD_SCENE:
                seq = orjson.loads(message.data)["seq"]
                if seq >= first:
                    out.setdefault(channel.topic, {})[seq] = message.data
    return out


@pytest.fixture(scope="module")
def original(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("forkcli") / "match.mcap"
    code = main(["run", str(SOCCER), "--duration", "20", "--players", "2", "--record", str(path)])
    assert code == 0
    return path


def _fork(original: Path, out: Path, at: int, *more: str) -> int:
    return main(
        ["run", str(SOCCER), "--fork", str(original), "--at", str(at), "--duration", "8", "--record", str(out), *more]
    )


def test_a_fork_with_the_unchanged_behavior_continues_the_recording_exactly(original: Path, tmp_path: Path) -> None:
    out = tmp_path / "fork.mcap"
    assert _fork(original, out, FORK_AT) == 0
    with Recording(original) as before, Recording(out) as after:
        assert after.header["forked_from"] == {"file": original.name, "seq": FORK_AT}
        assert after.first == FORK_AT and len(after) == 8 * 40 and after.end == FORK_AT + 320
        assert after.header["deterministic"] and after.header["seed"] == before.header["seed"]
        assert after.header["world_options"] == before.header["world_options"] == {"robots": 2, "half_duration_s": 10.0}
        assert after.programs[("chase", 0)].sources == before.programs[("chase", 0)].sources is not None
        compared = 0
        for old, new in zip(before.ticks(FORK_AT, after.end), after.ticks(), strict=True):
            assert (new.seq, new.t, new.scene) == (old.seq, old.t, old.scene)
            for name, agent in new.agents.items():
                was = old.agents[name]
                assert (agent.gen, agent.tick, agent.path, agent.inputs, agent.outputs, agent.fault) == (
                    was.gen,
                    was.tick,
                    was.path,
                    was.inputs,
                    was.outputs,
                    was.fault,
                ), (new.seq, name)
                compared += 1
        assert compared == 4 * 320
    # Both files are valid against their schemas (the new header fields and the program sources too).
    for path in (original, out):
        checked = _validate_all(path)
        assert checked["xabsl.Recording"] == 1 and checked["xabsl.Program"] == 2
    # From a key frame tick on, the messages are the same bytes (same key frames, same deltas).
    keyed = tmp_path / "keyed.mcap"
    assert _fork(original, keyed, KEY_AT) == 0
    old_messages, new_messages = _messages(original, KEY_AT), _messages(keyed, KEY_AT)
    assert sorted(new_messages) == sorted(old_messages) and len(new_messages) == 5
    for topic, by_seq in new_messages.items():
        assert len(by_seq) == 320
        assert all(old_messages[topic][seq] == data for seq, data in by_seq.items()), topic


def test_a_fork_with_an_edited_behavior_differs_from_the_fork_tick_on(original: Path, tmp_path: Path) -> None:
    copy = tmp_path / "soccer"
    for team in ("behavior", "chase"):  # the chase team includes the example team's symbol files
        shutil.copytree(SOCCER / team, copy / team)
    ball = copy / "chase" / "chase_ball.xabsl"
    text = ball.read_text()
    assert "go_to_ball(distance = 250" in text
    ball.write_text(text.replace("go_to_ball(distance = 250", "go_to_ball(distance = 400"))
    out = tmp_path / "edited.mcap"
    assert _fork(original, out, FORK_AT, "--home", str(copy / "behavior"), "--away", str(copy / "chase")) == 0
    with Recording(original) as before, Recording(out) as after:
        reloaded = after.programs[("chase", 0)].sources
        assert reloaded is not None and "go_to_ball(distance = 400" in reloaded["files"]["chase_ball.xabsl"]
        first_difference = None
        for old, new in zip(before.ticks(FORK_AT, after.end), after.ticks(), strict=True):
            paths = {name: agent.path for name, agent in new.agents.items()}
            if paths != {name: agent.path for name, agent in old.agents.items()}:
                first_difference = new.seq
                break
        assert first_difference == FORK_AT
        # The example team was not edited: it runs the recorded behavior (no switch).
        assert after.programs[("behavior", 0)].sources == before.programs[("behavior", 0)].sources


def _recording(path: Path, **options: Any) -> Path:
    world = build_world(3, players=1)
    recorder = Recorder.for_world(
        path,
        world,
        lambda agent: ("behavior", "chase")[agent.team_index],  # type: ignore[attr-defined]
        behavior_hz=40,
        physics_hz=120,
        world_options={"robots": 1, "half_duration_s": 600.0},
        **options,
    )
    loop = BehaviorLoop(world)
    for _ in range(50):
        now = loop.now_ms
        loop.tick()
        recorder.tick(now)
    recorder.close()
    return path


@pytest.mark.parametrize(
    ("case", "message"),
    [
        ("late", "--at 99999 is outside the recording (0.."),
        ("early", "--at -1 is outside the recording"),
        ("live", "not a recording of a deterministic run"),
        ("errands", "is a recording of 'errands', not of soccer"),
        ("fork", "is itself a fork (from tick 720): fork its original"),
        ("lonely", "--fork REC.mcap and --at SEQ go together"),
    ],
)
def test_bad_forks_are_one_clear_line(
    case: str, message: str, original: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path, at = original, "99999" if case == "late" else "-1" if case == "early" else "10"
    if case == "live":
        path = _recording(tmp_path / "live.mcap", example="soccer", deterministic=False)
    elif case == "errands":
        path = _recording(tmp_path / "errands.mcap", example="errands")
    elif case == "fork":
        assert _fork(original, tmp_path / "first.mcap", KEY_AT) == 0
        path, at = tmp_path / "first.mcap", "800"
    args = ["run", str(SOCCER), "--fork", str(path), "--at", at]
    if case == "lonely":
        args = ["run", str(SOCCER), "--at", "10"]
    capsys.readouterr()
    assert main(args) == 2
    err = capsys.readouterr().err
    assert message in err, err
    assert err.count("\n") == 1 and "Traceback" not in err
