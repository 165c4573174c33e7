"""Dotted names through the IC emitter, the IC reader and the JSON description (issue 11).

The IC names everything qualified (``guard.robot.x``, ``v save.mode.dive.left``); read back
without the sources, a parameter keeps its whole declared name within its owner and an enum
element belongs to the enumeration its context names, never to its name up to the last dot.
"""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.lang.dotted import sources
from xabsl_studio.engine import ir
from xabsl_studio.engine.emit.ic import emit_ic
from xabsl_studio.engine.emit.json import program_to_json, render_expression
from xabsl_studio.engine.ir.ic_reader import ICError, read_ic
from xabsl_studio.engine.lang import Compilation
from xabsl_studio.engine.types import Kind

Compile = Callable[..., Compilation]


@pytest.fixture
def compiled(compile_sources: Compile) -> Compilation:
    compilation = compile_sources(sources())
    assert compilation.program is not None, [d.format() for d in compilation.errors]
    return compilation


def test_the_ic_names_dotted_parameters_and_elements_in_full(compiled: Compilation) -> None:
    assert compiled.program is not None
    lines = emit_ic(compiled.program).split("\r\n")
    assert "guard 5 d guard.shift.y b guard.use.hands e save.mode guard.save.kind d guard.x d guard.robot.x" in lines
    assert "keeper.phase 3 keeper.phase.set.up keeper.phase.react keeper.phase.recover.now" in lines
    for line in (
        "d goal.dist.goal.x",
        "d keeper.dive.to.robot.x",
        "b keeper.dive.to.state.fast",
        "e hand keeper.dive.to.target.hand",
        "e hand shot.on.target.hand.used",
        "d save.pick.angle.deg",
        "v save.mode.dive.left ",
        "v save.mode.dive ",
        "v hand.both.hands ",
        "p guard.robot.x",
    ):
        assert line in lines, line


def test_the_ic_reads_back_with_whole_names(compiled: Compilation) -> None:
    assert compiled.program is not None
    text = emit_ic(compiled.program)
    read = read_ic(text)
    assert [p.short_name for p in read.options["guard"].params] == ["shift.y", "use.hands", "save.kind", "x", "robot.x"]
    assert [p.short_name for p in read.inputs["goal.dist"].params] == ["x", "goal.x"]
    assert [p.short_name for p in read.behaviors["keeper.dive.to"].params] == [
        "x",
        "robot.x",
        "state.fast",
        "target.hand",
    ]
    # no enumeration "save.mode.dive" made up from "save.mode.dive.left"
    assert set(read.enums) == {"save.mode", "hand", "keeper.phase"}
    assert set(read.enums["save.mode"].elements) == {
        "save.mode.dive",
        "save.mode.dive.left",
        "save.mode.dive.right",
    }
    assert read.outputs["keeper.save.out"].enum == "save.mode"
    assert read.outputs["keeper.hand.out"].enum == "hand"
    assert emit_ic(read) == text


def test_an_element_literal_belongs_to_the_enumeration_of_its_context() -> None:
    # `e a.b o.p` names enumeration a.b, so `v a.b.c.d` is its element `c.d` (not `d` of a.b.c)
    text = "0 0 1 o 1 e a.b o.p 1 s n s 0 1 e out p o.p i c p o.p v a.b.c.d t s t s 1 ag o"
    read = read_ic(text)
    assert set(read.enums) == {"a.b"} and read.enums["a.b"].elements == ("a.b.c.d",)
    decision = read.options["o"].state("s").decision
    assert isinstance(decision, ir.If) and isinstance(decision.condition, ir.Binary)
    assert decision.condition.right == ir.EnumLiteral("a.b.c.d", "a.b")
    assert read.outputs["out"].enum == "a.b"


def test_a_literal_without_context_takes_the_longest_named_enumeration() -> None:
    # `out2` is assigned nothing but a literal; a.b is named elsewhere, a.b.c nowhere
    text = "0 0 1 o 1 e a.b o.p 1 s n s 0 1 e out2 v a.b.c.d t s 1 ag o"
    read = read_ic(text)
    assert read.outputs["out2"].enum == "a.b"
    assert read.enums["a.b"].elements == ("a.b.c.d",)


def test_a_literal_nothing_names_is_cut_at_its_last_dot() -> None:
    read = read_ic("0 0 1 o 0 1 s n s 0 1 e out v x.y.z t s 1 ag o")
    assert read.outputs["out"].enum == "x.y"
    assert read.enums["x.y"].elements == ("x.y.z",)


@pytest.mark.parametrize(
    ("text", "what"),
    [
        ("0 0 1 o 0 1 s n s 0 1 e out v plain t s 1 ag o", "must be qualified"),
        (
            "0 0 1 o 1 e a.b o.p 1 s n s 0 1 e out p o.p i c p o.p v q.r t s t s 1 ag o",
            "cannot be an element of enumeration a.b",
        ),
        (
            "1 ph 1 ph.a 1 e ph m 1 o 0 1 s n s 0 1 e m v ph.b t s 1 ag o",
            "not an element of the internal enumeration ph",
        ),
    ],
)
def test_an_element_outside_its_enumeration_is_an_ic_error(text: str, what: str) -> None:
    with pytest.raises(ICError, match=what):
        read_ic(text)


def test_the_json_description_keeps_whole_short_names(compiled: Compilation) -> None:
    assert compiled.program is not None
    doc = program_to_json(compiled.program, compiled.source_text)
    guard = next(o for o in doc["options"] if o["name"] == "guard")
    assert [(p["name"], p["short_name"]) for p in guard["params"]][-2:] == [
        ("guard.x", "x"),
        ("guard.robot.x", "robot.x"),
    ]
    goal = next(s for s in doc["inputs"] if s["name"] == "goal.dist")
    assert [p["short_name"] for p in goal["params"]] == ["x", "goal.x"]
    dive = next(b for b in doc["behaviors"] if b["name"] == "keeper.dive.to")
    assert [p["short_name"] for p in dive["params"]] == ["x", "robot.x", "state.fast", "target.hand"]


def test_the_json_of_a_program_read_from_ic_renders_whole_names(compiled: Compilation) -> None:
    assert compiled.program is not None
    read = read_ic(emit_ic(compiled.program))
    doc = program_to_json(read)
    guard = next(o for o in doc["options"] if o["name"] == "guard")
    watch, save = guard["states"]
    assert watch["decision"]["if"] == "(@save.kind == dive.left) || (@save.kind == dive)"
    assert watch["decision"]["else"]["if"] == "@use.hands && (@robot.x > @x)"
    shot = "shot.on.target(speed.min = @shift.y, rolling.only = false, hand.used = both.hands)"
    assert save["decision"]["if"] == shot
    first = next(t for t in guard["transitions"] if t["from"] == "watch")
    assert (first["leaf"], first["to"]) == (0, watch["decision"]["then"]["to"])
    assigned = [a["value"] for a in watch["actions"] if a["type"] == "assign"]
    assert "goal.dist(x = @x, goal.x = @robot.x)" in assigned


def test_render_expression_strips_only_the_owner_prefix() -> None:
    arg = ir.Argument("f.g.h.i", Kind.DECIMAL, None, ir.ParameterRef("o.p.q", Kind.DECIMAL))
    call = ir.InputRef("f.g", Kind.DECIMAL, None, (arg,))
    assert render_expression(call, option="o") == "f.g(h.i = @p.q)"
