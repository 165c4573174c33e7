"""Bad conditions, robots and files: errors of the project's tree, with line and column in the condition."""

from __future__ import annotations

from pathlib import Path

import pytest

from xabsl_studio.engine.errors import QueryError, RecordError, XabslError
from xabsl_studio.engine.query import QueryConditionError, query_recording, query_ticks
from xabsl_studio.engine.record import TickView


@pytest.mark.parametrize(
    ("condition", "line", "col", "words"),
    [
        ("ball.distance >", 1, 16, "unexpected end of the condition"),
        ("ball.distanc > 3", 1, 1, "did you mean 'ball.distance'"),
        ("ball.distance > 3 &&\n  striker.state == kik", 2, 20, "option striker has no state 'kik' (states: approach"),
        ("striker.state == 3", 1, 15, "type mismatch"),
        ("ball.distance", 1, 1, "must be boolean"),
        ("ball.distance > 3 )", 1, 19, "syntax error"),
        ("state_time > 300", 1, 1, "state_time"),
        ("", 1, 1, "empty"),
    ],
)
def test_a_bad_condition_says_where(match: Path, condition: str, line: int, col: int, words: str) -> None:
    with pytest.raises(QueryConditionError) as caught:
        query_recording(match, condition)
    error = caught.value
    assert isinstance(error, QueryError) and isinstance(error, XabslError)
    assert (error.line, error.col) == (line, col), str(error)
    assert words in str(error)
    assert str(error).startswith(f"{line}:{col}: ")
    shown = error.format().splitlines()
    assert shown[0].startswith(f"<condition>:{line}:{col}: ")
    assert shown[-1].index("^") == col - 1 + 2  # under the column, after the two-space indent


def test_a_condition_no_robot_can_evaluate_is_an_error(match: Path) -> None:
    """Every robot's behavior lacks the option: not an empty answer but the error."""
    with pytest.raises(QueryConditionError) as caught:
        query_recording(match, "no_such_option.state == x")
    assert (caught.value.line, caught.value.col) == (1, 1)


def test_a_condition_only_one_team_has_skips_the_other(match: Path) -> None:
    result = query_recording(match, "striker.active")
    assert set(result.skipped) == {"red1", "red2"}
    assert "striker.active" in result.skipped["red1"]
    assert result.to_json()["skipped"] == result.skipped


def test_an_unknown_robot(match: Path) -> None:
    with pytest.raises(QueryError, match=r"no robot 'blue9'.*blue1"):
        query_recording(match, "ball.seen", robot="blue9")


def test_not_a_recording(tmp_path: Path) -> None:
    path = tmp_path / "x.mcap"
    path.write_bytes(b"not an mcap file")
    with pytest.raises(RecordError):
        query_recording(path, "ball.seen")


def test_views_with_a_bad_condition(views: list[TickView]) -> None:
    with pytest.raises(QueryConditionError) as caught:
        query_ticks(views[:10], "ball.seen &&")
    assert caught.value.line == 1 and caught.value.col == 13
