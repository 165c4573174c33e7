"""The engine on a behavior whose names contain dots (issue 11), from source and from its IC.

Parameters are bound and read by their whole qualified names: ``x`` and ``goal.x`` of one input
function, ``@x`` and ``@robot.x`` of one option, and a basic behavior that reads its parameters
``robot.x`` and ``state.fast`` by their declared (dotted) names.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import ClassVar

import pytest

from tests.lang.dotted import sources
from xabsl_studio.engine.emit.ic import emit_ic
from xabsl_studio.engine.ir.ic_reader import read_ic
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.lang import Compilation
from xabsl_studio.engine.runtime import Engine
from xabsl_studio.engine.runtime.activation import BehaviorNode, OptionNode
from xabsl_studio.engine.runtime.bindings import BasicBehavior
from xabsl_studio.engine.trace.conformance import conformance_bindings
from xabsl_studio.engine.types import Kind, Value


class Dive(BasicBehavior):
    """Records what ``param`` gives for the declared (dotted) parameter names."""

    name = "keeper.dive.to"
    parameters = (
        ("x", Kind.DECIMAL),
        ("robot.x", Kind.DECIMAL),
        ("state.fast", Kind.BOOLEAN),
        ("target.hand", Kind.ENUM),
    )
    seen: ClassVar[list[dict[str, Value]]] = []

    def execute(self) -> None:
        type(self).seen.append({p: self.param(p) for p in ("x", "robot.x", "state.fast", "target.hand")})


@pytest.fixture(params=["source", "ic"])
def program(request: pytest.FixtureRequest, compile_sources: Callable[..., Compilation]) -> Program:
    compilation = compile_sources(sources())
    assert compilation.program is not None
    if request.param == "source":
        return compilation.program
    return read_ic(emit_ic(compilation.program), compilation.program)


def test_dotted_parameters_are_bound_by_their_whole_names(program: Program) -> None:
    bindings, values = conformance_bindings(program)
    Dive.seen = []
    bindings.behavior(Dive)
    engine = Engine(bindings, program)

    values.update({"ball.rel.y": 12.0, "ball.close.now": False})
    engine.execute(0)
    assert engine.fault is None
    keeper = engine.activation()[0]
    assert isinstance(keeper, OptionNode)
    guard = keeper.sub[0]
    assert isinstance(guard, OptionNode) and guard.state == "watch"
    assert guard.params["guard.x"] == 750.0 and guard.params["guard.robot.x"] == 12.0
    assert guard.params["guard.shift.y"] == 12.0
    # the kit's binding weighs x by 1 and goal.x by 2: a mix-up would give 1512
    assert engine.output("dist.out") == 750.0 + 2 * 12.0
    assert engine.output("keeper.memo.y") == 12.0 - 750.0
    assert engine.output("keeper.phase.now") == engine.enum_value("keeper.phase.set.up")

    values.update({"ball.rel.y": 1000.0, "ball.close.now": True})
    engine.execute(100)
    assert engine.fault is None
    guard = engine.activation()[0].sub[0]  # type: ignore[union-attr]
    assert isinstance(guard, OptionNode) and guard.state == "save"
    dive = guard.sub[-1]
    assert isinstance(dive, BehaviorNode) and dive.behavior == "keeper.dive.to"
    assert dive.params["keeper.dive.to.robot.x"] == 1000.0 and dive.params["keeper.dive.to.x"] == 750.0
    assert Dive.seen == [
        {"x": 750.0, "robot.x": 1000.0, "state.fast": True, "target.hand": engine.enum_value("hand.both.hands")}
    ]
    assert engine.output("keeper.save.out") == engine.enum_value("save.mode.dive.left")
    assert engine.output("keeper.hand.out") == engine.enum_value("hand.left")
    assert engine.output("keeper.phase.now") == engine.enum_value("keeper.phase.react")


def test_forced_basic_behavior_and_option_take_dotted_parameter_names(program: Program) -> None:
    bindings, _ = conformance_bindings(program)
    Dive.seen = []
    bindings.behavior(Dive)
    engine = Engine(bindings, program)
    engine.root_actions.force_behavior("keeper.dive.to", {"robot.x": 3.0, "x": 1.0, "state.fast": True})
    engine.execute(0)
    assert engine.fault is None
    assert Dive.seen == [{"x": 1.0, "robot.x": 3.0, "state.fast": True, "target.hand": 0}]
    engine.root_actions.force_option("guard", {"robot.x": 900.0, "use.hands": True})
    engine.execute(100)
    guard = engine.activation()[0]
    assert isinstance(guard, OptionNode) and guard.option == "guard"
    assert guard.params["guard.robot.x"] == 900.0 and guard.params["guard.x"] == 0.0
    assert guard.state == "save"  # @use.hands && @robot.x > @x


def test_the_debugger_writes_dotted_parameters_and_elements_whole() -> None:
    # "why" renders an operand from the IR when the condition's text cannot be cut: the option's
    # prefix goes, the parameter's own dots stay (it used to say "@y" for "@offset.y").
    from xabsl_studio.engine.ir.model import Argument, EnumLiteral, InputRef, ParameterRef
    from xabsl_studio.engine.runtime.debug import render

    assert render(ParameterRef("offset_walk.offset.y", Kind.DECIMAL), "offset_walk") == "@offset.y"
    call = InputRef(
        "ball.is.near",
        Kind.BOOLEAN,
        args=(Argument("ball.is.near.dist.max", Kind.DECIMAL, None, ParameterRef("twin_x.robot.x", Kind.DECIMAL)),),
    )
    assert render(call, "twin_x") == "ball.is.near(dist.max = @robot.x)"
    assert render(EnumLiteral("play.kind.kick.left", "play.kind"), "") == "kick.left"
