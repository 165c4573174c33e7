"""Input symbols answer the same whoever asked before: reading is free of effects.

A recorder reads every input every tick; the behavior reads some, in some ticks. The team
queries used to keep the last striker, team ball and pass target found when none was known this
tick, so after a tick without one the answer depended on which earlier ticks had been read: a
recorded run's values could not be reproduced by a fork that read less (issue 12).
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

from xabsl_studio.examples.soccer.bindings import Role, SoccerSymbols


def _model(now: int, messages: dict[int, Any]) -> Any:
    return SimpleNamespace(
        time_ms=now, team_messages=messages, ball_x=0.0, ball_y=0.0, opponents=[], x=0.0, y=0.0, rotation=0.0
    )


def _teammate(sent: int) -> Any:
    payload = {
        "x": 2500.0,
        "y": 900.0,
        "role": int(Role.STRIKER),
        "time_to_ball": 3.0,
        "ball_age": 0,
        "ball_x": 3100.0,
        "ball_y": -400.0,
    }
    return SimpleNamespace(sender=3, sent_ms=sent, payload=payload)


def _answers(symbols: SoccerSymbols) -> tuple[Any, ...]:
    return (
        symbols.get_team_ball_known(),
        symbols.get_team_ball_x(),
        symbols.get_team_ball_y(),
        symbols.get_striker_known(),
        symbols.get_striker_x(),
        symbols.get_striker_y(),
        symbols.get_pass_available(),
        symbols.get_pass_x(),
        symbols.get_pass_y(),
    )


def test_the_team_queries_do_not_depend_on_earlier_reads() -> None:
    read_every_tick = SoccerSymbols(_model(0, {3: _teammate(0)}))
    assert _answers(read_every_tick)[:2] == (True, 3100.0)
    read_once = SoccerSymbols(_model(0, {3: _teammate(0)}))
    for symbols in (read_every_tick, read_once):  # 5 s later the teammate went silent
        symbols.wm = _model(5000, {3: _teammate(0)})
    assert _answers(read_every_tick) == _answers(read_once)
    assert _answers(read_once) == (False, 0.0, 0.0, False, 0.0, 0.0, False, 0.0, 0.0)
