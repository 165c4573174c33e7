"""Why from the values the decision saw: the engine records what each decision read (issue 23).

The behavior's input function ``lag(since)`` answers ``clock - since`` for the host's clock, so
asking it again after the tick ("the world as it is now") gives another answer than the one the
decision got. ``Engine.record_reads`` makes each decision record what it read (inputs, input
function calls with their arguments and results, outputs, parameters, times, ``action_done``);
``Debugger.explain`` answers from that record and nothing else.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar

import pytest

from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.lang import Compilation
from xabsl_studio.engine.runtime import BasicBehavior, Bindings, Debugger, Engine
from xabsl_studio.engine.runtime.debug import decision_reads
from xabsl_studio.engine.types import Kind

SOURCES = {
    "agents.xabsl": """
include "symbols.xabsl";
include "behaviors.xabsl";
include "main.xabsl";
include "walk.xabsl";
agent lagging("Lagging", main);
""",
    "symbols.xabsl": """namespace s("S") {
  enum mode { idle, go };
  float input clock "ms";
  float input lag "ms" ( float since; );
  float input abs ( float value; );
  bool input near ( enum mode m; float x; float y; );
  enum mode input mode.now;
  float output count;
  float internal memo;
}
""",
    "behaviors.xabsl": """namespace b("B") {
  behavior step { float size; }
}
""",
    "main.xabsl": """option main {
  initial state wait {
    decision {
      /** the host's lag of this tick, a plain input and an output the actions change */
      if (lag(since = 1000) > 0 && clock > 500 && count < 3)
        goto run;
      else
        stay;
    }
    action {
      count = count + 1;
      walk(to = 20);
    }
  }
  state run {
    decision {
      if (action_done && near(x = abs(value = clock), m = mode.now, y = 2) && state_time >= 0)
        goto wait;
      else
        stay;
    }
    action {
      walk(to = lag(since = 0));
    }
  }
}
""",
    "walk.xabsl": """option walk {
  float @to;
  initial state going {
    decision {
      if (@to > 10 && option_time >= 0)
        goto there;
      else
        stay;
    }
    action { step(size = @to); }
  }
  target state there {
    decision { stay; }
    action { memo = @to; }
  }
}
""",
}


class Step(BasicBehavior):
    name = "step"
    parameters = (("size", Kind.DECIMAL),)
    calls: ClassVar[int] = 0

    def execute(self) -> None:
        type(self).calls += 1


class World:
    """The host: a clock, and input functions that answer from it."""

    def __init__(self) -> None:
        self.clock = 0.0
        self.mode = 1

    def lag(self, since: float) -> float:
        return self.clock - since

    def near(self, y: float, m: int, x: float) -> bool:
        return m == self.mode and x > y


def abs_value(value: float) -> float:
    return abs(value)


@pytest.fixture
def program(compile_sources: Callable[..., Compilation]) -> Program:
    compilation = compile_sources(SOURCES, "agents.xabsl")
    assert compilation.program is not None, [
        d.as_dict() for d in compilation.diagnostics if d.severity.value == "error"
    ]
    return compilation.program


def make(program: Program, record: bool = True) -> tuple[Engine, World]:
    world = World()
    b = Bindings()
    b.enum("mode", ["idle", "go"])
    b.input("clock", Kind.DECIMAL, lambda: world.clock)
    b.input("lag", Kind.DECIMAL, world.lag, params=[("since", Kind.DECIMAL)])
    # near is registered in another order than declared (m, x, y), and with a call in its
    # arguments that makes the generated code set them through its shared parameter storage.
    b.input("near", Kind.BOOLEAN, world.near, params=[("y", Kind.DECIMAL), ("m", Kind.ENUM), ("x", Kind.DECIMAL)])
    b.input("abs", Kind.DECIMAL, abs_value, params=[("value", Kind.DECIMAL)])
    b.input("mode.now", Kind.ENUM, lambda: world.mode, enum="mode")
    b.output("count", Kind.DECIMAL)
    b.behavior(Step)
    engine = Engine(b, program)
    engine.record_reads = record
    return engine, world


def conditions(engine: Engine, option: str) -> list[tuple[Any, bool, list[str]]]:
    explanation = Debugger(engine).explain(option)
    return [(c.value, c.branch, [str(k) for k in c.comparisons]) for c in explanation.conditions]


def test_why_shows_what_the_input_function_returned_in_that_tick_not_now(program: Program) -> None:
    engine, world = make(program)
    world.clock = 900.0
    engine.execute(900)  # lag(since = 1000) = -100: main stays in wait
    world.clock = 5000.0  # the world moved on: lag(since = 1000) is 4000 now
    # && short-circuits: the decision never read clock and count, so they are unknown, not guessed.
    assert conditions(engine, "main") == [
        (False, False, ["lag(since = 1000) (-100) > 0", "clock (?) > 500", "count (?) < 3"])
    ]
    world.clock = 1200.0
    engine.execute(1200)  # lag = 200 > 0, clock > 500, count (1 after the first tick) < 3: to run
    world.clock = 0.0
    explanation = Debugger(engine).explain("main")
    assert (explanation.decided_in, explanation.target, explanation.leaf) == ("wait", "run", 0)
    assert conditions(engine, "main") == [
        (True, True, ["lag(since = 1000) (200) > 0", "clock (1200) > 500", "count (1) < 3"])
    ]


def test_why_of_a_decision_reads_its_own_arguments_nested_calls_enums_and_action_done(program: Program) -> None:
    engine, world = make(program)
    world.clock = 1200.0
    engine.execute(1200)  # main: wait -> run; walk(to = lag(since = 0) = 1200): going -> there
    world.clock = 0.0
    walk = Debugger(engine).explain("walk")
    assert (walk.decided_in, walk.target) == ("going", "there")
    assert conditions(engine, "walk") == [(True, True, ["@to (1200) > 10", "option_time (0) >= 0"])]
    world.clock = 1225.0
    engine.execute(1225)  # main: run -> wait (walk is in its target state; near(...) is true)
    world.clock, world.mode = -1.0, 0  # asked now, near(...) would be false and action_done too
    explanation = Debugger(engine).explain("main")
    assert (explanation.decided_in, explanation.target) == ("run", "wait")
    assert conditions(engine, "main") == [(True, True, ["state_time (25) >= 0"])]
    reads = decision_reads(engine.reads(), program.options["main"].index)
    lag, near, absolute, clock, mode = (program.inputs[n].index for n in ("lag", "near", "abs", "clock", "mode.now"))
    assert reads == [
        ("done", True),
        (clock, 1225.0),  # through the shared storage the engine sets decimals (y, x) first...
        (absolute, 1225.0, 1225.0),
        (mode, 1),  # ...then enums (§2.5)
        (near, 1, 1225.0, 2.0, True),  # arguments as declared (m, x, y), not as registered (y, m, x)
        ("st", 25.0),
    ]
    assert lag not in {r[0] for r in reads}


def test_without_recorded_reads_why_shows_unknown_values_not_the_host_now(program: Program) -> None:
    engine, world = make(program, record=False)
    world.clock = 900.0
    engine.execute(900)
    world.clock = 5000.0
    [(value, branch, shown)] = conditions(engine, "main")
    assert value is None and branch is False
    assert shown == ["lag(since = 1000) (?) > 0", "clock (?) > 500", "count (?) < 3"]


def test_recording_reads_changes_nothing_the_behavior_does(program: Program) -> None:
    runs = []
    for record in (False, True):
        engine, world = make(program, record)
        trace = []
        for now in range(0, 3000, 25):
            world.clock = float(now % 1700)
            world.mode = (now // 300) % 2
            engine.execute(now)
            trace.append((engine.activation_dict(), engine.outputs()))
        runs.append(trace)
    assert runs[0] == runs[1]


def test_reads_follow_overrides_and_survive_a_reload(program: Program) -> None:
    engine, world = make(program)
    engine.root_actions.override_input("clock", 100.0)
    world.clock = 1200.0
    engine.execute(1200)
    assert conditions(engine, "main")[0][2][1] == "clock (100) > 500", "the decision read the override"
    engine.reload(program)
    assert engine.record_reads
    engine.root_actions.release_input("clock")
    engine.execute(1225)
    assert conditions(engine, "main")[0][2] == ["lag(since = 1000) (200) > 0", "clock (1200) > 500", "count (1) < 3"]
