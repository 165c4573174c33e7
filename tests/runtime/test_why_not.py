"""Why not: what stood in the way of each route to a state the decision did not go to (issue 28).

The striker below picks ``kick`` when the ball is near and the goal is free, ``dribble`` when the
ball is near and the goal is blocked, ``search`` twice (the ball lost, or too far and a long time in
``wait``). Each answer is checked against the values the host gave that tick, and against the
decision's own "why": a route leaves the path taken at an ``if`` the decision evaluated, and that
``if`` is the blocker, with the value the decision saw.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from xabsl_studio.engine.errors import DebugError
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.lang import Compilation
from xabsl_studio.engine.runtime import Bindings, Debugger, Engine
from xabsl_studio.engine.runtime.debug import ReadValues
from xabsl_studio.engine.runtime.whynot import explain_why_not, leaves
from xabsl_studio.engine.types import Kind

SOURCES = {
    "agents.xabsl": """
include "symbols.xabsl";
include "striker.xabsl";
agent s("S", striker);
""",
    "symbols.xabsl": """namespace s("S") {
  float input ball.distance "mm";
  bool input ball.seen;
  bool input goal.free;
  float input far "mm" ( float of; );
}
""",
    "striker.xabsl": """option striker {
  initial state wait {
    decision {
      if (!ball.seen)
        goto search;
      else if (ball.distance < 300) {
        if (goal.free)
          goto kick;
        else
          goto dribble;
      }
      else if (far(of = ball.distance) > 1000 && state_time > 2000)
        goto search;
      else
        stay;
    }
    action { }
  }
  state kick { decision { stay; } action { } }
  state dribble { decision { goto wait; } action { } }
  state search { decision { goto wait; } action { } }
}
""",
}


class World:
    def __init__(self) -> None:
        self.distance, self.seen, self.free = 1500.0, True, True
        self.far_calls = 0

    def far(self, of: float) -> float:
        self.far_calls += 1
        return of - 200.0


@pytest.fixture
def program(compile_sources: Callable[..., Compilation]) -> Program:
    compilation = compile_sources(SOURCES, "agents.xabsl")
    assert compilation.program is not None, [d.as_dict() for d in compilation.diagnostics]
    return compilation.program


def make(program: Program) -> tuple[Engine, World]:
    world = World()
    b = Bindings()
    b.input("ball.distance", Kind.DECIMAL, lambda: world.distance)
    b.input("ball.seen", Kind.BOOLEAN, lambda: world.seen)
    b.input("goal.free", Kind.BOOLEAN, lambda: world.free)
    b.input("far", Kind.DECIMAL, world.far, params=[("of", Kind.DECIMAL)])
    engine = Engine(b, program)
    engine.record_reads = True
    return engine, world


def why_not(engine: Engine, target: str) -> object:
    option, state, leaf, values = Debugger(engine).last_decision("striker")
    return explain_why_not(option, state, leaf, target, values)


def test_a_near_ball_with_the_goal_blocked_is_why_not_kick(program: Program) -> None:
    engine, world = make(program)
    world.distance, world.free = 250.0, False
    engine.execute(0)
    option, state, leaf, values = Debugger(engine).last_decision("striker")
    answer = explain_why_not(option, state, leaf, "kick", values)
    print(answer)
    assert (answer.decided_in, answer.went_to, answer.went) == ("wait", "dribble", False)
    (route,) = answer.routes
    # the route to kick: seen, near, goal free; it parts from the path taken at `goal.free`
    assert [(c.text, c.branch, c.value) for c in route.conditions] == [
        ("!ball.seen", False, False),
        ("ball.distance < 300", True, True),
        ("goal.free", True, False),
    ]
    assert route.blocked_at == 2 == route.leaves_taken_path_at
    assert route.blocker is not None and route.blocker.text == "goal.free"
    (comparison,) = route.conditions[1].comparisons
    assert str(comparison) == "ball.distance (250) < 300"


def test_two_routes_to_search_each_with_its_blocker_and_unread_values_unknown(program: Program) -> None:
    engine, world = make(program)
    world.distance = 250.0
    engine.execute(0)
    answer = why_not(engine, "search")
    print(answer)
    first, second = answer.routes  # type: ignore[attr-defined]
    assert (first.blocked_at, first.leaves_taken_path_at) == (0, 0)
    assert first.conditions[0].value is False  # ball.seen was true: !ball.seen false
    # the second route needs the ball far: the decision saw 250 < 300 and never called far()
    assert second.blocked_at == second.leaves_taken_path_at == 1
    assert second.conditions[1].value is True and second.conditions[1].branch is False
    assert second.conditions[2].value is None, "far(of = ...) was not called: unknown, never asked again"
    assert world.far_calls == 0
    shown = [str(c) for c in second.conditions[2].comparisons]
    assert shown == ["far(of = ball.distance) (?) > 1000", "state_time (?) > 2000"]


def test_stay_is_the_route_to_the_decided_in_state(program: Program) -> None:
    engine, world = make(program)
    world.distance = 1500.0
    engine.execute(0)  # far, but state_time 0: stays in wait
    answer = why_not(engine, "wait")
    assert answer.went and answer.went_to == "wait"  # type: ignore[attr-defined]
    (route,) = answer.routes  # type: ignore[attr-defined]
    assert route.stay and route.blocked_at is None and route.leaves_taken_path_at is None
    not_search = why_not(engine, "search")
    blocked = [r.blocker.text if r.blocker else None for r in not_search.routes]  # type: ignore[attr-defined]
    assert blocked == ["!ball.seen", "far(of = ball.distance) > 1000 && state_time > 2000"]
    cond = not_search.routes[1].conditions[2]  # type: ignore[attr-defined]
    assert [str(c) for c in cond.comparisons] == ["far(of = ball.distance) (1300) > 1000", "state_time (0) > 2000"]
    assert world.far_calls == 1, "why not asks the host nothing"


def test_a_state_no_leaf_leads_to_and_an_unknown_state(program: Program) -> None:
    engine, _world = make(program)
    engine.execute(0)
    option, state, leaf, values = Debugger(engine).last_decision("striker")
    assert explain_why_not(option, option.state("kick"), 0, "search", values).routes == ()
    with pytest.raises(DebugError, match="no state nowhere"):
        explain_why_not(option, state, leaf, "nowhere", values)


def test_without_reads_every_value_is_unknown_and_nothing_blocks(program: Program) -> None:
    engine, _world = make(program)
    engine.execute(0)
    option, state, leaf, _ = Debugger(engine).last_decision("striker")
    answer = explain_why_not(option, state, leaf, "kick", ReadValues(program, option, None, {}))
    (route,) = answer.routes
    assert route.blocked_at is None and all(c.value is None for c in route.conditions)
    assert route.leaves_taken_path_at == 1  # the tree still says where the route parts


def test_why_not_agrees_with_why_on_every_leaf_over_many_ticks(program: Program) -> None:
    engine, world = make(program)
    import random

    rng = random.Random(28)
    checked = 0
    for tick in range(300):
        world.distance = rng.choice([100.0, 299.0, 300.0, 1100.0, 1300.0, 5000.0])
        world.seen, world.free = rng.random() < 0.8, rng.random() < 0.5
        engine.execute(tick * 20)
        option, state, leaf, values = Debugger(engine).last_decision("striker")
        taken = Debugger(engine).explain("striker")
        for target in {t.target or state.name for t in leaves(state.decision)}:
            answer = explain_why_not(option, state, leaf, target, values)
            assert answer.went is (target == taken.target)
            for route in answer.routes:
                checked += 1
                if route.leaf == leaf:
                    assert route.blocked_at is None and route.leaves_taken_path_at is None
                    continue
                parting = route.leaves_taken_path_at
                assert parting is not None and route.blocked_at == parting, (str(answer), str(taken))
                # the blocker is the decision's own condition, with the value "why" shows for it
                assert route.conditions[parting].value == taken.conditions[parting].value
                assert route.conditions[parting].branch is not taken.conditions[parting].branch
    assert checked > 300
