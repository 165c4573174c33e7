"""Each robot's world model: pose, ball, field of view, opponents, team messages (examples/soccer/perception.py)."""

from __future__ import annotations

import math

import pytest

from xabsl_studio.examples.soccer.perception import NEVER_SEEN_MS, SensorModel, TeamChannel, WorldModel

from .conftest import place, playing_world, run_ticks


def sensed(world, agent_index: int, now_ms: int = 0) -> WorldModel:
    agent = world.agents[agent_index]
    agent.sense(now_ms)
    return agent.perception


def test_own_pose_in_team_frame_for_both_teams():
    world = playing_world(1)
    place(world, 0, -1.0, 0.5, 30.0)
    place(world, 1, 1.0, 0.5, 180.0)  # red attacks -x: its team frame is turned by 180 degrees
    blue, red = sensed(world, 0), sensed(world, 1)
    assert (blue.x, blue.y, blue.rotation) == pytest.approx((-1000.0, 500.0, 30.0))
    assert (red.x, red.y) == pytest.approx((-1000.0, -500.0))
    assert math.remainder(red.rotation, 360.0) == pytest.approx(0.0, abs=1e-9)


def test_ball_in_view_distance_and_angle():
    world = playing_world(1)
    place(world, 0, 0.0, 0.0, 0.0)
    place(world, 1, 3.0, -2.5, 0.0)
    world.place_ball(1.0, 1.0)
    wm = sensed(world, 0)
    assert wm.ball_seen
    assert wm.ball_distance == pytest.approx(math.sqrt(2) * 1000)
    assert wm.ball_angle == pytest.approx(45.0)
    assert (wm.ball_rel_x, wm.ball_rel_y) == pytest.approx((1000.0, 1000.0))
    assert (wm.ball_x, wm.ball_y) == pytest.approx((1000.0, 1000.0))
    assert wm.ball_time_since_seen == 0


@pytest.mark.parametrize(
    ("ball", "seen"),
    [
        ((1.0, 1.6), True),  # 58 degrees left
        ((1.0, 1.8), False),  # 61 degrees left: outside the +-60 degree field of view
        ((1.0, -1.8), False),
        ((-1.0, 0.0), False),  # behind
        ((4.9, 0.0), True),  # 4.9 m away
        ((-2.0, 2.0), False),
    ],
)
def test_field_of_view_and_range(ball, seen):
    world = playing_world(1)
    place(world, 0, 0.0, 0.0, 0.0)
    place(world, 1, 3.0, -2.5, 0.0)
    world.place_ball(*ball)
    assert sensed(world, 0).ball_seen is seen


def test_ball_beyond_max_distance_is_not_seen():
    world = playing_world(1)
    place(world, 0, -4.0, 0.0, 0.0)
    place(world, 1, 3.0, -2.5, 0.0)
    world.place_ball(1.1, 0.0)  # 5.1 m
    assert not sensed(world, 0).ball_seen
    world.place_ball(0.9, 0.0)  # 4.9 m
    assert sensed(world, 0).ball_seen


def test_never_seen_ball_is_very_old():
    world = playing_world(1)
    place(world, 0, 0.0, 0.0, 180.0)
    world.place_ball(1.0, 0.0)
    wm = sensed(world, 0)
    assert not wm.ball_seen
    assert wm.ball_time_since_seen >= NEVER_SEEN_MS


def test_time_since_seen_and_last_seen_position_are_kept():
    world = playing_world(1)
    place(world, 0, 0.0, 0.0, 0.0)
    place(world, 1, 3.0, -2.5, 0.0)
    world.place_ball(1.0, 0.0)
    loop = run_ticks(world, 1)
    wm = world.agents[0].perception
    assert wm.ball_seen and wm.ball_time_since_seen == 0
    place(world, 0, 0.0, 0.0, 90.0)  # look away: the ball is now 90 degrees to the right
    run_ticks(world, 4, loop)
    assert not wm.ball_seen
    assert wm.time_ms == 100
    assert wm.ball_time_since_seen == 100
    assert wm.ball_last_seen_ms == 0
    # the estimate stays where the ball was, re-expressed from the new heading
    assert (wm.ball_x, wm.ball_y) == pytest.approx((1000.0, 0.0))
    assert wm.ball_distance == pytest.approx(1000.0)
    assert wm.ball_angle == pytest.approx(-90.0)


def test_opponents_in_view_relative_to_the_robot():
    world = playing_world(2)
    place(world, 0, 0.0, 0.0, 0.0)
    place(world, 1, -3.0, 0.0, 0.0)  # a teammate: not an opponent
    place(world, 2, 1.0, 0.0, 0.0)  # in front
    place(world, 3, -1.0, 0.0, 0.0)  # behind
    world.place_ball(2.0, 2.0)
    wm = sensed(world, 0)
    assert len(wm.opponents) == 1
    seen = wm.opponents[0]
    assert (seen.distance, seen.angle, seen.x, seen.y) == pytest.approx((1000.0, 0.0, 1000.0, 0.0))


def test_team_messages_arrive_after_the_latency_and_only_at_teammates():
    world = playing_world(3)
    sender = world.agents[0]
    sender.perception.outgoing.update({"role": 3, "ball_distance": 1200.0})
    loop = run_ticks(world, 1)  # sent at 0 ms
    sender.perception.outgoing["role"] = 4  # a later change does not travel with the sent copy
    arrivals = []
    for _ in range(10):
        run_ticks(world, 1, loop)
        arrivals.append(1 in world.agents[1].perception.team_messages)
    # 200 ms latency at 25 ms ticks: first visible at the tick at 200 ms (the 9th tick)
    assert arrivals == [False] * 7 + [True] * 3
    message = world.agents[2].perception.team_messages[1]
    assert (message.sender, message.sent_ms, message.received_ms) == (1, 0, 200)
    assert message.payload == {"role": 3, "ball_distance": 1200.0}
    assert 1 not in sender.perception.team_messages
    # red's number 1 talks to red (an empty payload): blue's message never reaches red
    for opponent in world.agents[4:]:
        assert opponent.perception.team_messages[1].payload == {}


def test_team_channel_delivers_in_order():
    channel = TeamChannel(latency_ms=200)
    receivers = [WorldModel(number=1), WorldModel(number=2)]
    channel.send(0, 1, {"n": 1})
    channel.send(100, 1, {"n": 2})
    assert channel.deliver(199, receivers) == 0
    assert channel.deliver(250, receivers) == 1
    assert receivers[1].team_messages[1].payload == {"n": 1}
    assert channel.deliver(300, receivers) == 1
    assert receivers[1].team_messages[1].payload == {"n": 2}
    assert len(channel) == 0
    assert receivers[0].team_messages == {}


def test_noise_is_present_and_reproducible():
    values = []
    for _ in range(2):
        world = playing_world(1, seed=5, sensor=SensorModel())
        place(world, 0, 0.0, 0.0, 0.0)
        world.place_ball(1.0, 0.0)
        wm = sensed(world, 0)
        values.append((wm.x, wm.y, wm.rotation, wm.ball_distance, wm.ball_angle))
    assert values[0] == values[1]
    assert values[0] != pytest.approx((0.0, 0.0, 0.0, 1000.0, 0.0))
    other = playing_world(1, seed=6, sensor=SensorModel())
    place(other, 0, 0.0, 0.0, 0.0)
    other.place_ball(1.0, 0.0)
    wm = sensed(other, 0)
    assert (wm.x, wm.y, wm.rotation, wm.ball_distance, wm.ball_angle) != values[0]


def test_referee_information_reaches_the_world_model():
    world = playing_world(2)
    world.game.score = [2, 1]
    red = sensed(world, 3)
    assert (red.own_score, red.opponent_score) == (1, 2)
    assert red.game_state == 3
    assert red.own_kickoff is False
    assert (red.kickoff_x, red.kickoff_y) == pytest.approx((-1000.0, 0.0))  # red 2, defending
    assert red.kick_ready
