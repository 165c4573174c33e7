"""Property: generated Python and the reference interpreter give identical traces.

Hypothesis builds random IR programs directly: options with parameters and states, decision
trees over input symbols, times, parameters and ``action_done``, assignments to outputs that are
read back, an input function with nested (clobbering) calls, subsequent options without cycles.
Both run the same random input stream; every tick's activation nodes and outputs must agree.
"""

from __future__ import annotations

import math
from typing import Any

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.runtime.interpreter import Interpreter
from xabsl_studio.engine.ir import model as ir
from xabsl_studio.engine.runtime import Engine
from xabsl_studio.engine.trace.conformance import conformance_bindings
from xabsl_studio.engine.types import Kind

NUMBERS = [0.0, -0.0, 1.0, -2.5, 0.0, 3.0, 100.0, 0.1, 1e-7, 7.0]
D, B = Kind.DECIMAL, Kind.BOOLEAN


class Builder:
    def __init__(self, data: st.DataObject, option_count: int) -> None:
        self.data = data
        self.option_count = option_count

    def draw(self, strategy: st.SearchStrategy[Any]) -> Any:
        return self.data.draw(strategy)

    def decimal(self, params: list[ir.Parameter], depth: int) -> ir.Expression:
        leaves = ["num", "x0", "x1", "state_time", "option_time", "out0"]
        leaves += ["param"] if any(p.kind is D for p in params) else []
        # Composite nodes are listed more than once: deep arithmetic is where the engine's
        # edge cases live (division by an exact zero, C++ modulo, clobbered parameters).
        choices = leaves + (["bin", "bin", "bin", "neg", "cond", "f", "f", "mod"] if depth > 0 else [])
        kind = self.draw(st.sampled_from(choices))
        if kind == "num":
            return ir.Number(self.draw(st.sampled_from(NUMBERS)))
        if kind in ("x0", "x1"):
            return ir.InputRef(kind, D)
        if kind == "state_time":
            return ir.StateTime()
        if kind == "option_time":
            return ir.OptionTime()
        if kind == "out0":
            return ir.OutputRef("out0", D)
        if kind == "param":
            p = self.draw(st.sampled_from([p for p in params if p.kind is D]))
            return ir.ParameterRef(p.name, D)
        if kind == "bin":
            op = self.draw(st.sampled_from(["/", "+", "-", "*", "/"]))
            return ir.Binary(op, self.decimal(params, depth - 1), self.decimal(params, depth - 1), D)
        if kind == "mod":
            divisor = ir.Number(self.draw(st.sampled_from([3.0, -2.5, 7.0])))
            return ir.Binary("%", self.decimal(params, depth - 1), divisor, D)
        if kind == "neg":
            return ir.Unary("-", self.decimal(params, depth - 1), D)
        if kind == "cond":
            return ir.Conditional(
                self.boolean(params, depth - 1), self.decimal(params, depth - 1), self.decimal(params, depth - 1), D
            )
        args = []
        for name in self.draw(st.sampled_from([(), ("f.a",), ("f.b",), ("f.a", "f.b"), ("f.b", "f.a")])):
            args.append(ir.Argument(name, D, None, self.decimal(params, depth - 1)))
        return ir.InputRef("f", D, None, tuple(args))

    def boolean(self, params: list[ir.Parameter], depth: int) -> ir.Expression:
        leaves = ["lit", "b0", "done", "flag"] + (["param"] if any(p.kind is B for p in params) else [])
        kind = self.draw(st.sampled_from(leaves + ["cmp", "cmp"] + (["and", "or", "not"] if depth > 0 else [])))
        if kind == "lit":
            return ir.BooleanLiteral(self.draw(st.booleans()))
        if kind == "b0":
            return ir.InputRef("b0", B)
        if kind == "done":
            return ir.ActionDone()
        if kind == "flag":
            return ir.OutputRef("flag", B)
        if kind == "param":
            p = self.draw(st.sampled_from([p for p in params if p.kind is B]))
            return ir.ParameterRef(p.name, B)
        if kind == "cmp":
            op = self.draw(st.sampled_from(ir.COMPARISON_OPERATORS))
            return ir.Binary(op, self.decimal(params, max(depth - 1, 0)), self.decimal(params, max(depth - 1, 0)), B)
        if kind == "not":
            return ir.Unary("!", self.boolean(params, depth - 1), B)
        count = self.draw(st.integers(2, 3))
        return ir.Logical("&&" if kind == "and" else "||", tuple(self.boolean(params, depth - 1) for _ in range(count)))

    def value(self, kind: Kind, params: list[ir.Parameter]) -> ir.Expression:
        return self.decimal(params, 1) if kind is D else self.boolean(params, 1)

    def tree(self, params: list[ir.Parameter], states: list[str], me: str, depth: int, leaf: list[int]) -> Any:
        if depth == 0 or self.draw(st.booleans()):
            target = self.draw(st.sampled_from(states))
            leaf[0] += 1
            return ir.Transition(target, stay=target == me, leaf=leaf[0] - 1)
        condition = self.boolean(params, 2)
        then = self.tree(params, states, me, depth - 1, leaf)
        return ir.If(condition, then, self.tree(params, states, me, depth - 1, leaf))

    def option(self, index: int, all_params: dict[str, list[ir.Parameter]]) -> ir.Option:
        name = f"o{index}"
        params = all_params[name]
        states = [f"s{k}" for k in range(self.draw(st.integers(1, 3)))]
        initial = self.draw(st.sampled_from(states))
        built = []
        for k, state in enumerate(states):
            actions: list[ir.Action] = []
            for _ in range(self.draw(st.integers(0, 2))):
                if self.draw(st.booleans()):
                    actions.append(ir.Assignment("out0", D, None, self.decimal(params, 2)))
                else:
                    actions.append(ir.Assignment("flag", B, None, self.boolean(params, 2)))
            if index + 1 < self.option_count and self.draw(st.booleans()):
                callee = f"o{self.draw(st.integers(index + 1, self.option_count - 1))}"
                args = tuple(
                    ir.Argument(p.name, p.kind, None, self.value(p.kind, params))
                    for p in all_params[callee]
                    if self.draw(st.booleans())
                )
                position = self.draw(st.integers(0, len(actions)))
                actions.insert(position, ir.OptionCall(callee, args))
                if self.draw(st.booleans()):
                    actions.append(ir.Assignment("out1", D, None, ir.OutputRef("out0", D)))
            decision = self.tree(params, states, state, 3, [0])
            built.append(
                ir.State(state, k, decision, tuple(actions), initial=state == initial, target=self.draw(st.booleans()))
            )
        return ir.Option(name, index, tuple(params), tuple(built), initial)


def build_program(data: st.DataObject) -> ir.Program:
    count = data.draw(st.integers(1, 4))
    builder = Builder(data, count)
    all_params = {
        f"o{i}": [
            ir.Parameter(f"o{i}.p{k}", kind)
            for k, kind in enumerate(data.draw(st.lists(st.sampled_from([D, B]), max_size=2)))
        ]
        for i in range(count)
    }
    options = {f"o{i}": builder.option(i, all_params) for i in range(count)}
    inputs = {
        "x0": ir.InputSymbol("x0", D),
        "x1": ir.InputSymbol("x1", D),
        "b0": ir.InputSymbol("b0", B),
        "f": ir.InputSymbol("f", D, params=(ir.Parameter("f.a", D), ir.Parameter("f.b", D))),
    }
    outputs = {
        "out0": ir.OutputSymbol("out0", D),
        "out1": ir.OutputSymbol("out1", D, internal=True),
        "flag": ir.OutputSymbol("flag", B),
    }
    return ir.Program("random", options, (ir.Agent("a", "a", "o0"),), {}, inputs, outputs, {}, {})


def same(a: Any, b: Any) -> bool:
    if isinstance(a, float) and isinstance(b, float):
        return a == b or (math.isnan(a) and math.isnan(b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    return bool(a == b)


def flatten(nodes: list[Any]) -> list[tuple[Any, ...]]:
    result: list[tuple[Any, ...]] = []
    for node in nodes:
        if isinstance(node, ir.Option) or not hasattr(node, "option"):
            continue
        result.append((node.option, node.state, node.option_time, node.state_time, dict(node.params)))
        result.extend(flatten(list(node.sub)))
    return result


TICKS = st.lists(
    st.tuples(
        st.integers(-50, 400),
        st.sampled_from([0.0, 1.0, -1.0, 5.0, 50.0, -0.0]),
        st.sampled_from([0.0, 2.0, 10.0, -3.0]),
        st.booleans(),
    ),
    min_size=1,
    max_size=12,
)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.data(), TICKS)
def test_codegen_and_interpreter_agree(data: st.DataObject, ticks: list[tuple[int, float, float, bool]]) -> None:
    program = build_program(data)
    bindings, values = conformance_bindings(program)
    engine = Engine(bindings, program)
    oracle_values: dict[str, Any] = {}
    oracle = Interpreter(program, {"f": bindings.inputs["f"].read}, oracle_values, {})
    now = 1000
    for number, (dt, x0, x1, b0) in enumerate(ticks):
        now = (now + dt) & 0xFFFFFFFF
        values.update(x0=x0, x1=x1, b0=b0)
        oracle_values.update(x0=x0, x1=x1, b0=b0)
        engine.execute(now)
        assert engine.fault is None, engine.fault
        got = (flatten(engine.activation()), engine.outputs())
        want = oracle.execute(now, "o0")
        if not same(got, want):
            print("tick", number, "now", now)
            print(" codegen    ", got)
            print(" interpreter", want)
            for name in program.options:
                print(engine.source(name))
        assert same(got, want)
