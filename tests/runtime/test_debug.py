"""The debug interface: forced roots and release, input overrides, explain, input values."""

from __future__ import annotations

import pytest

from tests.runtime.helpers import Host, ic
from xabsl_studio.engine.runtime import DebugError, Debugger, ValueConversionError

PROGRAM = """
0 0 2 child 1 d child.v main 0
2 c1 n c2 n c1
0 1 d seen p child.v  i > p child.v v 10 t c2 t c1
0 1 d seen p child.v  t c2
2 a n b n a
0 1 o child 1 d child.v i x 0  i & 2 > i x 0 v 1 ! i hold 0 t b t a
0 1 a beep 1 d beep.loud v 2   t b
1 solo main
"""


def test_force_option_with_parameters_then_release() -> None:
    host = Host(ic(PROGRAM))
    host.tick(0, x=0.0)
    host.engine.root_actions.force_option("child", {"v": 20})
    host.tick(10)
    root = host.engine.activation()[0]
    assert (root.option, root.state, root.params) == ("child", "c2", {"child.v": 20.0})
    host.engine.root_actions.release()
    host.tick(20, x=0.0)
    assert host.engine.activation()[0].option == "main"
    assert host.node("main").option_time == 0, "main did not run while forced: it restarts"
    assert host.state("child") == "c2", "child ran in the previous tick: it continues"


def test_force_basic_behavior() -> None:
    host = Host(ic(PROGRAM))
    host.engine.root_actions.force_behavior("beep", {"beep.loud": 3.5})
    host.tick(0)
    node = host.engine.activation()[0]
    assert (node.behavior, node.params) == ("beep", {"beep.loud": 3.5})


def test_force_with_unknown_names_or_wrong_values_is_refused() -> None:
    roots = Host(ic(PROGRAM)).engine.root_actions
    with pytest.raises(DebugError, match="unknown option"):
        roots.force_option("nope")
    with pytest.raises(DebugError, match="no parameter"):
        roots.force_option("child", {"w": 1})
    with pytest.raises(ValueConversionError, match="decimal"):
        roots.force_option("child", {"v": True})
    with pytest.raises(ValueConversionError, match="not a finite number"):
        roots.force_option("child", {"v": float("nan")})
    with pytest.raises(ValueConversionError, match="out of the range"):
        roots.force_option("child", {"v": 10**400})
    assert roots.forced == ()


def test_override_input_and_release() -> None:
    host = Host(ic(PROGRAM))
    host.engine.root_actions.override_input("x", 5.0)
    host.tick(0, x=0.0)
    assert Debugger(host.engine).input_values()["x"] == 5.0
    assert host.state("main") == "b"
    host.engine.root_actions.release_input("x")
    assert Debugger(host.engine).input_values() == {"x": 0.0, "hold": False}
    assert host.engine.root_actions.overrides == {}


def test_explain_gives_the_conditions_on_the_path_to_the_leaf() -> None:
    host = Host(ic(PROGRAM))
    host.engine.record_reads = True  # why from what the decisions read (else: unknown values)
    host.tick(0, x=3.0, hold=True)
    explanation = Debugger(host.engine).explain("main")
    print(explanation)
    assert (explanation.decided_in, explanation.target, explanation.leaf, explanation.stay) == ("a", "a", 1, True)
    assert [(c.value, c.branch) for c in explanation.conditions] == [(False, False)]
    child = Debugger(host.engine).explain("child")
    assert child.target == "c1" and child.stay and child.conditions[0].value is False
    host.tick(10, hold=False)
    explanation = Debugger(host.engine).explain("main")
    print(explanation)
    assert (explanation.target, explanation.leaf) == ("b", 0)
    assert [(c.value, c.branch) for c in explanation.conditions] == [(True, True)]


def test_explain_unknown_or_idle_option() -> None:
    debug = Debugger(Host(ic(PROGRAM)).engine)
    with pytest.raises(DebugError):
        debug.explain("nope")
    with pytest.raises(DebugError, match="not run"):
        debug.explain("child")


# -- several root actions (§2.9 addRootAction / addRootAction...OutputSymbol) ----------------------


def test_add_root_action_runs_after_the_agents_root() -> None:
    host = Host(ic(PROGRAM))
    host.engine.root_actions.force_behavior("beep", {"beep.loud": 1.0}, add=True)
    host.tick(0, x=0.0)
    tree = host.engine.activation()
    assert [getattr(n, "option", None) or n.behavior for n in tree] == ["main", "beep"]
    assert [r.kind for r in host.engine.root_actions.forced] == ["option", "behavior"]
    host.engine.root_actions.release()
    host.tick(10, x=0.0)
    assert [getattr(n, "option", None) or n.behavior for n in host.engine.activation()] == ["main"]


def test_added_roots_run_in_order_and_force_replaces_them_all() -> None:
    host = Host(ic(PROGRAM))
    debug = host.engine.root_actions
    debug.force_option("child", {"v": 20})
    debug.force_behavior("beep", add=True)
    host.tick(0)
    assert [getattr(n, "option", None) or n.behavior for n in host.engine.activation()] == ["child", "beep"]
    debug.force_behavior("beep")
    host.tick(10)
    assert [n.behavior for n in host.engine.activation()] == ["beep"]


def test_output_symbol_root_action_assigns_every_tick() -> None:
    host = Host(ic(PROGRAM))
    debug = host.engine.root_actions
    debug.force_option("child", {"v": 20})
    debug.add_output("seen", 7.5)  # after child, which writes seen = 20: the later write wins
    host.tick(0)
    assert host.engine.output("seen") == 7.5
    assert host.engine.path()[0][2] == host.program.options["child"].index  # not in the path
    debug.release()
    with pytest.raises(DebugError, match="unknown output"):
        debug.add_output("nothing", 1.0)
