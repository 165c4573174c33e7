"""Breakpoints compiled against an engine: each kind hits at the tick it should, bad ones are refused."""

from __future__ import annotations

from pathlib import Path

import pytest

from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.lang.condition import check_condition
from xabsl_studio.engine.runtime import Engine
from xabsl_studio.engine.runtime.breakpoints import Breakpoint, BreakpointError, BreakpointSet, check_breakpoint
from xabsl_studio.engine.trace.conformance import conformance_bindings

SYMBOLS = """
namespace world("World") {
  enum mode { calm, busy };
  float input ball.distance [0..10000] "mm";
  bool input ball.seen;
  enum mode input world.mode;
  enum mode output wanted.mode;
}
"""

MAIN = """
option main {
  initial state searching {
    decision {
      if (ball.seen) goto approaching;
      else stay;
    }
    action { wanted.mode = mode.calm; }
  }
  state approaching {
    decision {
      if (!ball.seen) goto searching;
      else if (ball.distance < 300) goto near;
      else stay;
    }
    action { child(); }
  }
  state near {
    decision {
      if (ball.distance >= 300) goto approaching;
      else stay;
    }
    action { wanted.mode = mode.busy; }
  }
}
"""

CHILD = """
option child {
  initial state only {
    decision { stay; }
    action { wanted.mode = mode.busy; }
  }
}
"""

AGENTS = """
include "symbols.xabsl";
include "main.xabsl";
include "child.xabsl";
agent solo("Solo", main);
"""


@pytest.fixture(scope="module")
def program(tmp_path_factory: pytest.TempPathFactory) -> Program:
    folder: Path = tmp_path_factory.mktemp("bp")
    for name, text in {"symbols": SYMBOLS, "main": MAIN, "child": CHILD, "agents": AGENTS}.items():
        (folder / f"{name}.xabsl").write_text(text)
    compilation = compile_file(str(folder / "agents.xabsl"), base=str(folder))
    assert compilation.ok, [d.format() for d in compilation.diagnostics]
    assert compilation.program is not None
    return compilation.program


#: per tick: ball.seen, ball.distance
SCRIPT: list[tuple[bool, float]] = [
    (False, 900.0),  # 1 searching
    (True, 900.0),  # 2 -> approaching (child entered)
    (True, 500.0),  # 3 approaching
    (True, 250.0),  # 4 -> near (child left)
    (True, 250.0),  # 5 near
    (True, 400.0),  # 6 -> approaching
    (False, 400.0),  # 7 -> searching
]


def run(program: Program, points: list[Breakpoint]) -> dict[int, list[int]]:
    """Tick through SCRIPT; per breakpoint id, the ticks it hit in."""
    bindings, values = conformance_bindings(program)
    engine = Engine(bindings, program)
    breakpoints = BreakpointSet()
    breakpoints.replace("b", points)
    found: dict[int, list[int]] = {p.id: [] for p in points}
    for k, (seen, distance) in enumerate(SCRIPT):
        values["ball.seen"] = seen
        values["ball.distance"] = distance
        engine.execute(k * 100)
        for hit in breakpoints.check([(0, "b", engine)]):
            assert hit.robot == 0
            found[hit.id].append(hit.tick)
    return found


def test_each_kind_hits_at_the_right_tick(program: Program) -> None:
    points = [
        Breakpoint(1, "enter_option", option="child"),
        Breakpoint(2, "leave_option", option="child"),
        Breakpoint(3, "enter_state", option="main", state="near"),
        Breakpoint(4, "leave_state", option="main", state="approaching"),
        Breakpoint(5, "leaf", option="main", state="approaching", leaf=1),
        Breakpoint(6, "condition", condition="ball.seen && ball.distance < 450"),
        Breakpoint(7, "enter_state", option="main", state="searching"),
        Breakpoint(8, "leave_state", option="child", state="only"),
    ]
    found = run(program, points)
    assert found[1] == [2, 6]
    assert found[2] == [4, 7]
    assert found[3] == [4]
    assert found[4] == [4, 7]
    # leaf 1 of approaching is `ball.distance < 300 -> near` (leaf 0: !ball.seen)
    assert found[5] == [4]
    # true in 4, 5, 6 (400 < 450): one hit when it becomes true
    assert found[6] == [4]
    assert found[7] == [1, 7], "entering the option enters its initial state"
    assert found[8] == [4, 7], "leaving an option leaves its active state"


def test_disabled_and_other_robot_breakpoints_do_not_hit(program: Program) -> None:
    found = run(
        program,
        [
            Breakpoint(1, "enter_option", option="child", enabled=False),
            Breakpoint(2, "enter_option", option="child", robot=3),
            Breakpoint(3, "enter_option", option="child", robot=0),
        ],
    )
    assert found == {1: [], 2: [], 3: [2, 6]}


def test_a_condition_hits_again_after_it_was_false(program: Program) -> None:
    found = run(program, [Breakpoint(1, "condition", condition="ball.distance < 300 || !ball.seen")])
    # true at 1 (not seen), false 2-3, true 4-5, false 6, true 7
    assert found[1] == [1, 4, 7]


def test_enum_condition_reads_outputs(program: Program) -> None:
    found = run(program, [Breakpoint(1, "condition", condition="wanted.mode == mode.busy")])
    assert found[1] == [2]  # busy from tick 2 on (child, then near)


def test_armed_only_while_a_breakpoint_is_enabled(program: Program) -> None:
    breakpoints = BreakpointSet()
    assert not breakpoints.armed
    breakpoints.put("b", Breakpoint(1, "enter_option", option="child"))
    assert breakpoints.armed
    breakpoints.enable("b", 1, False)
    assert not breakpoints.armed
    breakpoints.remove("b", 1)
    with pytest.raises(BreakpointError, match="no breakpoint 1"):
        breakpoints.remove("b", 1)


def test_a_bad_condition_gives_diagnostics_with_line_and_column(program: Program) -> None:
    checked = check_condition(program, "ball.seen && ball.distanc < 300")
    assert not checked.ok
    (error,) = checked.diagnostics
    assert (error.span.line, error.span.col, error.span.end_col) == (1, 14, 26)  # type: ignore[union-attr]
    assert "did you mean 'ball.distance'" in error.message
    checked = check_condition(program, "ball.distance <\n 300 &&")
    assert not checked.ok
    assert checked.diagnostics[0].span is not None and checked.diagnostics[0].span.line == 2
    assert "end of the condition" in checked.diagnostics[0].message
    assert "1:1: a condition must be boolean" in check_condition(program, "ball.distance").message()
    assert "state_time" in check_condition(program, "state_time > 10").message()
    assert not check_condition(program, "wanted.mode == ball.seen").ok
    with pytest.raises(BreakpointError, match=r"condition: 1:14: no matching symbol"):
        check_breakpoint(program, Breakpoint(1, "condition", condition="ball.seen && ball.distanc < 300"))


def test_names_the_program_lacks_are_refused(program: Program) -> None:
    with pytest.raises(BreakpointError, match="no option 'nope'"):
        check_breakpoint(program, Breakpoint(1, "enter_option", option="nope"))
    with pytest.raises(BreakpointError, match="no state 'gone'"):
        check_breakpoint(program, Breakpoint(1, "enter_state", option="main", state="gone"))
    with pytest.raises(BreakpointError, match="no leaf 9"):
        check_breakpoint(program, Breakpoint(1, "leaf", option="main", state="near", leaf=9))
    with pytest.raises(BreakpointError, match="needs a state"):
        Breakpoint.from_dict({"id": 1, "kind": "leaf", "option": "main", "leaf": 0})
    with pytest.raises(BreakpointError, match="unknown breakpoint kind"):
        Breakpoint.from_dict({"id": 1, "kind": "explode"})


def test_round_trip_through_json_fields() -> None:
    point = Breakpoint(4, "leaf", option="main", state="near", leaf=0, robot=2, enabled=False)
    assert Breakpoint.from_dict(point.as_dict()) == point
    assert point.describe() == "main.near leaf 0"


def test_a_condition_that_stays_true_does_not_hit_again_when_breakpoints_change(program: Program) -> None:
    bindings, values = conformance_bindings(program)
    engine = Engine(bindings, program)
    breakpoints = BreakpointSet()
    breakpoints.put("b", Breakpoint(1, "condition", condition="ball.seen"))
    found = []
    for k, (seen, distance) in enumerate(SCRIPT):
        values["ball.seen"], values["ball.distance"] = seen, distance
        engine.execute(k * 100)
        found += [(hit.id, hit.tick) for hit in breakpoints.check([(0, "b", engine)])]
        if k == 2:  # another breakpoint set while ball.seen stays true: no second hit of 1
            breakpoints.put("b", Breakpoint(2, "enter_option", option="child"))
        if k == 3:  # a hot reload: the engine loads the program again
            engine.reload(program)
    assert found == [(1, 2), (2, 6)]
