"""Reading an engine for debugging: input values and why a decision chose what it chose (§2.12).

A :class:`Debugger` observes an :class:`~xabsl_studio.engine.runtime.engine.Engine` between ticks: the values
of all input symbols without parameters (:meth:`Debugger.input_values`) and why an option's
decision chose its leaf (:meth:`Debugger.explain`); the activation tree is
``engine.activation()``. Steering (selecting an agent, forcing roots, overriding inputs) belongs
to the engine's :class:`~xabsl_studio.engine.runtime.roots.RootActions` (``engine.root_actions``).

:meth:`Debugger.explain` **re-evaluates** the conditions on the path to the recorded leaf after
the tick, with the option's parameters and the ``state_time``/``option_time`` its decision saw
(both recorded); inputs are read again (overrides included) and ``action_done`` sees the
children's state after the tick, so values may differ from the decision's if the world moved
on. Decisions themselves record only the leaf, to keep ticks cheap.

Every condition also lists its **comparisons with the values of both sides**
(``ball.distance (412.3) < 500``), computed by :func:`evaluate`, a small evaluator of the IR
with the engine's semantics (``/`` by 0 divides by 1e-7, ``%`` truncates) over a :class:`Values`
source: :class:`LiveValues` reads an engine now; a host may pass recorded values instead
(:func:`explain_decision`, what the studio does for a past tick from its ring buffer).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

from xabsl_studio.engine.codegen.layout import default_value
from xabsl_studio.engine.codegen.python import expression_source
from xabsl_studio.engine.codegen.support import MS_MASK, modulo
from xabsl_studio.engine.emit.json import render_expression
from xabsl_studio.engine.errors import DebugError
from xabsl_studio.engine.ir.model import (
    COMPARISON_OPERATORS,
    ENUM_COMPARISON_OPERATORS,
    ActionDone,
    Binary,
    BooleanLiteral,
    Conditional,
    Conflict,
    Constant,
    EnumLiteral,
    Expression,
    If,
    InputRef,
    Logical,
    Number,
    Option,
    OptionTime,
    OutputRef,
    ParameterRef,
    State,
    StateTime,
    Transition,
    Unary,
    leaf_path,
    walk,
)
from xabsl_studio.engine.runtime.engine import Engine
from xabsl_studio.engine.types import Kind, Span, Value

__all__ = [
    "Comparison",
    "Condition",
    "Debugger",
    "Explanation",
    "LiveValues",
    "Unknown",
    "Values",
    "decision_tree",
    "evaluate",
    "explain_decision",
    "render",
    "show_value",
]


class Unknown(DebugError):
    """A value the source cannot give (e.g. ``action_done`` of a recorded tick)."""


class Values(Protocol):
    """Where :func:`evaluate` reads symbols, parameters and times (one option's context)."""

    state_time: float
    option_time: float

    def input(self, name: str, args: Mapping[str, Value]) -> Value:
        """Input symbol ``name`` (``args``: qualified parameter -> value, for parameterized inputs)."""
        ...

    def output(self, name: str) -> Value:
        """Output or internal symbol ``name``."""
        ...

    def parameter(self, name: str) -> Value:
        """The option's parameter ``name`` (qualified)."""
        ...

    def element(self, element: str) -> Value:
        """The value of the qualified enum element ``element`` as this source encodes enums."""
        ...

    def show(self, kind: Kind, enum: str | None, value: Value) -> str:
        """``value`` as text (enum elements by name)."""
        ...

    def special(self, expression: Expression) -> Value:
        """``action_done`` or ``conflict`` (raise :class:`Unknown` when the source cannot tell)."""
        ...


def show_value(value: Value) -> str:
    """A decimal with at most 3 fractional digits, a boolean as ``true``/``false``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        text = f"{value:.3f}".rstrip("0").rstrip(".")
        return "0" if text == "-0" else text
    return str(value)


def evaluate(expression: Expression, values: Values) -> Value:
    """The value of ``expression`` with the engine's semantics, reading ``values``.

    Raises:
        Unknown: a value the source cannot give.
    """
    e = expression
    match e:
        case Number(value=value) | Constant(value=value):
            return float(value)
        case BooleanLiteral(value=value):
            return value
        case EnumLiteral(element=element):
            return values.element(element)
        case ParameterRef(param=param):
            return values.parameter(param)
        case OutputRef(symbol=symbol):
            return values.output(symbol)
        case InputRef(symbol=symbol, args=args):
            return values.input(symbol, {a.param: evaluate(a.value, values) for a in args})
        case StateTime():
            return values.state_time
        case OptionTime():
            return values.option_time
        case ActionDone() | Conflict():
            return values.special(e)
        case Unary(op="-", operand=operand):
            return 0.0 - float(evaluate(operand, values))
        case Unary(op="!", operand=operand):
            return not evaluate(operand, values)
        case Binary(op=op, left=left, right=right):
            a, b = evaluate(left, values), evaluate(right, values)
            return _binary(op, a, b)
        case Logical(op="&&", operands=operands):
            return all(evaluate(o, values) for o in operands)
        case Logical(operands=operands):
            return any(evaluate(o, values) for o in operands)
        case Conditional(condition=c, then=t, otherwise=o):
            return evaluate(t, values) if evaluate(c, values) else evaluate(o, values)
    raise TypeError(f"cannot evaluate {e!r}")


def _binary(op: str, a: Value, b: Value) -> Value:
    if op in ("enum==", "=="):
        return a == b
    if op in ("enum!=", "!="):
        return a != b
    x, y = float(a), float(b)
    if op == "<":
        return x < y
    if op == "<=":
        return x <= y
    if op == ">":
        return x > y
    if op == ">=":
        return x >= y
    if op == "+":
        return x + y
    if op == "-":
        return x - y
    if op == "*":
        return x * y
    if op == "/":
        return x / (y if y != 0 else 1e-07)
    if op == "%":
        return modulo(x, y)
    raise TypeError(f"unknown operator {op}")


_COMPARISONS = frozenset(COMPARISON_OPERATORS) | frozenset(ENUM_COMPARISON_OPERATORS)


@dataclass(frozen=True, slots=True)
class Comparison:
    """One comparison of a condition with the values of its sides (``?`` when unknown)."""

    text: str
    op: str
    left: str
    left_value: str
    right: str
    right_value: str
    value: bool | None

    def __str__(self) -> str:
        left = self.left if self.left_value == self.left else f"{self.left} ({self.left_value})"
        right = self.right if self.right_value == self.right else f"{self.right} ({self.right_value})"
        return f"{left} {self.op} {right}"


def comparisons(condition: Expression, values: Values, text: Callable[[Expression], str]) -> tuple[Comparison, ...]:
    """Every comparison in ``condition`` (pre-order) with its operand values; ``text`` gives an operand's source."""
    found = []
    for node in walk(condition):
        if not isinstance(node, Binary) or node.op not in _COMPARISONS:
            continue
        shown: list[str] = []
        raw: list[Value | None] = []
        for side in (node.left, node.right):
            try:
                value = evaluate(side, values)
                raw.append(value)
                shown.append(values.show(side.kind, side.enum, value))
            except Unknown:
                raw.append(None)
                shown.append("?")
            except (ArithmeticError, DebugError, ValueError, TypeError):
                raw.append(None)
                shown.append("?")
        left, right = raw
        result = None if left is None or right is None else bool(_binary(node.op, left, right))
        found.append(
            Comparison(
                text(node), node.op.removeprefix("enum"), text(node.left), shown[0], text(node.right), shown[1], result
            )
        )
    return tuple(found)


@dataclass(frozen=True, slots=True)
class Condition:
    """One ``if`` on the path to a leaf: its text, its value, the branch the decision took, its comparisons."""

    text: str
    source: str
    #: None: the values do not tell (a recorded tick without the input function or ``action_done``)
    value: Value | None
    branch: bool
    span: Span | None
    comparisons: tuple[Comparison, ...] = field(default=())


@dataclass(frozen=True, slots=True)
class Explanation:
    """Why option ``option`` in state ``decided_in`` took leaf ``leaf`` (to ``target``)."""

    option: str
    decided_in: str
    leaf: int
    target: str
    stay: bool
    conditions: tuple[Condition, ...]

    def __str__(self) -> str:
        lines = [f"{self.option}.{self.decided_in}: leaf {self.leaf} -> {'stay' if self.stay else self.target}"]
        for c in self.conditions:
            lines.append(f"  {'if' if c.branch else 'else of'} ({c.text or c.source}) = {c.value!r}")
            lines.extend(f"    {comparison}" for comparison in c.comparisons)
        return "\n".join(lines)


class LiveValues:
    """An engine's values now, in the context of one option (what :meth:`Debugger.explain` reads)."""

    def __init__(self, engine: Engine, option: Option, state_time: float, option_time: float) -> None:
        self.engine = engine
        self.loaded = engine.loaded
        self.option = option
        self.state_time = state_time
        self.option_time = option_time

    def input(self, name: str, args: Mapping[str, Value]) -> Value:
        """The host's value now (overrides included)."""
        slot = self.loaded.layout.inputs[name]
        read = self.loaded.input_reads[name]
        value: Value = (
            read() if not slot.params else read(*(args.get(p, default_value(kind)) for p, kind in slot.params))
        )
        return value

    def output(self, name: str) -> Value:
        """The symbol's value now."""
        return self.engine.output(name)

    def parameter(self, name: str) -> Value:
        """The option's parameter value now."""
        slot = self.loaded.layout.options[self.option.name]
        position = [p[0] for p in slot.params].index(name)
        return self.loaded.option_params[slot.offset + position]

    def element(self, element: str) -> Value:
        """The host value of the element."""
        return self.loaded.layout.enum_values[element]

    def show(self, kind: Kind, enum: str | None, value: Value) -> str:
        """Enum host values by element name."""
        if kind is Kind.ENUM:
            for name, host in self.loaded.enum_values(enum).elements.items():
                if host == value:
                    return name[len(enum) + 1 :] if enum and name.startswith(enum + ".") else name
            return f"{value}?"
        return show_value(value)

    def special(self, expression: Expression) -> Value:
        """``action_done``/``conflict`` cannot be re-evaluated outside their state's code."""
        raise Unknown("only the decision's own code can evaluate this")


def decision_tree(
    tree: If | Transition,
    leaf: int,
    values: Values | None,
    text: Callable[[If], str],
) -> dict[str, Any]:
    """The decision tree as nested dicts, the path to ``leaf`` marked ``taken``; conditions evaluated."""
    path = {id(node): branch for node, branch in leaf_path(tree, leaf)} if leaf >= 0 else {}

    def visit(node: If | Transition, on_path: bool) -> dict[str, Any]:
        if isinstance(node, Transition):
            return {"leaf": node.leaf, "target": node.target, "stay": node.stay, "taken": on_path and node.leaf == leaf}
        value: Value | None = None
        if values is not None:
            try:
                value = evaluate(node.condition, values)
            except (Unknown, ArithmeticError, DebugError, ValueError, TypeError):
                value = None
        branch = path.get(id(node))
        return {
            "if": text(node),
            "value": value if isinstance(value, bool) else None,
            "taken": on_path,
            "branch": branch,
            "then": visit(node.then, on_path and branch is True),
            "else": visit(node.otherwise, on_path and branch is False),
        }

    return visit(tree, True)


def explain_decision(
    option: Option,
    state: State,
    leaf: int,
    values: Values,
    text: Callable[[Expression], str],
) -> Explanation:
    """Why ``option``'s decision in ``state`` took ``leaf``, with every condition evaluated from ``values``."""
    conditions = []
    for node, branch in leaf_path(state.decision, leaf):
        try:
            value: Value | None = evaluate(node.condition, values)
        except (Unknown, ArithmeticError, DebugError, ValueError, TypeError):
            value = None
        conditions.append(
            Condition(
                node.text,
                text(node.condition),
                value,
                branch,
                node.condition.span,
                comparisons(node.condition, values, text),
            )
        )
    transition = _leaf(state.decision, leaf)
    target = transition.target or state.name
    return Explanation(option.name, state.name, leaf, target, target == state.name, tuple(conditions))


class Debugger:
    """Debug reads of one engine; cheap to create (``Debugger(engine)``)."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine

    # -- reading -----------------------------------------------------------------------------

    def input_values(self) -> dict[str, Value]:
        """The current value of every input symbol without parameters (overrides included)."""
        loaded = self.engine.loaded
        return {
            name: loaded.input_reads[name]()
            for name, symbol in loaded.program.inputs.items()
            if not symbol.params and name in loaded.input_reads
        }

    def explain(self, option: str) -> Explanation:
        """The decision option ``option`` took in the last tick it ran (see module docstring).

        Raises:
            DebugError: unknown option, or it has not decided anything since the last load.
        """
        loaded = self.engine.loaded
        slot = loaded.layout.options.get(option)
        if slot is None:
            raise DebugError(f"unknown option {option}")
        record = loaded.decisions[slot.index]
        if record is None:
            raise DebugError(f"option {option} has not run yet")
        _, leaf, decided = record
        ir_option = loaded.program.options[option]
        state = ir_option.states[decided]
        namespace = {
            "st": loaded.decision_state_time[slot.index],
            "ot": float((self.engine.now - loaded.activated[slot.index]) & MS_MASK),
            "tick": self.engine.tick,
        }
        live = LiveValues(self.engine, ir_option, float(namespace["st"]), float(namespace["ot"]))
        conditions = []
        for node, branch in leaf_path(state.decision, leaf):
            assert isinstance(node, If)
            source = expression_source(loaded.layout, ir_option, state, node.condition)
            value = eval(compile(source, f"<xabsl-explain:{option}>", "eval"), loaded.globals, namespace)
            found = comparisons(node.condition, live, functools.partial(_span_text, node, option))
            conditions.append(Condition(node.text, source, value, branch, node.condition.span, found))
        transition = _leaf(state.decision, leaf)
        target = transition.target or state.name
        return Explanation(option, state.name, leaf, target, target == state.name, tuple(conditions))


def _leaf(tree: If | Transition, leaf: int) -> Transition:
    if isinstance(tree, Transition):
        return tree
    path = leaf_path(tree, leaf)
    node: If | Transition = tree
    for _, branch in path:
        assert isinstance(node, If)
        node = node.then if branch else node.otherwise
    assert isinstance(node, Transition)
    return node


def _span_text(node: If, option: str, expression: Expression) -> str:
    """The source text of a sub-expression of ``node``'s condition, cut from the condition's text.

    ``node.text`` is the condition's source with runs of blanks collapsed; a sub-expression's span
    lies inside the condition's span, so its offsets relative to it cut the same text when the
    condition has no line breaks or double blanks (else the IR is rendered).
    """
    outer, inner = node.condition.span, expression.span
    if outer is None or inner is None or node.text is None or len(node.text) != outer.end - outer.start:
        return render(expression, option)
    return node.text[inner.start - outer.start : inner.end - outer.start]


def render(expression: Expression, option: str = "") -> str:
    """XABSL source for an IR expression (what a condition's operand is shown as without its text).

    ``option`` is the option the expression belongs to: its parameters are written ``@name`` with
    the whole declared name (dots kept). One renderer for the description and the debugger.
    """
    return render_expression(expression, option)
