"""A small, obviously-correct tree-walking interpreter of the IR: the oracle for the codegen.

It follows §2.2 literally (``wasActive``/``isActive`` flags swapped at the end of each tick,
parameter storage written one parameter at a time in the engine's order, every input-function
call through shared storage) and favours clarity over speed. Only tests use it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from xabsl_studio.engine.ir import model as ir
from xabsl_studio.engine.types import Kind

MASK = 0xFFFFFFFF
GROUP = {Kind.DECIMAL: 0, Kind.BOOLEAN: 1, Kind.ENUM: 2}


def cpp_int(value: float) -> int:
    """C++ ``(int)value`` on x86: truncation; NaN and values outside int32 become INT_MIN."""
    if math.isnan(value) or math.isinf(value):
        return -(2**31)
    truncated = int(value)
    return truncated if -(2**31) <= truncated < 2**31 else -(2**31)


def default(kind: Kind) -> Any:
    return {Kind.DECIMAL: 0.0, Kind.BOOLEAN: False, Kind.ENUM: 0}[kind]


def ordered(params: tuple[ir.Parameter, ...]) -> list[ir.Parameter]:
    return sorted(params, key=lambda p: (GROUP[p.kind], params.index(p)))


@dataclass
class OptionState:
    active: str
    was_active: bool = False
    is_active: bool = False
    activated: int = 0
    state_entered: int = 0
    params: dict[str, Any] = field(default_factory=dict)


class Interpreter:
    """Runs a program; ``execute(now)`` returns the tick's nodes and outputs."""

    def __init__(
        self,
        program: ir.Program,
        functions: dict[str, Callable[..., Any]],
        values: dict[str, Any],
        enum_values: dict[str, int],
    ) -> None:
        self.program = program
        self.functions = functions
        self.values = values
        self.enum_values = enum_values
        self.options = {
            name: OptionState(o.initial_state, params={p.name: default(p.kind) for p in o.params})
            for name, o in program.options.items()
        }
        self.storage = {name: {p.name: default(p.kind) for p in s.params} for name, s in program.inputs.items()}
        self.outputs: dict[str, Any] = {}
        for out in program.outputs.values():
            if out.kind is Kind.ENUM:
                self.outputs[out.name] = enum_values[program.enums[out.enum].elements[0]]
            else:
                self.outputs[out.name] = default(out.kind)
        self.now = 0
        self.nodes: list[tuple[Any, ...]] = []

    def execute(self, now: int, root: str) -> tuple[list[tuple[Any, ...]], dict[str, Any]]:
        self.now = now & MASK
        self.nodes = []
        self.call_option(root, (), None)
        for state in self.options.values():
            state.was_active, state.is_active = state.is_active, False
        return self.nodes, dict(self.outputs)

    # -- calls ------------------------------------------------------------------------------------

    def call_option(self, name: str, args: tuple[ir.Argument, ...], context: tuple[str, str] | None) -> None:
        option = self.program.options[name]
        st = self.options[name]
        given = {a.param: a.value for a in args}
        for p in ordered(option.params):
            st.params[p.name] = self.eval(given[p.name], context) if p.name in given else default(p.kind)
        if not st.was_active:
            st.activated = self.now
        assert not st.is_active, "the generator builds no double executions"
        if not st.was_active:
            st.active = option.initial_state
            st.state_entered = self.now
        state = option.state(st.active)
        target = self.decide(state.decision, (name, state.name))
        if target != state.name:
            st.active = target
            st.state_entered = self.now
        node_index = len(self.nodes)
        self.nodes.append(None)  # type: ignore[arg-type]
        for action in option.state(st.active).actions:
            if isinstance(action, ir.Assignment):
                self.outputs[action.symbol] = self.eval(action.value, (name, st.active))
            elif isinstance(action, ir.OptionCall):
                self.call_option(action.option, action.args, (name, st.active))
        st.is_active = True
        self.nodes[node_index] = (
            name,
            st.active,
            (self.now - st.activated) & MASK,
            (self.now - st.state_entered) & MASK,
            dict(st.params),
        )

    def decide(self, tree: ir.DecisionTree, context: tuple[str, str]) -> str:
        while isinstance(tree, ir.If):
            tree = tree.then if self.eval(tree.condition, context) else tree.otherwise
        assert tree.target is not None
        return tree.target

    # -- expressions ------------------------------------------------------------------------------

    def eval(self, e: ir.Expression, context: tuple[str, str] | None) -> Any:
        assert context is not None
        option, state = context
        st = self.options[option]
        if isinstance(e, ir.Number | ir.Constant):
            return e.value
        if isinstance(e, ir.BooleanLiteral):
            return e.value
        if isinstance(e, ir.EnumLiteral):
            return self.enum_values[e.element]
        if isinstance(e, ir.ParameterRef):
            return st.params[e.param]
        if isinstance(e, ir.OutputRef):
            return self.outputs[e.symbol]
        if isinstance(e, ir.InputRef):
            symbol = self.program.inputs[e.symbol]
            if not symbol.params:
                return self.values[e.symbol]
            given = {a.param: a.value for a in e.args}
            storage = self.storage[e.symbol]
            for p in ordered(symbol.params):
                storage[p.name] = self.eval(given[p.name], context) if p.name in given else default(p.kind)
            return self.functions[e.symbol](*(storage[p.name] for p in symbol.params))
        if isinstance(e, ir.StateTime):
            return float((self.now - st.state_entered) & MASK)
        if isinstance(e, ir.OptionTime):
            return float((self.now - st.activated) & MASK)
        if isinstance(e, ir.ActionDone):
            for child in self.program.options[option].state(state).subsequent_options:
                c = self.options[child]
                if c.was_active and self.program.options[child].state(c.active).target:
                    return True
            return False
        if isinstance(e, ir.Unary):
            value = self.eval(e.operand, context)
            return 0.0 - value if e.op == "-" else not value
        if isinstance(e, ir.Binary):
            a = self.eval(e.left, context)
            b = self.eval(e.right, context)
            if e.op == "/":
                return a / (b if b != 0 else 1e-7)
            if e.op == "%":
                return float(int(math.fmod(cpp_int(a), cpp_int(b))))
            return {
                "+": lambda: a + b,
                "-": lambda: a - b,
                "*": lambda: a * b,
                "<": lambda: a < b,
                "<=": lambda: a <= b,
                ">": lambda: a > b,
                ">=": lambda: a >= b,
                "==": lambda: a == b,
                "!=": lambda: a != b,
                "enum==": lambda: a == b,
                "enum!=": lambda: a != b,
            }[e.op]()
        if isinstance(e, ir.Logical):
            if e.op == "&&":
                return all(self.eval(o, context) for o in e.operands)
            return any(self.eval(o, context) for o in e.operands)
        if isinstance(e, ir.Conditional):
            return self.eval(e.then if self.eval(e.condition, context) else e.otherwise, context)
        raise TypeError(e)
