"""SoccerWorld and the host contract: determinism, scenes, a whole match (examples/soccer/world.py)."""

from __future__ import annotations

import hashlib

import orjson
import pytest

from xabsl_studio.engine.host import Agent, AgentController, World, run_headless
from xabsl_studio.examples.soccer.game import GameRules, GameState
from xabsl_studio.examples.soccer.scripted import plug_scripted_team
from xabsl_studio.examples.soccer.world import SoccerWorld, build_world


def scene_hash_after(seed: int, seconds: float) -> str:
    world = build_world(seed, players_per_team=5, half_duration_s=300)
    plug_scripted_team(world)
    frames = hashlib.sha256()

    def record(now_ms: int) -> None:
        frames.update(orjson.dumps(world.dynamic_scene()))

    run_headless(world, seconds, on_tick=record)
    return frames.hexdigest()


def test_the_world_fulfils_the_host_contract():
    world = build_world(1)
    assert isinstance(world, World)
    plug_scripted_team(world)
    assert all(isinstance(agent, Agent) for agent in world.agents)
    assert all(isinstance(agent.controller, AgentController) for agent in world.agents)


def test_agents_are_named_by_team_and_number():
    world = build_world(1, players_per_team=3)
    assert [a.name for a in world.agents] == ["blue1", "blue2", "blue3", "red1", "red2", "red3"]
    assert [a.team for a in world.agents] == ["blue"] * 3 + ["red"] * 3
    assert [a.number for a in world.agents] == [1, 2, 3] * 2
    assert all(agent.controller is None for agent in world.agents)


@pytest.mark.parametrize("players", [0, 8])
def test_team_size_is_checked(players):
    with pytest.raises(ValueError):
        build_world(1, players_per_team=players)


def test_same_seed_same_match():
    assert scene_hash_after(11, 30.0) == scene_hash_after(11, 30.0)


def test_different_seed_different_match():
    assert scene_hash_after(11, 30.0) != scene_hash_after(12, 30.0)


def test_scenes_and_status_are_plain_json():
    world = build_world(3, players_per_team=7)
    plug_scripted_team(world)
    run_headless(world, 10.0)
    for payload in (world.static_scene(), world.dynamic_scene(), world.status()):
        # orjson without options: only str/int/float/bool/None/list/dict, and it round-trips
        assert orjson.loads(orjson.dumps(payload)) == payload
    dynamic = world.dynamic_scene()
    assert len(dynamic["robots"]) == 14
    assert all(isinstance(v, int) for robot in dynamic["robots"] for v in robot[:2])
    assert dynamic["t"] == 10_000
    static = world.static_scene()
    assert static["units"]["length"] == "mm"
    assert [a["name"] for a in static["agents"]] == [a.name for a in world.agents]


def test_status_reports_time_state_and_score():
    world = build_world(3, players_per_team=2)
    status = world.status()
    assert status["time_ms"] == 0
    assert status["finished"] is False
    assert status["game_state"] == "initial"
    assert status["score"] == [0, 0]
    assert status["teams"] == ["blue", "red"]


def test_a_headless_match_finishes_with_a_valid_score():
    world = build_world(7, players_per_team=5, half_duration_s=45.0)
    plug_scripted_team(world)
    stats = run_headless(world, duration_s=300.0)
    assert world.finished
    assert world.game.state == GameState.FINISHED
    status = world.status()
    assert status["finished"] is True
    assert status["half"] == 2
    assert all(isinstance(goals, int) and goals >= 0 for goals in status["score"])
    assert sum(status["score"]) == len(status["goals"])
    # two halves of play plus the INITIAL/READY/SET pauses, then the run stopped by itself
    assert 90.0 < stats.sim_seconds < 300.0
    # chasing the ball at all moved it: the scripted players play, they are not frozen
    assert status["outs"] + sum(status["score"]) > 0 or world.dynamic_scene()["ball"] != [0, 0]


def test_robots_walk_to_their_kickoff_positions_in_ready():
    world = build_world(2, players_per_team=5, rules=GameRules(initial_s=0.0, ready_s=30.0))
    plug_scripted_team(world)
    for agent in world.agents:  # shuffle them across the field
        world.place_robot(agent, 0.5 * agent.number - 1.0, 2.0 if agent.team == "blue" else -2.0, 0.0)
    run_headless(world, 25.0)
    assert world.game.state == GameState.READY
    for agent in world.agents:
        wm = agent.perception
        assert abs(wm.x - wm.kickoff_x) < 150.0 and abs(wm.y - wm.kickoff_y) < 150.0, agent.name


def test_world_is_a_soccer_world():
    assert isinstance(build_world(0), SoccerWorld)
