"""Property: recording reads changes nothing, and why from the reads agrees with every decision.

The random IR programs of ``test_codegen_property`` (decision trees over inputs, times,
parameters, outputs written earlier in the tick, ``action_done``, an input function nested in
its own arguments) run twice on the same inputs: without and with ``Engine.record_reads``. The
traces must be identical, and after every tick, for every option whose decision ran, each
condition on the path to the leaf it took must evaluate, from that decision's reads alone, to the
branch taken. Only a call nested inside the arguments of a call of the same function (§2.5: it may
overwrite the outer call's arguments) may make a value unknown; never a contradiction.
"""

from __future__ import annotations

import dataclasses

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.runtime.test_codegen_property import TICKS, build_program, flatten, same
from xabsl_studio.engine.ir import model as ir
from xabsl_studio.engine.runtime import Debugger, Engine
from xabsl_studio.engine.trace.conformance import conformance_bindings


def numbered(program: ir.Program) -> ir.Program:
    """``program`` with its symbols numbered as a compiled program's are (reads name them by id)."""
    return dataclasses.replace(
        program,
        inputs={n: dataclasses.replace(s, index=i) for i, (n, s) in enumerate(program.inputs.items())},
        outputs={n: dataclasses.replace(s, index=i) for i, (n, s) in enumerate(program.outputs.items())},
    )


def nests_itself(expression: ir.Expression) -> bool:
    return any(
        isinstance(node, ir.InputRef)
        and any(
            isinstance(inner, ir.InputRef) and inner.symbol == node.symbol
            for a in node.args
            for inner in ir.walk(a.value)
        )
        for node in ir.walk(expression)
    )


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data(), TICKS)
def test_reads_change_nothing_and_explain_every_decision(
    data: st.DataObject, ticks: list[tuple[int, float, float, bool]]
) -> None:
    program = numbered(build_program(data))
    engines = []
    inputs = []
    for record in (False, True):
        bindings, values = conformance_bindings(program)
        engine = Engine(bindings, program)
        engine.record_reads = record
        engines.append(engine)
        inputs.append(values)
    plain, recording = engines
    now = 1000
    for dt, x0, x1, b0 in ticks:
        now = (now + dt) & 0xFFFFFFFF
        for values in inputs:
            values.update(x0=x0, x1=x1, b0=b0)
        for engine in engines:
            engine.execute(now)
        assert plain.fault is None and recording.fault is None
        assert same(
            (flatten(plain.activation()), plain.outputs()), (flatten(recording.activation()), recording.outputs())
        )
        debugger = Debugger(recording)
        for name in program.options:
            slot = recording.loaded.layout.options[name]
            if (
                recording.loaded.last_tick[slot.index] != recording.tick
                or recording.loaded.decisions[slot.index] is None
            ):
                continue
            explanation = debugger.explain(name)
            for condition, (node, branch) in zip(
                explanation.conditions,
                ir.leaf_path(program.options[name].state(explanation.decided_in).decision, explanation.leaf),
                strict=True,
            ):
                assert condition.branch is branch
                if condition.value is None:
                    assert nests_itself(node.condition), (name, condition, recording.source(name))
                else:
                    assert condition.value is branch, (name, condition, recording.reads(), recording.source(name))
