"""The conformance host: the kit's symbol bindings and its per-tick trace format.

The conformance kit (``data/conformance/README.md``) runs a behavior under fixed host
conventions and records one JSON object per tick. This module is that host:

* :func:`conformance_bindings` registers, for a program, every external enumeration (element
  *i* in declaration order has value *i*), every input symbol (plain ones are items of a value
  table that starts at 0 / false / the first element, read by generated code with a subscript
  rather than a getter call; parameterized ones are the kit's functions of
  ``sum((i+1) * value_i)``), every output symbol as engine storage, and every basic behavior as
  a behavior that only records its calls.
* :class:`TraceRunner` applies one ``in.jsonl`` line (agent switch, ``set``, clock), executes
  one tick and renders the ``expected.out.jsonl`` line: the activation tree without output
  assignments and every output and internal symbol, enum values as qualified element names.

Bad input (an unknown or parameterized symbol in ``set``, a value of the wrong type or not
finite, an enum value that is not a qualified element name, an unknown agent) raises
:class:`TraceInputError` with one line; values are converted by
:func:`xabsl_studio.engine.runtime.values.coerce`, as the debugger's and the studio's are.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from xabsl_studio.engine.errors import TraceError, ValueConversionError
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.runtime.activation import AssignmentNode, BehaviorNode, Node, OptionNode
from xabsl_studio.engine.runtime.bindings import BasicBehavior, Bindings
from xabsl_studio.engine.runtime.checks import Policy
from xabsl_studio.engine.runtime.engine import Engine
from xabsl_studio.engine.runtime.values import coerce
from xabsl_studio.engine.types import Kind, Value

__all__ = ["TraceFaultError", "TraceInputError", "TraceRunner", "conformance_bindings"]


class TraceInputError(TraceError, ValueError):
    """A line of the input trace cannot be applied (message is one line, names the tick)."""


class TraceFaultError(TraceError, RuntimeError):
    """The behavior faulted during the trace (the engine stopped the agent)."""


def _enum_size(program: Program, enum: str | None) -> int:
    if enum is None or enum not in program.enums:
        return 0
    return len(program.enums[enum].elements)


def _weighted(arity: int) -> Callable[..., float]:
    """``sum((i+1) * value_i)`` of ``arity`` values, summed left to right from ``0.0``."""
    # Unrolled for the usual arities: the same float operations in the same order as the loop
    # (so bit-identical results), without its per-call loop; these run several times a tick.
    if arity == 1:
        return lambda a: 0.0 + 1 * float(a)
    if arity == 2:
        return lambda a, b: 0.0 + 1 * float(a) + 2 * float(b)
    if arity == 3:
        return lambda a, b, c: 0.0 + 1 * float(a) + 2 * float(b) + 3 * float(c)

    def weighted(*values: Value) -> float:
        total = 0.0
        for i, value in enumerate(values):
            total += (i + 1) * float(value)
        return total

    return weighted


def _function(kind: Kind, size: int, arity: int) -> Callable[..., Value]:
    """The kit's binding for a parameterized input symbol of ``kind`` with ``arity`` parameters."""
    weighted = _weighted(arity)
    if kind is Kind.DECIMAL:
        return weighted
    if kind is Kind.BOOLEAN:
        # One call instead of two for the usual arities (as _weighted, the same operations).
        if arity == 1:
            return lambda a: 0.0 + 1 * float(a) > 0
        if arity == 2:
            return lambda a, b: 0.0 + 1 * float(a) + 2 * float(b) > 0
        return lambda *values: weighted(*values) > 0
    if size == 0:
        raise ValueError("an enum-valued input function needs a declared enumeration")
    return lambda *values: math.trunc(weighted(*values)) % size


class _RecordingBehavior(BasicBehavior):
    """A kit basic behavior: does nothing but count its calls."""

    def __init__(self) -> None:
        super().__init__()
        self.calls = 0

    def execute(self) -> None:
        self.calls += 1


def conformance_bindings(program: Program) -> tuple[Bindings, dict[str, Value]]:
    """Bindings of the kit's host for ``program`` and the table the plain inputs read.

    Returns:
        ``(bindings, values)``: assign ``values[name]`` to change a plain input symbol.
    """
    bindings = Bindings()
    for enum in program.enums.values():
        if not enum.internal:
            bindings.enum(enum.name, list(enum.elements))
    values: dict[str, Value] = {}
    for symbol in program.inputs.values():
        if symbol.params:
            bindings.input(
                symbol.name,
                symbol.kind,
                _function(symbol.kind, _enum_size(program, symbol.enum), len(symbol.params)),
                params=symbol.params,
                enum=symbol.enum,
            )
            continue
        values[symbol.name] = 0.0 if symbol.kind is Kind.DECIMAL else (False if symbol.kind is Kind.BOOLEAN else 0)
        bindings.input_item(symbol.name, symbol.kind, values, symbol.name, enum=symbol.enum)
    for out in program.outputs.values():
        if not out.internal:
            bindings.output(out.name, out.kind, enum=out.enum)
    for behavior in program.behaviors.values():
        cls = type(
            f"Kit_{behavior.name}",
            (_RecordingBehavior,),
            {"name": behavior.name, "parameters": behavior.params, "__doc__": "A kit basic behavior."},
        )
        bindings.behavior(cls)
    return bindings, values


class TraceRunner:
    """Runs a program under the kit's host conventions, one input line per tick."""

    def __init__(self, program: Program, *, policy: Policy = Policy.B2) -> None:
        self.program = program
        self.bindings, self.values = conformance_bindings(program)
        self.engine = Engine(self.bindings, program, policy=policy)
        self.line = 0

    def select_agent(self, name: str) -> None:
        """Select agent ``name`` (as an ``agent`` key of an input line does)."""
        if name not in {a.name for a in self.program.agents}:
            raise TraceInputError(f"tick {self.line}: unknown agent {name!r}")
        self.engine.root_actions.select_agent(name)

    def apply(self, settings: dict[str, Any]) -> None:
        """Apply a ``set`` object: validate every name and value, then assign."""
        for name, raw in settings.items():
            symbol = self.program.inputs.get(name)
            if symbol is None:
                raise TraceInputError(f"tick {self.line}: unknown input symbol {name!r}")
            if symbol.params:
                raise TraceInputError(f"tick {self.line}: input symbol {name!r} has parameters and cannot be set")
            self.values[name] = self._value(name, symbol.kind, symbol.enum, raw)

    def _value(self, name: str, kind: Kind, enum: str | None, raw: Any) -> Value:
        where = f"tick {self.line}: input symbol {name!r}"
        if kind is Kind.ENUM and not isinstance(raw, str):
            # The kit's traces name enum values; host values are not part of the format.
            raise TraceInputError(f"{where} is an enum, give a qualified element name, got {raw!r}")
        try:
            return coerce(kind, self.engine.loaded.enum_values(enum), raw, name=where)
        except ValueConversionError as error:
            raise TraceInputError(str(error)) from None

    def tick(self, line: dict[str, Any]) -> dict[str, Any]:
        """Apply one input line, execute one tick and return the output line."""
        self.line += 1
        if not isinstance(line, dict):
            raise TraceInputError(f"tick {self.line}: expected a JSON object")
        t = line.get("t")
        if isinstance(t, bool) or not isinstance(t, int):
            raise TraceInputError(f"tick {self.line}: 't' must be an integer number of milliseconds")
        unknown = set(line) - {"t", "set", "agent"}
        if unknown:
            raise TraceInputError(f"tick {self.line}: unknown key(s) {', '.join(sorted(unknown))}")
        if "agent" in line:
            if not isinstance(line["agent"], str):
                raise TraceInputError(f"tick {self.line}: 'agent' must be a string")
            self.select_agent(line["agent"])
        settings = line.get("set", {})
        if not isinstance(settings, dict):
            raise TraceInputError(f"tick {self.line}: 'set' must be an object")
        self.apply(settings)
        self.engine.execute(t)
        if self.engine.fault is not None:
            raise TraceFaultError(f"tick {self.line}: the behavior faulted: {self.engine.fault}")
        return self.render(t)

    def render(self, t: int) -> dict[str, Any]:
        """The output line of the tick just run at clock ``t`` (the kit's ``expected.out.jsonl`` format)."""
        engine = self.engine
        outputs: dict[str, Any] = {}
        for out in self.program.outputs.values():
            outputs[out.name] = _json_value(engine.enum_element(out.enum, engine.output(out.name)), out.kind)
        return {
            "t": t,
            "tree": [self._node(n) for n in engine.activation() if not isinstance(n, AssignmentNode)],
            "outputs": outputs,
        }

    def _node(self, node: Node) -> dict[str, Any]:
        engine = self.engine
        if isinstance(node, OptionNode):
            params = {k: _json_value(engine.enum_element(node.enums.get(k), v), None) for k, v in node.params.items()}
            return {
                "option": node.option,
                "state": node.state,
                "option_time": node.option_time,
                "state_time": node.state_time,
                "params": params,
                "sub": [self._node(n) for n in node.sub if not isinstance(n, AssignmentNode)],
            }
        assert isinstance(node, BehaviorNode)
        params = {k: _json_value(engine.enum_element(node.enums.get(k), v), None) for k, v in node.params.items()}
        return {"behavior": node.behavior, "params": params}

    def run(self, lines: Iterable[dict[str, Any]]) -> Iterator[dict[str, Any]]:
        """Run every input line; yields the output lines."""
        for line in lines:
            yield self.tick(line)


def _json_value(value: Value | str, kind: Kind | None) -> Value | str:
    if kind is Kind.DECIMAL and not isinstance(value, bool) and isinstance(value, int):
        return float(value)
    return value
