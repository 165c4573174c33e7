"""The join of a robot's messages with our compile, on the cases a game makes rare: values the robot
sends that our sources cannot name, symbols it does not have, decisions the structure does or does
not make certain. Messages are built with protobuf from the message definitions."""

from __future__ import annotations

from typing import Any

import pytest

from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.naoth import messages as M
from xabsl_studio.engine.naoth.join import BehaviorJoin, infer_decisions

from .test_import import BEHAVIOR


@pytest.fixture(scope="module")
def program() -> Program:
    compiled = compile_file(str(BEHAVIOR / "agents.xabsl")).program
    assert compiled is not None
    return compiled


def complete(program: Program, drop_input: str | None = None) -> Any:
    """A robot's complete message with our order and enum host values 100 + i."""
    m = M.new("BehaviorStateComplete", frameNumber=1)
    for name, enum in program.enums.items():
        e = m.enumerations.add(name=name)
        for i, element in enumerate(enum.elements):
            e.elements.add(value=100 + i, name=element)
    for option in program.options.values():
        o = m.options.add(name=option.name)
        for state in option.states:
            o.states.add(name=state.name, target=state.target)
        kinds = {"decimal": M.SymbolType.DECIMAL, "boolean": M.SymbolType.BOOLEAN, "enum": M.SymbolType.ENUM}
        counters: dict[str, int] = {}
        for p in option.params:
            o.parameters.add(id=counters.setdefault(p.kind.value, 0), type=kinds[p.kind.value], name=p.name)
            counters[p.kind.value] += 1
    for agent in program.agents:
        m.agents.add(name=agent.name, rootOption=agent.root)
    lists = {
        "decimal": m.inputSymbolList.decimal,
        "boolean": m.inputSymbolList.boolean,
        "enum": m.inputSymbolList.enumerated,
    }
    counters = {}
    for symbol in program.inputs.values():
        if symbol.name == drop_input:
            continue
        i = counters.setdefault(symbol.kind.value, 0)
        counters[symbol.kind.value] += 1
        value = {"decimal": 1.5, "boolean": True, "enum": 101}[symbol.kind.value]
        lists[symbol.kind.value].add(id=i, name=symbol.name, value=value)
    return m


def test_values_the_sources_cannot_name_are_unknown(program: Program) -> None:
    join = BehaviorJoin(program, complete(program, drop_input="ball.distance"))
    assert join.mismatches == [
        "input symbol 'ball.distance' is in the sources, not on the robot",
        *[f"output symbol {s!r} is in the sources, not on the robot" for s in program.outputs],
    ]
    sparse = M.new("BehaviorStateSparse", frameNumber=2)
    sparse.inputSymbolList.enumerated.add(id=0, value=999)  # game.state: a host value no element has
    frame = join.frame(sparse)
    names = [s.name for s in program.inputs.values() if not s.params]
    values = dict(zip(names, frame.inputs, strict=True))
    assert values["game.state"] is None and values["ball.distance"] is None
    assert values["ball.was_seen"] is True and values["ball.angle"] == 1.5  # load-time values


def test_a_root_basic_behavior_and_an_unknown_option_are_left_out_and_counted(program: Program) -> None:
    join = BehaviorJoin(program, complete(program))
    sparse = M.new("BehaviorStateSparse")
    sparse.activeRootActions.add(type=M.ActionType.BASIC_BEHAVIOR).option.id = 0
    sparse.activeRootActions.add(type=M.ActionType.OPTION).option.id = 99
    frame = join.frame(sparse)
    assert frame.path == [] and frame.unplaced == 2


def test_a_decision_is_filled_in_only_where_the_structure_makes_it_certain(program: Program) -> None:
    play = program.options["play_soccer"]
    wait, ball, search = (play.state(n).index for n in ("wait", "ball", "search"))
    node = [0, 0, play.index, ball, 100, 0, ball, -1, []]
    assert infer_decisions(program, [node], [[0, 0, play.index, wait, 67, 67, wait, -1, []]]) == 1
    leaf = next(t.leaf for t in _leaves(play.state("wait").decision) if t.target == "ball")
    assert node[6:8] == [wait, leaf]
    # no previous frame (a gap, a reload), or the option was not active before: nothing is filled in
    fresh = [0, 0, play.index, search, 100, 0, search, -1, []]
    assert infer_decisions(program, [fresh], None) == 0
    assert infer_decisions(program, [fresh], [[1, 0, 0, 5, []]]) == 0
    assert fresh[6:8] == [search, -1]


def _leaves(tree: Any) -> list[Any]:
    from xabsl_studio.engine.ir.model import leaves

    return list(leaves(tree))
