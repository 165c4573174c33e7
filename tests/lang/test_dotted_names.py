"""Dots inside declared names: the compiler keeps a name whole within its owner (issue 11).

A qualified parameter name is the owner's name, a dot and the declared name in full
(``guard.robot.x``, ``goal.dist.goal.x``), never only the part after the last dot; enum
elements are reachable by their name within the enumeration (``dive.left``) and in full.
"""

from __future__ import annotations

from collections.abc import Callable

from tests.lang.dotted import GUARD, KEEPER, sources
from xabsl_studio.engine import ir
from xabsl_studio.engine.lang import Compilation
from xabsl_studio.engine.types import Kind

Compile = Callable[..., Compilation]


def program(compile_sources: Compile, **replace: str) -> ir.Program:
    compilation = compile_sources(sources(**replace))
    assert [d.format() for d in compilation.errors] == []
    assert compilation.program is not None
    return compilation.program


def messages(compilation: Compilation, code: str) -> list[str]:
    return [d.message for d in compilation.diagnostics if d.code == code]


def test_the_behavior_compiles_without_a_diagnostic(compile_sources: Compile) -> None:
    compilation = compile_sources(sources())
    assert [d.format() for d in compilation.diagnostics] == []


def test_option_parameters_keep_their_whole_declared_names(compile_sources: Compile) -> None:
    guard = program(compile_sources).options["guard"]
    assert [p.name for p in guard.params] == [
        "guard.shift.y",
        "guard.use.hands",
        "guard.save.kind",
        "guard.x",
        "guard.robot.x",
    ]
    assert [p.short_name for p in guard.params] == ["shift.y", "use.hands", "save.kind", "x", "robot.x"]
    assert [p.kind for p in guard.params] == [Kind.DECIMAL, Kind.BOOLEAN, Kind.ENUM, Kind.DECIMAL, Kind.DECIMAL]
    assert guard.params[0].unit == "mm" and guard.params[2].enum == "save.mode"


def test_at_x_and_at_robot_x_are_two_parameters(compile_sources: Compile) -> None:
    guard = program(compile_sources).options["guard"]
    memo = guard.state("watch").actions[1]
    assert isinstance(memo, ir.Assignment) and isinstance(memo.value, ir.Binary)
    assert memo.value.left == ir.ParameterRef("guard.robot.x", Kind.DECIMAL, None, memo.value.left.span)
    assert memo.value.right == ir.ParameterRef("guard.x", Kind.DECIMAL, None, memo.value.right.span)


def test_calls_name_dotted_parameters_in_full(compile_sources: Compile) -> None:
    prog = program(compile_sources)
    call = prog.options["keeper"].state("play").actions[0]
    assert isinstance(call, ir.OptionCall)
    assert [a.param for a in call.args] == [
        "guard.shift.y",
        "guard.use.hands",
        "guard.save.kind",
        "guard.x",
        "guard.robot.x",
    ]
    save_kind = call.args[2].value
    assert isinstance(save_kind, ir.InputRef) and [a.param for a in save_kind.args] == ["save.pick.angle.deg"]
    dive = prog.options["guard"].state("save").actions[3]
    assert isinstance(dive, ir.BehaviorCall)
    assert [a.param for a in dive.args] == [
        "keeper.dive.to.x",
        "keeper.dive.to.robot.x",
        "keeper.dive.to.state.fast",
        "keeper.dive.to.target.hand",
    ]


def test_input_and_behavior_parameters_x_and_goal_x_are_distinct(compile_sources: Compile) -> None:
    prog = program(compile_sources)
    assert [p.short_name for p in prog.inputs["goal.dist"].params] == ["x", "goal.x"]
    assert [p.short_name for p in prog.inputs["shot.on.target"].params] == ["speed.min", "rolling.only", "hand.used"]
    # the first part of these names is a keyword (state, target): still identifiers
    assert [p.short_name for p in prog.behaviors["keeper.dive.to"].params] == [
        "x",
        "robot.x",
        "state.fast",
        "target.hand",
    ]


def test_a_missing_dotted_parameter_is_named_in_full(compile_sources: Compile) -> None:
    guard = GUARD.replace("goal.dist(x = @x, goal.x = @robot.x)", "goal.dist(goal.x = @robot.x)")
    compilation = compile_sources(sources(guard=guard))
    assert compilation.program is not None
    assert messages(compilation, "parameter-missing") == [
        "input symbol 'goal.dist' is called without parameter 'x'; it gets 0"
    ]
    call = compilation.program.options["guard"].state("watch").actions[2]
    assert isinstance(call, ir.Assignment) and isinstance(call.value, ir.InputRef)
    assert [a.param for a in call.value.args] == ["goal.dist.goal.x"]


def test_the_last_part_of_a_dotted_parameter_is_no_parameter(compile_sources: Compile) -> None:
    keeper = KEEPER.replace("shift.y = ball.rel.y", "y = ball.rel.y")
    compilation = compile_sources(sources(keeper=keeper))
    assert compilation.program is None
    assert messages(compilation, "unknown-parameter") == [
        "option 'guard' has no parameter 'y' (parameters: shift.y, use.hands, save.kind, x, robot.x)"
    ]


def test_at_the_last_part_of_a_dotted_parameter_is_no_parameter(compile_sources: Compile) -> None:
    compilation = compile_sources(sources(guard=GUARD.replace("keeper.shift.y = @shift.y;", "keeper.shift.y = @y;")))
    assert compilation.program is None
    assert [d.code for d in compilation.errors] == ["no-matching-symbol"]
    assert "'@y'" in compilation.errors[0].message


def test_a_dotted_parameter_declared_twice_is_an_error(compile_sources: Compile) -> None:
    compilation = compile_sources(sources(guard=GUARD.replace("float @x;", "float @robot.x;")))
    duplicates = [d for d in compilation.errors if d.code == "duplicate-definition"]
    assert [d.message for d in duplicates] == ["parameter '@robot.x' is defined more than once"]
    assert duplicates[0].span is not None and duplicates[0].span.line == 6


def test_enum_elements_short_and_in_full(compile_sources: Compile) -> None:
    guard = program(compile_sources).options["guard"]
    condition = guard.state("watch").decision
    assert isinstance(condition, ir.If) and isinstance(condition.condition, ir.Logical)
    compared = [b.right for b in condition.condition.operands if isinstance(b, ir.Binary)]
    # `dive.left` is its own element, not `left` of some enumeration `save.mode.dive`
    assert [(e.element, e.enum) for e in compared if isinstance(e, ir.EnumLiteral)] == [
        ("save.mode.dive.left", "save.mode"),
        ("save.mode.dive", "save.mode"),
    ]
    actions = guard.state("save").actions
    assert isinstance(actions[0], ir.Assignment) and isinstance(actions[0].value, ir.Conditional)
    branches = (actions[0].value.then, actions[0].value.otherwise)
    assert [e.element for e in branches if isinstance(e, ir.EnumLiteral)] == [
        "save.mode.dive.right",
        "save.mode.dive.left",
    ]
    assert isinstance(actions[1], ir.Assignment) and actions[1].value == ir.EnumLiteral(
        "hand.left", "hand", actions[1].value.span
    )


def test_an_element_of_another_enumeration_is_refused(compile_sources: Compile) -> None:
    # `left` is an element of `hand`, and `save.mode` has `dive.left` but no `left`
    compilation = compile_sources(sources(guard=GUARD.replace("@save.kind == dive.left", "@save.kind == left")))
    assert compilation.program is None
    assert [d.code for d in compilation.errors] == ["no-matching-symbol"]


def test_dotted_declarations(compile_sources: Compile) -> None:
    prog = program(compile_sources)
    assert prog.enums["save.mode"].elements == (
        "save.mode.none",
        "save.mode.dive",
        "save.mode.dive.left",
        "save.mode.dive.right",
    )
    assert prog.enums["keeper.phase"].internal
    assert prog.constants["goal.half.width"].value == 750
    assert prog.outputs["keeper.phase.now"].enum == "keeper.phase"
    assert prog.outputs["keeper.memo.y"].internal
