"""Queries against an independent scan: the same condition written as Python over each decoded tick.

The reference below knows nothing of the query engine: per robot and tick it reads the values of
the reader's :class:`TickView` (``AgentTick.inputs``/``outputs``), the activation tree the reader
rebuilds (``AgentTick.tree()``) and the raw ``reads`` list, combines them in Kleene's three-valued
logic (None is unknown), and cuts the true ticks into runs. Every query's intervals, match count and
unknown count must be exactly the reference's.
"""

from __future__ import annotations

import dataclasses
import operator
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from xabsl_studio.engine.query import Interval, QueryIndex, query_recording, query_ticks
from xabsl_studio.engine.record import AgentTick, Recording, TickView
from xabsl_studio.engine.runtime import BehaviorNode, OptionNode

Maybe = bool | None


@dataclass
class Tick:
    """One robot in one tick, as the reference reads it."""

    agent: AgentTick
    decimals: int

    def v(self, name: str) -> Any:
        values = {**self.agent.inputs, **self.agent.outputs}
        return values.get(name)

    def nodes(self) -> list[OptionNode | BehaviorNode]:
        found: list[OptionNode | BehaviorNode] = []

        def walk(items: Any) -> None:
            for item in items:
                if isinstance(item, OptionNode):
                    found.append(item)
                    walk(item.sub)
                elif isinstance(item, BehaviorNode):
                    found.append(item)

        walk(self.agent.tree())
        return found

    def option(self, name: str) -> OptionNode | None:
        return next((n for n in self.nodes() if isinstance(n, OptionNode) and n.option == name), None)

    def behavior(self, name: str) -> BehaviorNode | None:
        return next((n for n in self.nodes() if isinstance(n, BehaviorNode) and n.behavior == name), None)

    def call(self, function: str, *args: float | None) -> float | None:
        """What the tick's decisions got from ``function`` called with ``args`` (at the recording's precision)."""
        if any(a is None for a in args) or self.agent.reads is None:
            return None
        ident = next(s["id"] for s in self.agent.program.description["inputs"] if s["name"] == function)
        scale = 10.0**self.decimals
        wanted = [round(float(a) * scale) / scale for a in args if a is not None]
        results = {
            entry[-1]
            for entry in self.agent.reads
            if isinstance(entry, list)
            and entry[:1] == [ident]
            and len(entry) == len(args) + 2
            and [round(float(x) * scale) / scale for x in entry[1:-1]] == wanted
        }
        return results.pop() if len(results) == 1 else None


def AND(*values: Maybe) -> Maybe:
    if any(v is False for v in values):
        return False
    return None if any(v is None for v in values) else True


def OR(*values: Maybe) -> Maybe:
    if any(v is True for v in values):
        return True
    return None if any(v is None for v in values) else False


def NOT(value: Maybe) -> Maybe:
    return None if value is None else not value


def cmp(left: Any, op: Callable[[Any, Any], bool], right: Any) -> Maybe:
    return None if left is None or right is None else bool(op(left, right))


def state_is(t: Tick, option: str, state: str) -> bool:
    node = t.option(option)
    return node is not None and node.state == state


def param(t: Tick, option: str, name: str) -> Any:
    node = t.option(option)
    return None if node is None else node.params.get(name)


lt, gt, eq, ne = operator.lt, operator.gt, operator.eq, operator.ne


def minus(a: Any, b: Any) -> Any:
    return None if a is None or b is None else a - b


#: (condition, the same as Python over a Tick, the robots it applies to, whether it must match somewhere)
CASES: list[tuple[str, Callable[[Tick], Maybe], str, bool]] = [
    (
        "ball.distance < 400 && game.state == playing",
        lambda t: AND(cmp(t.v("ball.distance"), lt, 400), cmp(t.v("game.state"), eq, "game.state.playing")),
        "all",
        True,
    ),
    ("striker.state == shoot", lambda t: state_is(t, "striker", "shoot"), "home", True),
    ("striker.state != approach", lambda t: not state_is(t, "striker", "approach"), "home", True),
    (
        "kick.active || dribble.active",
        lambda t: t.behavior("kick") is not None or t.behavior("dribble") is not None,
        "all",
        True,
    ),
    (
        "go_to_position.active && go_to_position.x > -2000",
        lambda t: AND(
            t.option("go_to_position") is not None, cmp(param(t, "go_to_position", "go_to_position.x"), gt, -2000)
        ),
        "home",
        True,
    ),
    (
        "approach_ball.state_time > 1000",
        lambda t: None if t.option("approach_ball") is None else t.option("approach_ball").state_time > 1000,  # type: ignore[union-attr]
        "home",
        True,
    ),
    (
        "approach_ball.decided_in == far && approach_ball.leaf == 0",
        lambda t: AND(
            t.option("approach_ball") is not None and t.option("approach_ball").decided_in == "far",  # type: ignore[union-attr]
            None if t.option("approach_ball") is None else t.option("approach_ball").leaf == 0,  # type: ignore[union-attr]
        ),
        "home",
        True,
    ),
    (
        "team.role == striker && !ball.seen",
        lambda t: AND(cmp(t.v("team.role"), eq, "role.striker"), NOT(t.v("ball.seen"))),
        "home",
        True,
    ),
    (
        "ball.x - robot.x > 1000 || robot.y * 2 < -1000",
        lambda t: OR(
            cmp(minus(t.v("ball.x"), t.v("robot.x")), gt, 1000),
            cmp(None if t.v("robot.y") is None else t.v("robot.y") * 2, lt, -1000),
        ),
        "all",
        True,
    ),
    (
        "(ball.seen ? ball.distance : 9999) < 500",
        lambda t: (
            None if t.v("ball.seen") is None else cmp(t.v("ball.distance") if t.v("ball.seen") else 9999.0, lt, 500)
        ),
        "all",
        True,
    ),
    (
        "team.rank(time = team.time_to_ball) == 0",
        lambda t: cmp(t.call("team.rank", t.v("team.time_to_ball")), eq, 0),
        "home",
        True,
    ),
    (
        "abs(value = ball.angle) < 10 && face_ball.active",
        lambda t: AND(cmp(t.call("abs", t.v("ball.angle")), lt, 10), t.option("face_ball") is not None),
        "home",
        False,
    ),
    (
        "!(team.rank(time = -12345) == 0)",
        lambda t: NOT(cmp(t.call("team.rank", -12345.0), eq, 0)),
        "home",
        False,
    ),
    (
        "field.opponent_goal_x - ball.x < 1500 && game.state == playing",
        lambda t: AND(cmp(minus(4500.0, t.v("ball.x")), lt, 1500), cmp(t.v("game.state"), eq, "game.state.playing")),
        "home",
        True,
    ),
]


def reference(
    views: list[TickView], decimals: int, check: Callable[[Tick], Maybe], robots: list[str]
) -> tuple[list[Interval], int, int]:
    """Intervals, matches and unknowns of ``check`` over ``views`` (in tick order, then robot order)."""
    intervals: list[Interval] = []
    matched = unknown = 0
    for robot in robots:
        run: list[TickView] = []
        for view in [*views, None]:
            value = None if view is None or robot not in view.agents else check(Tick(view.agents[robot], decimals))
            if view is not None and robot in view.agents:
                matched += value is True
                unknown += value is None
            if value is True and view is not None and (not run or run[-1].seq + 1 == view.seq):
                run.append(view)
                continue
            if run:
                intervals.append(Interval(robot, run[0].seq, run[-1].seq, run[0].t, run[-1].t))
            run = [view] if value is True and view is not None else []
    intervals.sort(key=lambda i: (i.first_seq, robots.index(i.robot)))
    return intervals, matched, unknown


def robots_of(views: list[TickView], which: str) -> list[str]:
    names = list(views[0].agents)
    if which == "home":
        return [n for n in names if views[0].agents[n].program.key == "behavior"]
    return names


@pytest.mark.parametrize(("condition", "check", "which", "matches"), CASES, ids=[c[0] for c in CASES])
def test_query_equals_the_scan(
    match: Path, views: list[TickView], condition: str, check: Callable[[Tick], Maybe], which: str, matches: bool
) -> None:
    with Recording(match) as recording:
        decimals = int(recording.header["decimals"])
    robots = robots_of(views, which)
    expected, matched, unknown = reference(views, decimals, check, robots)
    result = query_recording(match, condition)
    assert result.robots == robots
    assert result.intervals == expected
    assert (result.matched, result.unknown) == (matched, unknown)
    assert result.ticks == len(views) * len(robots)
    if matches:
        assert matched > 0, "the case is meant to match somewhere in the match"
    if which == "home":
        assert sorted(result.skipped) == sorted(set(views[0].agents) - set(robots))


def test_one_robot(match: Path, views: list[TickView]) -> None:
    robot = robots_of(views, "home")[1]
    with Recording(match) as recording:
        decimals = int(recording.header["decimals"])
    expected, matched, _unknown = reference(views, decimals, lambda t: state_is(t, "striker", "shoot"), [robot])
    result = query_recording(match, "striker.state == shoot", robot=robot)
    assert result.robots == [robot] and result.skipped == {}
    assert result.intervals == expected and result.matched == matched


def test_tick_views_answer_like_the_file(match: Path, views: list[TickView]) -> None:
    """The in-memory variant (the live history's) over the same ticks gives the same intervals."""
    for condition in ("striker.state == shoot", "ball.distance < 400 && game.state == playing", "kick.active"):
        from_file = query_recording(match, condition)
        from_views = query_ticks(views, condition)
        assert from_views.intervals == from_file.intervals, condition
        assert from_views.matched == from_file.matched


def test_a_part_of_the_views(match: Path, views: list[TickView]) -> None:
    """A window of the history: intervals are cut at its ends."""
    window = views[700:1100]
    result = query_ticks(window, "game.state == playing")
    assert result.intervals
    assert all(700 <= i.first_seq <= i.last_seq < 1100 for i in result.intervals)
    assert result.ticks == len(window) * len(views[0].agents)


def test_an_index_answers_many_queries_and_reads_what_is_missing(match: Path) -> None:
    with Recording(match) as recording:
        index = QueryIndex.from_recording(recording)
    for condition, *_rest in CASES:
        assert index.query(condition).intervals == query_recording(match, condition).intervals, condition


def test_enum_values_as_indices_like_a_live_recording(views: list[TickView]) -> None:
    """A studio recording holds enum values as element indices (its tables name them): same answer."""
    condition = "game.state == playing && team.role != role.striker"
    window = views[600:900]

    def as_index(agent: AgentTick) -> AgentTick:
        tables = agent.program.tables["enums"]
        index = {enum: {e: int(v) for v, e in table.items()} for enum, table in tables.items()}
        inputs = {**agent.inputs, "game.state": index["game.state"][str(agent.inputs["game.state"])]}
        outputs = dict(agent.outputs)
        if "team.role" in outputs:
            outputs["team.role"] = index["role"][str(outputs["team.role"])]
        return dataclasses.replace(agent, inputs=inputs, outputs=outputs)

    numbered = [dataclasses.replace(v, agents={n: as_index(a) for n, a in v.agents.items()}) for v in window]
    assert isinstance(numbered[0].agents["blue1"].inputs["game.state"], int)
    expected = query_ticks(window, condition)
    assert expected.matched > 0
    assert query_ticks(numbered, condition).intervals == expected.intervals
