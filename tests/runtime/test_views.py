"""Cheap per-tick views of the engine: which options ran, active states, positional parameters."""

from __future__ import annotations

from typing import ClassVar

from xabsl_studio.engine.ir import model as ir
from xabsl_studio.engine.runtime import BasicBehavior, Bindings, Debugger, Engine
from xabsl_studio.engine.types import Kind

D = Kind.DECIMAL


class Act(BasicBehavior):
    name = "act"
    parameters = (("p", D), ("q", D))
    seen: ClassVar[list[tuple[float, float]]] = []

    def execute(self) -> None:
        v, k = self.parameter_values, self.parameter_offset
        Act.seen.append((v[k], v[k + 1]))
        assert (v[k], v[k + 1]) == (self.param("p"), self.param("q"))


def program() -> ir.Program:
    x = ir.InputRef("x", D)
    to_b = ir.If(
        ir.Binary(">", x, ir.Number(0.5), Kind.BOOLEAN), ir.Transition("b", leaf=0), ir.Transition("a", leaf=1)
    )
    main = ir.Option(
        "main",
        0,
        (),
        (
            ir.State("a", 0, to_b, (ir.OptionCall("child"),), initial=True),
            ir.State("b", 1, to_b, (ir.BehaviorCall("act", (ir.Argument("act.q", D, None, x),)),)),
        ),
        "a",
    )
    child = ir.Option("child", 1, (), (ir.State("c", 0, ir.Transition("c", leaf=0), ()),), "c")
    inputs = {"x": ir.InputSymbol("x", D)}
    behaviors = {"act": ir.BasicBehavior("act", (ir.Parameter("act.p", D), ir.Parameter("act.q", D)))}
    options = {"main": main, "child": child}
    return ir.Program("views", options, (ir.Agent("views", "views", "main"),), {}, inputs, {}, {}, behaviors)


def test_ran_options_and_active_states_follow_the_activation_tree() -> None:
    value = [0.0]
    bindings = Bindings()
    bindings.input("x", D, lambda: value[0])
    bindings.behavior(Act)
    engine = Engine(bindings, program())
    assert engine.option_names == ("main", "child")
    engine.execute(0)
    assert engine.ran_options() == b"\x01\x01"
    assert engine.active_states() == (0, 0)
    value[0] = 1.0
    engine.execute(10)
    assert engine.ran_options() == b"\x01\x00", "child did not run in state b"
    assert engine.active_states() == (1, 0)
    assert Act.seen[-1] == (0.0, 1.0), "unassigned p is reset to 0, q = x"


class Model:
    def __init__(self) -> None:
        self.x = 0.0


def test_attribute_inputs_are_read_directly_and_can_be_overridden() -> None:
    model = Model()
    bindings = Bindings()
    bindings.input_attribute("x", D, model, "x")
    bindings.behavior(Act)
    engine = Engine(bindings, program())
    assert "IA0.x" in engine.source("main")
    model.x = 1.0
    engine.execute(0)
    assert engine.active_states()[0] == 1 and Act.seen[-1] == (0.0, 1.0)
    engine.root_actions.override_input("x", 0.25)
    assert Debugger(engine).input_values() == {"x": 0.25}
    engine.execute(10)
    assert engine.active_states()[0] == 0, "the override is what the decision read"
    engine.root_actions.release_input("x")
    engine.execute(20)
    assert engine.active_states()[0] == 1 and Act.seen[-1] == (0.0, 1.0)
    assert Debugger(engine).input_values() == {"x": 1.0}


def test_item_inputs_are_subscripted_directly_and_can_be_overridden() -> None:
    values = {"x": 0.0}
    bindings = Bindings()
    bindings.input_item("x", D, values, "x")
    bindings.behavior(Act)
    engine = Engine(bindings, program())
    assert "IA0['x']" in engine.source("main") and "I0()" not in engine.source("main")
    values["x"] = 1.0
    engine.execute(0)
    assert engine.active_states()[0] == 1 and Act.seen[-1] == (0.0, 1.0)
    engine.root_actions.override_input("x", 0.25)
    assert Debugger(engine).input_values() == {"x": 0.25}
    engine.execute(10)
    assert engine.active_states()[0] == 0, "the override is what the decision read"
    engine.root_actions.release_input("x")
    values["x"] = 0.75
    engine.execute(20)
    assert engine.active_states()[0] == 1 and Act.seen[-1] == (0.0, 0.75)
    assert Debugger(engine).input_values() == {"x": 0.75}
