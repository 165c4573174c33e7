"""Evaluating a checked query over a robot's columns, all ticks at once, in three values.

Every sub-expression becomes a pair of arrays over the robot's ticks: the value (booleans 0/1,
enum elements their code) and whether it is known. Unknown spreads through arithmetic and
comparisons; ``&&`` and ``||`` follow Kleene's logic (``false && unknown`` is false, ``true ||
unknown`` true), ``c ? a : b`` is unknown when ``c`` is. Arithmetic is XABSL's: ``/`` by exactly
0 divides by 1e-7, ``%`` truncates both sides to 32-bit integers (a divisor that truncates to 0
faults in the engine: unknown here).

An input function's value in a tick is the result the tick's decisions got when they called it
with the same arguments (the recorded ``reads``); arguments are compared at the recording's
precision (``decimals``: plain symbol values are recorded rounded, calls exactly), and calls
that disagree, or no call at all, leave it unknown.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from xabsl_studio.engine import ir
from xabsl_studio.engine.query.language import CompiledQuery, Predicate, state_element
from xabsl_studio.engine.record.columns import CallTable, Codes, Floats, Mask, RobotColumns

__all__ = ["evaluate"]

#: XABSL ``/``: an exactly-zero divisor is replaced by this (engine/codegen/support.py ``divide``).
ZERO_DIVISOR = 1e-07
_INT_MIN, _INT_MAX = -(2**31), 2**31 - 1
#: the value of ``O.state`` while ``O`` does not run: no element has a negative code
_NO_STATE = -1.0

Pair = tuple[Floats, Mask]


def _to_int32(values: Floats) -> Floats:
    """C++ ``(int)v`` as x86 does it: truncate; NaN or out of range gives INT_MIN."""
    with np.errstate(invalid="ignore"):
        inside = (values > _INT_MIN - 1) & (values < _INT_MAX + 1)
    return np.where(inside, np.trunc(np.where(inside, values, 0.0)), float(_INT_MIN))


class _Evaluator:
    def __init__(
        self, columns: RobotColumns, gen: int, query: CompiledQuery, codes: Codes, decimals: int | None
    ) -> None:
        self.columns = columns
        self.n = len(columns)
        self.gen = gen
        self.query = query
        self.codes = codes
        self.decimals = decimals
        self.scale = None if decimals is None else 10.0**decimals
        description = columns.programs[gen].description
        self.options = {o["name"]: o for o in description["options"]}
        self.behaviors = {b["name"]: b for b in description["behaviors"]}
        self.inputs = {s["name"]: s for s in description["inputs"]}
        nodes = columns.nodes
        self.node_in_gen = columns.gen[nodes.row] == gen if len(nodes.row) else np.zeros(0, dtype=np.bool_)

    # -- leaves -------------------------------------------------------------------------------

    def constant(self, value: float) -> Pair:
        return np.full(self.n, value, dtype=np.float64), np.ones(self.n, dtype=np.bool_)

    def unknown(self) -> Pair:
        return np.zeros(self.n, dtype=np.float64), np.zeros(self.n, dtype=np.bool_)

    def symbol(self, name: str) -> Pair:
        found = self.columns.values.get(name)
        return self.unknown() if found is None else found

    def predicate(self, predicate: Predicate) -> Pair:
        nodes = self.columns.nodes
        n = self.n
        if predicate.kind in ("behavior_active", "behavior_param"):
            behavior = self.behaviors[predicate.target]
            hit = self.node_in_gen & (nodes.kind == 1) & (nodes.ident == int(behavior["id"]))
        else:
            option = self.options[predicate.target]
            hit = self.node_in_gen & (nodes.kind == 0) & (nodes.ident == int(option["id"]))
        rows = nodes.row[hit]
        kind = predicate.kind
        if kind in ("active", "behavior_active"):
            values = np.zeros(n, dtype=np.float64)
            values[rows] = 1.0
            return values, np.ones(n, dtype=np.bool_)
        values = np.zeros(n, dtype=np.float64)
        known = np.zeros(n, dtype=np.bool_)
        if kind in ("state", "decided_in"):
            option = self.options[predicate.target]
            states = np.asarray(
                [self.codes.code(state_element(option["name"], s["name"])) for s in option["states"]],
                dtype=np.float64,
            )
            ids = (nodes.state if kind == "state" else nodes.decided)[hit]
            values[:] = _NO_STATE
            valid = (ids >= 0) & (ids < len(states))
            values[rows[valid]] = states[ids[valid]]
            return values, np.ones(n, dtype=np.bool_)
        if kind == "leaf":
            values[rows] = nodes.leaf[hit]
        elif kind == "option_time":
            values[rows] = nodes.option_time[hit]
        elif kind == "state_time":
            values[rows] = nodes.state_time[hit]
        else:  # a parameter of the option or behavior, by position
            position = predicate.position
            present = nodes.param_count[hit] > position
            at = nodes.param_start[hit][present] + position
            rows = rows[present]
            values[rows] = nodes.params[at]
            known[rows] = nodes.params_known[at]
            return values, known
        known[rows] = ~np.isnan(values[rows])
        return values, known

    def call(self, node: ir.InputRef) -> Pair:
        table = self.columns.calls.get(node.symbol)
        if node.symbol not in self.columns.functions or table is None or not self.columns.has_reads:
            return self.unknown()
        declared = [p["name"] for p in self.inputs[node.symbol].get("params", ())]
        given = {a.param: self(a.value) for a in node.args}
        # a parameter left out of the call gets 0 (false, the enum's first element), as in the engine
        args: list[Pair] = []
        for param in declared:
            if param in given:
                args.append(given[param])
            else:
                enum = next((p.get("enum") for p in self.inputs[node.symbol]["params"] if p["name"] == param), None)
                default = self._host_zero(enum)
                args.append(self.constant(default) if default is not None else self.unknown())
        return self._lookup(table, args)

    def _host_zero(self, enum: str | None) -> float | None:
        if enum is None:
            return 0.0
        element = self.columns.programs[self.gen].tables.get("enums", {}).get(enum, {}).get("0")
        return None if element is None else float(self.codes.code(element))

    def _key(self, value: float | None) -> float | None:
        if value is None or self.scale is None:
            return value
        return round(value * self.scale) / self.scale

    def _keys(self, table: CallTable) -> dict[tuple[Any, ...], int]:
        """(row, arguments at the recording's precision) -> the call's index, -1 where calls disagree."""
        results = table.keys.get(self.decimals)
        if results is not None:
            return results
        results = table.keys[self.decimals] = {}
        key = self._key
        for index, (row, recorded) in enumerate(zip(table.row.tolist(), table.args, strict=True)):
            k = (row, *(key(v) for v in recorded))
            previous = results.get(k)
            if previous is None:
                results[k] = index
            elif previous != -1 and (
                table.known[previous] != table.known[index] or table.result[previous] != table.result[index]
            ):
                results[k] = -1  # the same call gave two results in one tick: not knowable
        return results

    def _lookup(self, table: CallTable, args: list[Pair]) -> Pair:
        results = self._keys(table)
        conflict = -1
        key = self._key
        values = np.zeros(self.n, dtype=np.float64)
        known = np.zeros(self.n, dtype=np.bool_)
        every = np.ones(self.n, dtype=np.bool_)
        for _value, arg_known in args:
            every &= arg_known
        rows = np.flatnonzero(every)
        arg_values = [a[0][rows].tolist() for a in args]
        for position, row in enumerate(rows.tolist()):
            found = results.get((row, *(key(a[position]) for a in arg_values)))
            if found is not None and found != conflict and table.known[found]:
                values[row] = table.result[found]
                known[row] = True
        return values, known

    # -- operators ----------------------------------------------------------------------------

    def __call__(self, node: ir.Expression) -> Pair:
        match node:
            case ir.Number(value=number) | ir.Constant(value=number):
                return self.constant(float(number))
            case ir.BooleanLiteral(value=truth):
                return self.constant(1.0 if truth else 0.0)
            case ir.EnumLiteral(element=element):
                return self.constant(float(self.codes.code(element)))
            case ir.InputRef(symbol=symbol) if symbol in self.query.predicates:
                return self.predicate(self.query.predicates[symbol])
            case ir.InputRef(symbol=symbol) if symbol in self.query.functions:
                return self.call(node)
            case ir.InputRef(symbol=symbol) | ir.OutputRef(symbol=symbol):
                return self.symbol(symbol)
            case ir.Unary(op="-", operand=operand):
                value, known = self(operand)
                return 0.0 - value, known
            case ir.Unary(op="!", operand=operand):
                value, known = self(operand)
                return 1.0 - value, known
            case ir.Binary(op=op, left=left, right=right):
                return self.binary(op, self(left), self(right))
            case ir.Logical(op=op, operands=operands):
                return self.logical(op, [self(o) for o in operands])
            case ir.Conditional(condition=condition, then=then, otherwise=otherwise):
                c, c_known = self(condition)
                a, a_known = self(then)
                b, b_known = self(otherwise)
                chosen = c != 0
                return np.where(chosen, a, b), c_known & np.where(chosen, a_known, b_known)
        raise AssertionError(f"a checked condition has no {type(node).__name__}")

    def binary(self, op: str, left: Pair, right: Pair) -> Pair:
        a, a_known = left
        b, b_known = right
        known = a_known & b_known
        with np.errstate(all="ignore"):
            if op in ("==", "enum=="):
                value = a == b
            elif op in ("!=", "enum!="):
                value = a != b
            elif op == "<":
                value = a < b
            elif op == "<=":
                value = a <= b
            elif op == ">":
                value = a > b
            elif op == ">=":
                value = a >= b
            elif op == "+":
                return a + b, known
            elif op == "-":
                return a - b, known
            elif op == "*":
                return a * b, known
            elif op == "/":
                return a / np.where(b != 0, b, ZERO_DIVISOR), known
            elif op == "%":
                x, y = _to_int32(a), _to_int32(b)
                nonzero = y != 0
                return np.fmod(x, np.where(nonzero, y, 1.0)), known & nonzero
            else:  # pragma: no cover - the checker knows no other operator
                raise AssertionError(f"unknown operator {op}")
        return value.astype(np.float64), known

    def logical(self, op: str, operands: list[Pair]) -> Pair:
        deciding = 0.0 if op == "&&" else 1.0  # the value that decides the whole: false for &&, true for ||
        decided = np.zeros(self.n, dtype=np.bool_)
        every = np.ones(self.n, dtype=np.bool_)
        for value, known in operands:
            decided |= known & (value == deciding)
            every &= known
        result = np.where(decided, deciding, 1.0 - deciding)
        return result, decided | every


def evaluate(
    columns: RobotColumns, gen: int, query: CompiledQuery, codes: Codes, decimals: int | None
) -> tuple[Mask, Mask]:
    """Whether the query is true and whether it is known, per tick of ``columns`` (valid in the ticks of ``gen``)."""
    assert query.expression is not None
    value, known = _Evaluator(columns, gen, query, codes, decimals)(query.expression)
    true: Mask = value != 0
    return true, known
