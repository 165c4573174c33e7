"""What the recording does not hold is unknown: it never matches, not even negated."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from xabsl_studio.engine.query import query_recording, query_ticks
from xabsl_studio.engine.record import TickView


def test_a_call_no_decision_made_is_unknown(match: Path) -> None:
    for condition in ("team.rank(time = -12345) == 0", "!(team.rank(time = -12345) == 0)"):
        result = query_recording(match, condition)
        assert result.intervals == [] and result.matched == 0
        assert result.unknown == result.ticks > 0


def test_unknown_is_decided_by_the_other_side_of_and_or(match: Path) -> None:
    """``false && ?`` is false and ``true || ?`` true (Kleene), so they are known."""
    never = query_recording(match, "team.rank(time = -12345) == 0 && false")
    assert never.unknown == 0 and never.matched == 0
    always = query_recording(match, "team.rank(time = -12345) == 0 || true")
    assert always.unknown == 0 and always.matched == always.ticks


def test_modulo_by_zero_is_unknown(match: Path) -> None:
    """The engine faults on ``%`` by a divisor that truncates to 0; the query does not guess."""
    result = query_recording(match, "robot.x % (robot.number - robot.number) == 0")
    assert result.matched == 0 and result.unknown == result.ticks


def test_values_of_an_option_that_does_not_run_are_unknown(match: Path) -> None:
    active = query_recording(match, "kick_ball.active")
    either = query_recording(match, "kick_ball.option_time >= 0 || !(kick_ball.option_time >= 0)")
    # known exactly in the ticks the option ran
    assert either.matched == active.matched > 0
    assert either.unknown == active.ticks - active.matched


def test_a_value_missing_from_the_views_is_unknown(views: list[TickView]) -> None:
    """A tick whose values lack a symbol (a getter that raised: recorded as unread) is unknown there."""
    window = [dataclasses.replace(v, agents=dict(v.agents)) for v in views[800:810]]
    robot = next(iter(window[0].agents))
    hole = window[5].agents[robot]
    window[5].agents[robot] = dataclasses.replace(hole, inputs={**hole.inputs, "ball.distance": None})
    result = query_ticks(window, "ball.distance >= 0", robot=robot)
    assert result.unknown == 1 and result.matched == 9
    assert [(i.first_seq, i.last_seq) for i in result.intervals] == [(800, 804), (806, 809)]


def test_reads_absent_make_calls_unknown(views: list[TickView]) -> None:
    """Ticks recorded without ``reads`` (older recordings) know no input function's result."""
    window = [
        dataclasses.replace(v, agents={n: dataclasses.replace(a, reads=None) for n, a in v.agents.items()})
        for v in views[900:950]
    ]
    result = query_ticks(window, "team.rank(time = team.time_to_ball) >= 0")
    assert result.matched == 0 and result.unknown == result.ticks > 0
