"""The profile of a short soccer match against counts made another way: from the rebuilt trees."""

from __future__ import annotations

from collections import Counter
from pathlib import Path
from typing import Any

import pytest

from xabsl_studio.engine.host import BehaviorLoop
from xabsl_studio.engine.profile import profile
from xabsl_studio.engine.record import Recorder, Recording
from xabsl_studio.engine.runtime import OptionNode
from xabsl_studio.examples.soccer.run import DEFAULT_AWAY, DEFAULT_HOME, build_world, load_team

TICKS = 1000  # pre-game (about 16 s at 40 Hz is 640 ticks) and some play


@pytest.fixture(scope="module")
def match(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("soccer") / "match.mcap"
    home, away = load_team(DEFAULT_HOME), load_team(DEFAULT_AWAY)
    world = build_world(3, home, away, players=2)
    loop = BehaviorLoop(world)
    recorder = Recorder(
        path, world, {"behavior": home, "chase": away}, example="soccer", behavior_hz=40, physics_hz=120
    )
    for _ in range(TICKS):
        now = loop.now_ms
        loop.tick()
        recorder.tick(now)
    recorder.close()
    return path


def _walk(nodes: Any, into: list[OptionNode]) -> None:
    for node in nodes:
        if isinstance(node, OptionNode):
            into.append(node)
            _walk(node.sub, into)


def test_counts_match_the_trees(match: Path) -> None:
    with Recording(match) as recording:
        report = profile(recording)
        active: Counter[tuple[str, str]] = Counter()
        states: Counter[tuple[str, str, str]] = Counter()
        activations: Counter[tuple[str, str]] = Counter()
        transitions: Counter[tuple[str, str, str, str, int]] = Counter()
        previous: dict[str, dict[str, OptionNode]] = {}
        for view in recording.ticks():
            for name, agent in view.agents.items():
                nodes: list[OptionNode] = []
                _walk(agent.tree(), nodes)
                now: dict[str, OptionNode] = {}
                for node in nodes:
                    now.setdefault(node.option, node)
                for option, node in now.items():
                    active[(name, option)] += 1
                    states[(name, option, node.state)] += 1
                    before = previous.get(name, {}).get(option)
                    if before is None or node.option_time < before.option_time:
                        activations[(name, option)] += 1
                    if node.leaf >= 0 and node.decided_in != node.state:
                        transitions[(name, option, node.decided_in, node.state, node.leaf)] += 1
                previous[name] = now
    assert len(report["agents"]) == 4
    for name, agent in report["agents"].items():
        for option, entry in agent["options"].items():
            assert entry["active_ticks"] == active[(name, option)], (name, option)
            assert entry["activations"] == activations[(name, option)], (name, option)
            for state, s in entry["states"].items():
                assert s["active_ticks"] == states[(name, option, state)], (name, option, state)
            for t in entry["transitions"]:
                assert t["count"] == transitions[(name, option, t["from"], t["to"], t["leaf"])]
        assert sum(e["active_ticks"] for e in agent["options"].values()) == sum(
            n for (a, _o), n in active.items() if a == name
        )
        assert sum(len(e["transitions"]) for e in agent["options"].values()) == len(
            [k for k in transitions if k[0] == name]
        )
    # the match got past the pre-game: the playing options ran, with role changes
    assert "game_playing" in report["teams"]["behavior"]["options"]
