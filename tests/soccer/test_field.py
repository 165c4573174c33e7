"""Field geometry, team frames and the static scene (examples/soccer/field.py)."""

from __future__ import annotations

import math

import orjson
import pytest

from xabsl_studio.examples.soccer.field import (
    FieldDimensions,
    from_team_frame,
    heading_to_team_frame,
    static_scene,
    to_team_frame,
)


def test_spl_dimensions():
    dims = FieldDimensions()
    assert (dims.length, dims.width, dims.border) == (9.0, 6.0, 0.7)
    assert dims.wall_x == pytest.approx(5.2)
    assert dims.wall_y == pytest.approx(3.7)
    # the gap between the inner sides of the posts is the goal width
    (_, y_low), (_, y_high) = dims.posts()[:2]
    assert (y_high - dims.post_radius) - (y_low + dims.post_radius) == pytest.approx(dims.goal_width)


def test_goal_nets_fit_between_goal_line_and_wall():
    dims = FieldDimensions()
    for side in (-1, 1):
        net = dims.net(side)
        assert len(net) == 4
        assert all(dims.half_length <= abs(x) < dims.wall_x for x, _ in net)


def test_team_frame_puts_the_own_goal_at_negative_x():
    # a team attacking -x sees its own goal (at world +4.5) at team -4.5
    assert to_team_frame(4.5, 0.0, -1) == (-4.5, 0.0)
    assert to_team_frame(1.0, 2.0, 1) == (1.0, 2.0)
    for side in (-1, 1):
        assert from_team_frame(*to_team_frame(1.25, -0.5, side), side) == (1.25, -0.5)
    assert heading_to_team_frame(0.0, -1) == pytest.approx(math.pi)


def test_static_scene_is_plain_json_in_millimetres():
    scene = static_scene(FieldDimensions())
    assert orjson.loads(orjson.dumps(scene)) == scene
    assert scene["field"] == {"length": 9000, "width": 6000, "border": 700, "line_width": 50}
    assert [0, -3000, 0, 3000] in scene["lines"]  # halfway line
    assert scene["circles"] == [[0, 0, 750]]
    assert [3200, 0] in scene["marks"]  # penalty mark 1.3 m in front of the +x goal
    assert [goal["side"] for goal in scene["goals"]] == [-1, 1]
    assert all(len(goal["posts"]) == 2 for goal in scene["goals"])
    assert len(scene["walls"]) == 4
    # 5 outer/halfway lines + per side 3 goal-area and 3 penalty-area lines
    assert len(scene["lines"]) == 5 + 2 * 6
