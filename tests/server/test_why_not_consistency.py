"""Why not never contradicts the decision taken: live, past ticks of the ring, replays (issue 28).

For soccer matches and every option that decided on a robot's path, "why not" is asked for every
state the decided-in state's decision can go to. Each route to a state not gone to must be blocked
exactly where it leaves the path taken, by the condition the decision evaluated there, with the
value "why" shows for it; the conditions before that point hold as "why" says; the route of the
leaf taken is blocked nowhere, and ``went`` says whether the decision went to the asked state.
"""

from __future__ import annotations

import contextlib
import gc
import random
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import orjson
import pytest

from tests.server.conftest import LiveServer
from tests.server.test_why_consistency import ID, decided, paths_at
from xabsl_studio.engine.host import DEFAULT_BEHAVIOR_HZ, DEFAULT_PHYSICS_HZ, run_headless
from xabsl_studio.engine.record import Recorder, Recording
from xabsl_studio.examples.soccer.run import build_world, load_team
from xabsl_studio.examples.soccer.studio import SoccerExample
from xabsl_studio.server.protocol.commands import Explain
from xabsl_studio.server.session.live import Session
from xabsl_studio.server.session.replay import ReplaySession
from xabsl_studio.server.simulation.worker import Simulation, WorkerConfig


def targets(tree: dict[str, Any]) -> set[str]:
    """Every state a decision tree (the ``explain`` result's) can go to."""
    if "if" in tree:
        return targets(tree["then"]) | targets(tree["else"])
    return {tree["target"]}


def contradictions(why: dict[str, Any], why_not: dict[str, Any], where: str) -> list[str]:
    """What in ``why_not`` disagrees with the decision ``why`` explains (empty: nothing)."""
    found = []
    where = f"{where} why not {why_not['target_name']}"
    if why_not["went"] is not (why_not["target_name"] == why["target_name"]):
        found.append(f"{where}: went={why_not['went']}, the decision went to {why['target_name']}")
    taken = why["conditions"]
    for route in why_not["routes"]:
        conditions, parts = route["conditions"], route["parts_at"]
        if route["leaf"] == why["leaf"]:
            if parts is not None or route["blocked_at"] is not None or not why_not["went"]:
                found.append(f"{where}: the leaf taken is blocked at {route['blocked_at']} (parts at {parts})")
            continue
        if parts is None or route["blocked_at"] != parts:
            found.append(f"{where} leaf {route['leaf']}: blocked at {route['blocked_at']}, parts at {parts}")
            continue
        for mine, theirs in zip(conditions[: parts + 1], taken, strict=False):
            if mine["value"] != theirs["value"] or mine["value"] is None:
                found.append(f"{where} leaf {route['leaf']}: {mine['text']} is {mine['value']}, why: {theirs['value']}")
        if conditions[parts]["branch"] is taken[parts]["branch"]:
            found.append(f"{where} leaf {route['leaf']}: parts where the decision went the same way")
    return found


@pytest.fixture
def soccer3(soccer_dir: Path) -> SoccerExample:
    return SoccerExample(soccer_dir, players_per_team=3, half_duration_s=600)


def test_live_why_not_agrees_with_every_decision(soccer3: SoccerExample) -> None:
    session = Session(soccer3, seed=5)  # compiles the behaviors; its process never starts
    programs = {k: (s.running, s.running_json) for k, s in session.programs.items()}
    sim = Simulation(WorkerConfig(soccer3, seed=5, programs=programs))  # type: ignore[arg-type]
    sim.generation("connect")
    problems: list[str] = []
    routes = 0
    for _ in range(600):
        sample = sim.tick()
        if sample.seq % 3:
            continue
        for robot, path in enumerate(sample.paths):
            for node in decided(orjson.loads(path)):
                why = sim.execute(Explain(op="explain", robot=robot, option=node[ID]))
                for state in sorted(targets(why["tree"])):
                    answer = sim.execute(Explain(op="explain", robot=robot, option=node[ID], why_not=state))
                    assert answer["leaf"] == why["leaf"]
                    routes += len(answer["why_not"]["routes"])
                    problems += contradictions(why, answer["why_not"], f"tick {sample.seq} robot {robot}")
    assert routes > 5000
    assert not problems, f"{len(problems)} contradictions:\n" + "\n".join(problems[:12])
    del sim
    gc.collect()


def test_past_ticks_of_the_ring_over_the_websocket(soccer3: SoccerExample, client_for: Any) -> None:
    session = Session(soccer3, seed=6, speed=20.0, ring_seconds=10.0)
    problems: list[str] = []
    routes = 0
    asked: dict[str, Any] = {}
    try:
        with LiveServer(session) as server:
            client = client_for(server)
            client.frame_after(lambda f: f["t"] > 15_000, timeout=60)
            assert client.command("pause")["ok"]
            entries = session.ring.snapshot()
            first = next(i for i, e in enumerate(entries) if e.full is not None)
            for seq in sorted(random.Random(28).sample([e.seq for e in entries[first:]], 8)):
                for robot, path in enumerate(paths_at(session, seq)):
                    for node in decided(path):
                        why = client.command("explain", robot=robot, option=node[ID], seq=seq)["result"]
                        asked = {"robot": robot, "option": node[ID], "seq": seq}
                        for state in sorted(targets(why["tree"])):
                            reply = client.command("explain", robot=robot, option=node[ID], seq=seq, why_not=state)
                            assert reply["ok"], reply
                            routes += len(reply["result"]["why_not"]["routes"])
                            problems += contradictions(why, reply["result"]["why_not"], f"ring {seq} robot {robot}")
            refused = client.command("explain", **asked, why_not="no_such_state")
            assert not refused["ok"] and "no state no_such_state" in refused["error"]
    finally:
        session.stop()
    assert routes > 100
    assert not problems, f"{len(problems)} contradictions:\n" + "\n".join(problems[:12])


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """A 20 s 3 v 3 match recorded headless (what ``xabsl run --record`` writes)."""
    root = Path(__file__).resolve().parents[2] / "examples" / "soccer"
    world = build_world(7, load_team(root / "behavior"), load_team(root / "chase"), players=3)
    path = tmp_path_factory.mktemp("whynot") / "match.mcap"
    recorder = Recorder.for_world(
        path,
        world,
        lambda agent: ("behavior", "chase")[agent.team_index],  # type: ignore[attr-defined]
        example="soccer",
        behavior_hz=DEFAULT_BEHAVIOR_HZ,
        physics_hz=DEFAULT_PHYSICS_HZ,
    )
    run_headless(world, duration_s=20, on_tick=recorder.on_tick)
    recorder.close()
    del world
    gc.collect()
    yield path


def test_a_replay_says_why_not_from_the_recorded_reads(recorded: Path) -> None:
    session = ReplaySession(recorded)
    problems: list[str] = []
    routes = 0
    with contextlib.ExitStack() as stack, Recording(recorded) as recording:
        stack.callback(session.stop)
        names = [a["name"] for a in recording.header["agents"]]
        for seq in sorted(random.Random(8).sample(range(recording.first + 1, recording.end), 40)):
            view = recording.tick(seq)
            for robot, name in enumerate(names):
                agent = view.agents.get(name)
                for node in decided(agent.path if agent else []):
                    why = session.explain_at(robot, node[ID], seq)
                    for state in sorted(targets(why["tree"])):
                        answer = session.explain_at(robot, node[ID], seq, why_not=state)["why_not"]
                        routes += len(answer["routes"])
                        # the replay shows the conditions as written (the description's texts)
                        assert all(c["text"] for r in answer["routes"] for c in r["conditions"])
                        problems += contradictions(why, answer, f"{recorded.name} {seq} {name}")
    assert routes > 500
    assert not problems, f"{len(problems)} contradictions:\n" + "\n".join(problems[:12])
