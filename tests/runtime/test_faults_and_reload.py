"""Faults stop the agent until reset; hot reload keeps what still exists; link errors list all."""

from __future__ import annotations

import pytest

from tests.runtime.helpers import Host, ic
from xabsl_studio.engine.runtime import BasicBehavior, Bindings, Engine, LinkError, LoadError, Policy
from xabsl_studio.engine.trace.conformance import conformance_bindings
from xabsl_studio.engine.types import Kind

V1 = """
0 0 2 child 0 main 0
2 c1 n c2 n c1
0 0 t c2
0 0 t c2
2 a n b n a
0 1 o child 0  i > i x 0 v 0 t b t a
0 1 o child 0  t b
1 solo main
"""

V2 = """
0 0 2 main 0 other 0
3 a n b n z n a
0 0  i > i x 0 v 0 t b t a
0 1 d marker v 1  t b
0 0 t z
1 a n a
0 0 t a
1 solo main
"""


def test_hot_reload_keeps_states_and_times_of_what_still_exists() -> None:
    host = Host(ic(V1))
    host.tick(0, x=1.0)
    host.tick(100)
    v2 = ic(V2)
    bindings, _ = conformance_bindings(v2)
    host.engine.bindings.outputs.update(bindings.outputs)
    host.engine.reload(v2)
    host.tick(150)
    node = host.node("main")
    assert (node.state, node.option_time, node.state_time) == ("b", 150, 150)
    assert host.engine.output("marker") == 1.0
    assert not host.ran("child")


def test_reload_that_fails_to_link_keeps_the_running_program() -> None:
    host = Host(ic(V1))
    host.tick(0, x=1.0)
    with pytest.raises(LinkError, match="marker"):
        host.engine.reload(ic(V2))  # the output symbol 'marker' is not registered
    host.tick(10)
    assert host.state("child") == "c2" and host.node("main").option_time == 10


def test_reload_of_a_removed_state_restarts_the_option() -> None:
    host = Host(ic(V1))
    host.tick(0, x=1.0)
    renamed = V1.replace("2 a n b n a", "2 a n q n a").replace("t b t a", "t q t a")
    smaller = ic(renamed.replace("0 1 o child 0  t b", "0 1 o child 0  t q"))
    host.engine.reload(smaller)
    host.tick(10, x=0.0)
    assert host.state("main") == "a" and host.node("main").option_time == 0


def test_link_error_lists_every_missing_name_at_once() -> None:
    program = ic("""
    0 0 1 main 0
    1 s n s
    0 3 d o i x 0  a stand 1 d stand.effort v 1  e m v mode.walk  t s
    1 solo main
    """)
    with pytest.raises(LinkError) as caught:
        Engine(Bindings(), program)
    message = str(caught.value)
    print(message)
    assert len(caught.value.problems) == 5
    for name in ("input symbol x", "output symbol o", "output symbol m", "basic behavior stand", "mode.walk"):
        assert name in message


def test_failing_input_function_faults_with_location_and_reset_clears_it() -> None:
    program = ic("""
    0 0 1 main 0
    2 a n b n a
    0 1 d r i f 1 d f.v i x 0  t b
    0 1 d r i f 1 d f.v i x 0  t b
    1 solo main
    """)

    def f(v: float) -> float:
        if v < 0:
            raise ValueError("negative")
        return v

    host = Host(program, f=f)
    host.tick(0, x=1.0)
    engine = host.tick(10, x=-1.0)
    fault = engine.fault
    assert fault is not None
    assert (fault.option, fault.state) == ("main", "b")
    assert "negative" in fault.message and "assignment r" in fault.message
    before = engine.tick
    host.tick(20, x=2.0)
    assert engine.tick == before, "an errored engine does nothing"
    assert engine.output("r") == 1.0
    engine.reset()
    host.tick(30)
    assert engine.fault is None and engine.output("r") == 2.0


def test_failing_basic_behavior_faults() -> None:
    program = ic("0 0 1 main 0 1 s n s 0 1 a kick 0 t s 1 solo main")
    bindings, _ = conformance_bindings(program)

    class Kick(BasicBehavior):
        name = "kick"

        def execute(self) -> None:
            raise RuntimeError("motor stalled")

    bindings.behavior(Kick)
    engine = Engine(bindings, program)
    engine.execute(0)
    assert engine.fault is not None and engine.fault.state == "s" and "kick" in engine.fault.message


def test_basic_behavior_hooks_time_and_parameters() -> None:
    program = ic("0 0 1 main 0 1 s n s 0 1 a walk 1 d walk.speed i x 0 t s 1 solo main")
    bindings, values = conformance_bindings(program)
    seen: list[tuple[int, float, int]] = []

    class Walk(BasicBehavior):
        name = "walk"
        parameters = (("speed", Kind.DECIMAL), ("careful", Kind.BOOLEAN))
        changes = 0

        def parameters_changed(self) -> None:
            self.changes += 1

        def execute(self) -> None:
            seen.append((self.time_of_execution, self.param("speed"), self.changes))

    bindings.behavior(Walk)
    engine = Engine(bindings, program)
    for now, x in ((100, 1.0), (150, 1.0), (175, 2.0)):
        values["x"] = x
        engine.execute(now)
    assert seen == [(0, 1.0, 1), (50, 1.0, 1), (75, 2.0, 2)]


LOOP = """
0 0 2 a 0 b 0
1 s n s 0 1 o b 0 t s
1 s n s 0 1 o a 0 t s
1 solo a
"""

SHARED = """
0 0 3 leaf 0 left 0 root 0
1 s n s 0 0 t s
1 s n s 0 1 o leaf 0 t s
1 s n s 0 2 o left 0 o leaf 0 t s
1 solo root
"""


def test_loops_are_rejected_under_both_policies() -> None:
    for policy in Policy:
        with pytest.raises(LoadError, match="reachable from itself"):
            Host(ic(LOOP), policy=policy)


def test_possible_double_execution_is_rejected_under_b2_and_warned_under_b1() -> None:
    with pytest.raises(LoadError, match="twice"):
        Host(ic(SHARED), policy=Policy.B2)
    host = Host(ic(SHARED), policy=Policy.B1)
    host.tick(0)
    assert host.engine.fault is None
    assert host.engine.warnings == ["option leaf is contained in the activation tree more than once"]
