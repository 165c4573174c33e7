"""RootActions and coerce: the one owner of forcing, the one conversion of outside values."""

from __future__ import annotations

import math
import re

import pytest

from xabsl_studio.engine.codegen.layout import STORAGE
from xabsl_studio.engine.ir import model as ir
from xabsl_studio.engine.runtime import (
    BasicBehavior,
    Bindings,
    DebugError,
    Engine,
    EnumValues,
    ValueConversionError,
    coerce,
)
from xabsl_studio.engine.runtime.activation import Snapshot
from xabsl_studio.engine.types import Kind

D, B, E = Kind.DECIMAL, Kind.BOOLEAN, Kind.ENUM
MODE = EnumValues("mode", {"mode.idle": 7, "mode.walk": 9})


# -- coerce -------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kind", "value", "expected"),
    [(D, 3, 3.0), (D, -0.5, -0.5), (B, True, True), (E, "mode.walk", 9), (E, 7, 7)],
)
def test_coerce_converts(kind: Kind, value: object, expected: object) -> None:
    result = coerce(kind, MODE, value)
    assert result == expected and type(result) is type(expected)


@pytest.mark.parametrize(
    ("kind", "value", "message"),
    [
        (D, True, "is decimal"),
        (D, "1.0", "is decimal"),
        (D, math.nan, "not a finite number"),
        (D, math.inf, "not a finite number"),
        (D, 10**400, "out of the range"),
        (B, 1, "is boolean"),
        (E, "walk", r"not qualified \(write mode.walk\)"),
        (E, "mode.run", "not an element of enumeration mode"),
        (E, "color.red", "not an element of enumeration mode"),
        (E, 8, "not a value of enumeration mode"),
        (E, True, "give an element name"),
        (E, 1.0, "give an element name"),
    ],
)
def test_coerce_refuses_with_one_error_type(kind: Kind, value: object, message: str) -> None:
    with pytest.raises(ValueConversionError, match=message):
        coerce(kind, MODE, value, name="parameter p")


def test_coerce_by_index_reads_enum_ints_as_declaration_positions() -> None:
    assert coerce(E, MODE, 1, by_index=True) == 9
    with pytest.raises(ValueConversionError, match="no element 2"):
        coerce(E, MODE, 2, by_index=True)
    assert coerce(E, MODE, "mode.idle", by_index=True) == 7


# -- RootActions ---------------------------------------------------------------------------------------


class Step(BasicBehavior):
    name = "step"
    parameters = (("step.mode", E), ("step.far", D))

    def __init__(self) -> None:
        super().__init__()
        self.seen: list[object] = []

    def execute(self) -> None:
        self.seen.append((self.param("mode"), self.param("far")))


def program() -> ir.Program:
    stay = ir.Transition(None, leaf=0)
    call = ir.BehaviorCall(
        "step",
        (
            ir.Argument("step.mode", E, "mode", ir.ParameterRef("walk.offset.mode", E, "mode")),
            ir.Argument("step.far", D, None, ir.ParameterRef("walk.offset.x", D)),
        ),
    )
    walk = ir.Option(
        "walk",
        0,
        (ir.Parameter("walk.offset.x", D), ir.Parameter("walk.offset.mode", E, "mode")),
        (ir.State("go", 0, stay, (call,), initial=True),),
        "go",
    )
    root = ir.Option("root", 1, (), (ir.State("idle", 0, stay, (), initial=True),), "idle")
    return ir.Program(
        "roots",
        {"root": root, "walk": walk},
        (ir.Agent("a", "A", "root"), ir.Agent("b", "B", "walk")),
        {"mode": ir.Enumeration("mode", ("mode.idle", "mode.walk")), "color": ir.Enumeration("color", ("color.red",))},
        {
            "speed": ir.InputSymbol("speed", D),
            "mood": ir.InputSymbol("mood", E, "mode"),
        },
        {"out": ir.OutputSymbol("out", D)},
        {},
        {"step": ir.BasicBehavior("step", (ir.Parameter("step.mode", E, "mode"), ir.Parameter("step.far", D)))},
    )


def engine() -> Engine:
    bindings = Bindings()
    bindings.enum("mode", {"idle": 7, "walk": 9})
    bindings.enum("color", {"red": 1})
    bindings.input("speed", D, lambda: 0.0)
    bindings.input("mood", E, lambda: 7, enum="mode")
    bindings.output("out", D)
    bindings.behavior(Step)
    return Engine(bindings, program())


def test_force_option_takes_qualified_or_ir_short_names_and_converts_once() -> None:
    e = engine()
    roots = e.root_actions
    # "offset.x" is the IR's short name of the dotted parameter walk.offset.x.
    short = next(p.short_name for p in e.program.options["walk"].params if p.name == "walk.offset.x")
    roots.force_option("walk", {short: 2, "walk.offset.mode": "mode.walk"})
    e.execute(0)
    node = e.activation()[0]
    assert node.option == "walk" and node.params == {"walk.offset.x": 2.0, "walk.offset.mode": 9}
    roots.force_option("walk", {"walk.offset.mode": 0}, by_index=True)
    e.execute(10)
    assert e.activation()[0].params["walk.offset.mode"] == 7


def test_force_refuses_an_element_of_another_enumeration() -> None:
    roots = engine().root_actions
    with pytest.raises(ValueConversionError, match="not an element of enumeration mode"):
        roots.force_option("walk", {"walk.offset.mode": "color.red"})
    with pytest.raises(ValueConversionError, match="not a value of enumeration mode"):
        roots.override_input("mood", 1)
    with pytest.raises(DebugError, match="unknown input symbol"):
        roots.override_input("nope", 1.0)
    assert roots.forced == () and roots.overrides == {}


def test_forced_roots_and_overrides_survive_a_reload_and_release() -> None:
    e = engine()
    roots = e.root_actions
    roots.select_agent("b")
    roots.force_behavior("step", {"far": 1.5})
    roots.add_output("out", 4)
    roots.override_input("speed", 3)
    e.reload(program())
    assert roots.agent == "b"
    assert [(r.kind, r.name) for r in roots.forced] == [("behavior", "step"), ("output", "out")]
    assert dict(roots.overrides) == {"speed": 3.0}
    e.execute(0)
    assert e.output("out") == 4.0 and e.input_reads["speed"]() == 3.0
    roots.release()
    roots.release_inputs()
    assert roots.forced == () and roots.overrides == {} and e.input_reads["speed"]() == 0.0
    assert [r.name for r in roots.roots] == ["walk"]


# -- the storage schema -------------------------------------------------------------------------------


def test_snapshots_and_generated_globals_follow_the_storage_schema() -> None:
    e = engine()
    e.execute(0)
    loaded = e.loaded
    # after now, tick, roots: the STORAGE lists; last the B1 call record, which is not one
    assert Snapshot._fields[3:-1] == tuple(spec.field for spec in STORAGE if spec.snapshot)
    assert Snapshot._fields[-1] == "behavior_calls"
    snapshot = e.snapshot()
    for spec in STORAGE:
        values = getattr(loaded, spec.field)
        assert loaded.globals[spec.name] is values, "generated code and engine share each list"
        if spec.snapshot:
            assert getattr(snapshot, spec.field) == tuple(values)
    # Every storage list the generated code indexes is one of the table's.
    names = {spec.name for spec in STORAGE}
    source = "\n".join(e.loaded.generated.options[o].source for o in e.option_names)
    indexed = set(re.findall(r"\b([A-Z]+)\[", source))
    assert indexed and indexed <= names, indexed - names


def test_reset_sets_back_the_schema_reset_lists() -> None:
    e = engine()
    e.execute(0)
    e.reset()
    for spec in STORAGE:
        if spec.reset:
            assert set(getattr(e.loaded, spec.field)) <= {-10}
