"""Reading an engine for debugging: input values and why a decision chose what it chose (§2.12).

A :class:`Debugger` observes an :class:`~xabsl_studio.engine.runtime.engine.Engine` between ticks: the values
of all input symbols without parameters (:meth:`Debugger.input_values`) and why an option's
decision chose its leaf (:meth:`Debugger.explain`); the activation tree is
``engine.activation()``. Steering (selecting an agent, forcing roots, overriding inputs) belongs
to the engine's :class:`~xabsl_studio.engine.runtime.roots.RootActions` (``engine.root_actions``).

"Why" is computed from **the values the decision saw**, never from the host asked again: with
``Engine.record_reads`` on, every decision records what it read (inputs, input function calls
with their arguments and results, outputs, parameters, ``state_time``, ``option_time``,
``action_done``; ``Engine.reads()``), and :meth:`Debugger.explain` walks the decision tree to
the recorded leaf evaluating each condition from those reads (:class:`ReadValues`). A value the
decision did not read is unknown (None, ``?``). The same reads, carried in the studio's samples
and in recordings, explain any past tick and any tick of a replay exactly
(:func:`decision_reads` picks one decision's part of a tick's reads).

Every condition also lists its **comparisons with the values of both sides**
(``ball.distance (412.3) < 500``), computed by :func:`evaluate`, a small evaluator of the IR
with the engine's semantics (``/`` by 0 divides by 1e-7, ``%`` truncates, short-circuit ``&&``
and ``||``, so it asks for exactly the values the engine read) over a :class:`Values` source
(:func:`explain_decision`).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

from xabsl_studio.engine.codegen.layout import default_value
from xabsl_studio.engine.codegen.support import modulo
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
    Program,
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
    "ReadValues",
    "Unknown",
    "Values",
    "comparisons",
    "decision_reads",
    "decision_tree",
    "evaluate",
    "explain_decision",
    "render",
    "show_value",
    "span_text",
]


class Unknown(DebugError):
    """A value the source cannot give (e.g. ``action_done`` of a recorded tick)."""


class Values(Protocol):
    """Where :func:`evaluate` reads symbols, parameters and times (one option's context)."""

    @property
    def state_time(self) -> float:
        """The decided-in state's ``state_time`` (raise :class:`Unknown` when the source cannot tell)."""
        ...

    @property
    def option_time(self) -> float:
        """The option's ``option_time``."""
        ...

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
            given = {a.param: evaluate(a.value, values) for a in args}
            if any(isinstance(n, InputRef) and n.symbol == symbol for a in args for n in walk(a.value)):
                # §2.5: a call of the same function inside the arguments may overwrite arguments
                # already set in its shared parameter storage, so the call's own arguments may
                # not be these: which call of the decision's reads it was is unknown.
                raise Unknown(f"{symbol} is called inside its own arguments")
            return values.input(symbol, given)
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


@dataclass(frozen=True, slots=True, kw_only=True)
class Comparison:
    """One comparison of a condition with the values of its sides (``?`` when unknown).

    Also the wire shape of the studio's ``explain`` result (``server.protocol.replies`` names
    this class), so it carries ``shown``, the text the studio prints: ``ball.distance (412.3) < 500``.
    """

    text: str
    op: str
    left: str
    left_value: str
    right: str
    right_value: str
    value: bool | None
    shown: str

    def __str__(self) -> str:
        return self.shown


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
        op, left_text, right_text = node.op.removeprefix("enum"), text(node.left), text(node.right)
        found.append(
            Comparison(
                text=text(node),
                op=op,
                left=left_text,
                left_value=shown[0],
                right=right_text,
                right_value=shown[1],
                value=result,
                # an operand whose value is its own text (a literal) is not repeated
                shown=" ".join(
                    (
                        left_text if shown[0] == left_text else f"{left_text} ({shown[0]})",
                        op,
                        right_text if shown[1] == right_text else f"{right_text} ({shown[1]})",
                    )
                ),
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


class _Clash:
    """Two reads of one key in one decision with different values: neither is the value."""


_CLASH = _Clash()


def decision_reads(reads: Sequence[Any], option: int) -> list[Sequence[Any]] | None:
    """The reads of option ``option``'s (IR id) last decision in ``reads`` (``Engine.reads()``).

    None when the option did not decide in that tick (or decided nothing that needed a read).
    A list from JSON works as well as the engine's tuple: ids are integers, reads arrays.
    """
    found: list[Sequence[Any]] | None = None
    current: list[Sequence[Any]] | None = None
    for entry in reads:
        if isinstance(entry, int) and not isinstance(entry, bool):
            current = [] if entry == option else None
            if current is not None:
                found = current
        elif current is not None and isinstance(entry, list | tuple) and entry:
            current.append(entry)
    return found


class ReadValues:
    """What one decision read in one tick, as :class:`Values` for :func:`explain_decision`.

    ``reads`` is the option's part of a tick's reads (:func:`decision_reads`); values are raw
    (enums as host values, named by ``enums``: enum name -> host value -> qualified element).
    Nothing is asked of a host: a value the decision did not read (an operand its condition
    short-circuited, a condition off the path) is :class:`Unknown`, and so is a key read twice
    with different values. ``ReadValues(program, option, None, enums)`` knows nothing.

    Reads name symbols by the ids of the program the engine ran (its description's ids);
    ``input_ids``/``output_ids`` give them by name when ``program`` numbers its symbols
    otherwise (a program rebuilt from intermediate code numbers inputs in the order the IC lists them).
    """

    def __init__(
        self,
        program: Program,
        option: Option,
        reads: Sequence[Sequence[Any]] | None,
        enums: Mapping[str, Mapping[int, str]],
        input_ids: Mapping[str, int] | None = None,
        output_ids: Mapping[str, int] | None = None,
    ) -> None:
        self.program = program
        self.option = option
        self.enums = enums
        self._inputs = input_ids if input_ids is not None else {n: s.index for n, s in program.inputs.items()}
        self._outputs = output_ids if output_ids is not None else {n: s.index for n, s in program.outputs.items()}
        self._elements = {element: host for table in enums.values() for host, element in table.items()}
        found: dict[tuple[Any, ...], Any] = {}
        for read in reads or ():
            key, value = tuple(read[:-1]), read[-1]
            known = found.get(key, value)
            found[key] = value if known is value or known == value else _CLASH
        self._found = found

    def _get(self, key: tuple[Any, ...], what: str) -> Value:
        value = self._found.get(key)
        if value is None or value is _CLASH:
            why = "the decision did not read" if value is None else "the decision read different values of"
            raise Unknown(f"{why} {what}")
        result: Value = value
        return result

    @property
    def state_time(self) -> float:
        """The decided-in state's time as the decision read it."""
        return float(self._get(("st",), "state_time"))

    @property
    def option_time(self) -> float:
        """The option's time as the decision read it."""
        return float(self._get(("ot",), "option_time"))

    def input(self, name: str, args: Mapping[str, Value]) -> Value:
        """The value the decision read (an input function: the call with these arguments)."""
        symbol = self.program.inputs[name]
        values = [args.get(p.name, default_value(p.kind)) for p in symbol.params]
        if name not in self._inputs:
            raise Unknown(f"{name} is not an input of the recorded program")
        return self._get((self._inputs[name], *values), name)

    def output(self, name: str) -> Value:
        """The symbol's value as the decision read it."""
        if name not in self._outputs:
            raise Unknown(f"{name} is not an output of the recorded program")
        return self._get((-1 - self._outputs[name],), name)

    def parameter(self, name: str) -> Value:
        """The option's parameter as the decision read it."""
        names = [p.name for p in self.option.params]
        if name not in names:
            raise Unknown(f"{self.option.name} has no parameter {name}")
        return self._get(("p", names.index(name)), f"@{name}")

    def element(self, element: str) -> Value:
        """The host value of the element."""
        if element not in self._elements:
            raise Unknown(f"the host gives {element} no value")
        return self._elements[element]

    def show(self, kind: Kind, enum: str | None, value: Value) -> str:
        """Enum host values by element name (without the enumeration's prefix)."""
        if kind is Kind.ENUM:
            element = self.enums.get(enum or "", {}).get(int(value))
            if element is None:
                return f"{value}?"
            return element.removeprefix(f"{enum}.")  # dots inside an element stay
        return show_value(value)

    def special(self, expression: Expression) -> Value:
        """``action_done`` or ``conflict`` as the decision read it."""
        if isinstance(expression, ActionDone):
            return self._get(("done",), "action_done")
        return self._get(("conflict",), "conflict")


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
    text: Callable[[Expression], str] | None = None,
) -> Explanation:
    """Why ``option``'s decision in ``state`` took ``leaf``, with every condition evaluated from ``values``.

    ``text`` gives an operand's source; by default it is cut from the condition's source text
    where the program has it, else the IR is rendered.
    """
    conditions = []
    for node, branch in leaf_path(state.decision, leaf):
        try:
            value: Value | None = evaluate(node.condition, values)
        except (Unknown, ArithmeticError, DebugError, ValueError, TypeError):
            value = None
        cut = text if text is not None else functools.partial(span_text, node, option.name)
        conditions.append(
            Condition(
                node.text,
                cut(node.condition),
                value,
                branch,
                node.condition.span,
                comparisons(node.condition, values, cut),
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
        """The decision option ``option`` took in the last tick it ran, from what it read then.

        With ``engine.record_reads`` on, every value is the one the decision read in that tick
        (:class:`ReadValues`); otherwise, or when the option did not decide in the last tick,
        the values are unknown (None; ``?`` in comparisons): never the host asked again.

        Raises:
            DebugError: unknown option, or it has not decided anything since the last load.
        """
        ir_option, state, leaf, values = self.last_decision(option)
        return explain_decision(ir_option, state, leaf, values)

    def last_decision(self, option: str) -> tuple[Option, State, int, ReadValues]:
        """The last decision of option ``option``: its state, leaf and the values it read (for "why" and "why not").

        The values are those read in the last tick, unknown when the decision did not run in it
        (see :meth:`explain`).

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
        # The record of the last decision; its reads only if that decision ran in the last tick.
        ran = loaded.last_tick[slot.index] == self.engine.tick
        reads = decision_reads(self.engine.reads(), ir_option.index) if ran else None
        values = ReadValues(loaded.program, ir_option, reads, self._enums(loaded.program))
        return ir_option, state, leaf, values

    def _enums(self, program: Program) -> dict[str, dict[int, str]]:
        loaded = self.engine.loaded
        tables: dict[str, dict[int, str]] = {}
        for name in program.enums:
            table: dict[int, str] = {}
            for element, host in loaded.enum_values(name).elements.items():
                table.setdefault(int(host), element)
            tables[name] = table
        return tables


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


def span_text(node: If, option: str, expression: Expression) -> str:
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
