"""Recordings carry what each decision read (``reads`` of ``xabsl.AgentTick``), exact, for every tick.

A soccer match recorded headless: the ``mcap`` package's own reader (no code of ours) finds a
``reads`` array in every agent message, equal value for value (floats bit for bit) to what the
engine's decisions read in that tick, laid out as docs/recordings.md says (option ids of the
path's decisions, input function calls with one argument per declared parameter); our reader
gives the same.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import jsonschema
import orjson
from mcap.reader import make_reader

from xabsl_studio.engine.host import BehaviorLoop
from xabsl_studio.engine.record import Recorder, Recording
from xabsl_studio.engine.record import schema as S
from xabsl_studio.examples.soccer.run import DEFAULT_AWAY, DEFAULT_HOME, build_world, load_team

#: into the playing phase (pre-game is about 16 s)
TICKS = 1000


def plain(value: Any) -> Any:
    """A read as JSON gives it back: arrays, and null for what JSON cannot hold."""
    if isinstance(value, tuple | list):
        return [plain(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def test_every_agent_tick_carries_the_reads_of_its_decisions(tmp_path: Path) -> None:
    home, away = load_team(DEFAULT_HOME), load_team(DEFAULT_AWAY)
    world = build_world(8, home, away, players=4)
    loop = BehaviorLoop(world)
    path = tmp_path / "match.mcap"
    programs = {"behavior": home, "chase": away}
    recorder = Recorder(path, world, programs, example="soccer", behavior_hz=40, physics_hz=120)
    engines = [a.controller.engine for a in world.agents]  # type: ignore[union-attr]
    assert all(e.record_reads for e in engines), "the recorder's samplers turn the reads on"
    live: list[list[Any]] = []
    for _ in range(TICKS):
        now = loop.now_ms
        loop.tick()
        recorder.tick(now)
        live.append([plain(e.reads()) for e in engines])
    recorder.close()

    names = [a.name for a in world.agents]
    seen = 0
    functions = 0
    with path.open("rb") as stream:
        reader = make_reader(stream)
        summary = reader.get_summary()
        assert summary is not None
        schema = orjson.loads(next(s.data for s in summary.schemas.values() if s.name == "xabsl.AgentTick"))
        validator = jsonschema.Draft202012Validator(schema)
        descriptions = {}
        for _schema, _channel, message in reader.iter_messages(topics=[S.PROGRAM]):
            data = orjson.loads(message.data)
            descriptions[data["key"]] = data["program"]
        for _schema, channel, message in reader.iter_messages(topics=[S.agent_topic(n) for n in names]):
            data = orjson.loads(message.data)
            validator.validate(data)
            name = channel.topic.rsplit("/", 1)[1]
            index = names.index(name)
            assert data["reads"] == live[data["seq"]][index], (data["seq"], name)
            program = descriptions["behavior" if world.agents[index].team_index == 0 else "chase"]  # type: ignore[attr-defined]
            decided = {n[2] for n in data["path"] if n[0] == 0 and n[7] >= 0}
            inputs = {s["id"]: s for s in program["inputs"]}
            for read in data["reads"]:
                if isinstance(read, int):
                    assert read in decided, "a read decision is one of the path's"
                elif isinstance(read[0], int) and read[0] >= 0 and inputs[read[0]].get("params"):
                    assert len(read) == len(inputs[read[0]]["params"]) + 2  # id, one argument per parameter, result
                    functions += 1
            seen += 1
    assert seen == TICKS * len(names)
    assert functions > 1000, "input functions (distance_to, team.rank, ...) were read and recorded"

    with Recording(path) as recording:
        for seq in (0, 17, 444, TICKS - 1):
            view = recording.tick(seq)
            assert [view.agents[n].reads for n in names] == live[seq]
