"""IR -> intermediate code (§3): the text the original C++ XabslEngine loads.

The output is byte-identical to the original Ruby compiler's for the same sources: CRLF line
ends, the blank-line layout of ``xabsl.rb``'s ``write_intermediate_code``, options and internal
symbols sorted by lower-cased name (the IR already holds options in that order), Ruby's number
formatting, n-ary ``&``/``|``, inlined common decision trees and common actions, constants as
written, and the trailing space after enum element tokens (§3.3).

Expressions are emitted by one ``match`` over the IR node types (``_expression``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from typing import TypeVar, assert_never

from xabsl_studio.engine import ir
from xabsl_studio.engine.types import Kind

ENDL = "\r\n"
_T = TypeVar("_T")

#: IC letters of decimal operators (division is 'd' because readers treat '/' as a comment).
_ARITHMETIC = {"+": "+", "-": "-", "*": "*", "/": "d", "%": "%"}
#: IC letters of decimal comparisons.
_COMPARISON = {"<": "<", "<=": "l", ">": ">", ">=": "g", "==": "=", "!=": "n"}


def format_number(value: float) -> str:
    """A decimal literal as the Ruby compiler prints it (§3.3).

    Integral values print as integers (``2.0`` -> ``2``, ``-0.0`` -> ``0``, ``1e26`` with all its
    digits); others as Ruby's ``Float#to_s``: shortest round-trip digits, fixed notation for
    decimal exponents -4 < e <= 16, else ``1.0e-05`` style.

    >>> format_number(0.00001), format_number(1234567890123456.8), format_number(2.5)
    ('1.0e-05', '1234567890123456.8', '2.5')
    """
    if math.isinf(value) or math.isnan(value):
        return "Infinity" if value > 0 else "-Infinity" if value < 0 else "NaN"
    if value == int(value):
        return str(int(value))
    import decimal  # here: only non-integral literals need it (an import less at start-up)

    sign = "-" if value < 0 else ""
    digits_tuple = decimal.Decimal(repr(abs(value))).normalize().as_tuple()
    digits = "".join(map(str, digits_tuple.digits))
    exponent = digits_tuple.exponent
    assert isinstance(exponent, int)
    decpt = len(digits) + exponent  # position of the decimal point relative to the digits
    if 0 < decpt <= 16:
        whole = digits[:decpt].ljust(decpt, "0")
        fraction = digits[decpt:] or "0"
        return f"{sign}{whole}.{fraction}"
    if -4 < decpt <= 0:
        return f"{sign}0.{'0' * -decpt}{digits}"
    mantissa = f"{digits[0]}.{digits[1:] or '0'}"
    power = decpt - 1
    return f"{sign}{mantissa}e{'-' if power < 0 else '+'}{abs(power):02d}"


class _Writer:
    """Accumulates lines; every line ends in CRLF."""

    def __init__(self) -> None:
        self.parts: list[str] = []

    def line(self, text: str = "") -> None:
        self.parts.append(text)
        self.parts.append(ENDL)

    def text(self) -> str:
        return "".join(self.parts)


def _arguments(out: _Writer, args: tuple[ir.Argument, ...]) -> None:
    out.line(str(len(args)))
    for arg in args:
        if arg.kind is Kind.ENUM:
            out.line(f"e {arg.enum} {arg.param}")
        else:
            out.line(f"{arg.kind.ic_code} {arg.param}")
        _expression(out, arg.value)


def _input(out: _Writer, e: ir.InputRef) -> None:
    out.line(f"i {e.symbol}")
    _arguments(out, e.args)


def _unary(out: _Writer, e: ir.Unary) -> None:
    out.line(e.op)
    if e.op == "-":
        out.line("v 0")  # the engine has no negation: -x is 0 - x
    _expression(out, e.operand)


def _binary(out: _Writer, e: ir.Binary) -> None:
    if e.op == "enum==":
        out.line("c")
    elif e.op == "enum!=":
        out.line("!")
        out.line("c")
    elif e.op in _ARITHMETIC and e.kind is Kind.DECIMAL:
        out.line(_ARITHMETIC[e.op])
    else:
        out.line(_COMPARISON[e.op])
    _expression(out, e.left)
    _expression(out, e.right)


def _logical(out: _Writer, e: ir.Logical) -> None:
    out.line(f"{'&' if e.op == '&&' else '|'} {len(e.operands)}")
    for operand in e.operands:
        _expression(out, operand)


def _conditional(out: _Writer, e: ir.Conditional) -> None:
    out.line("q")
    _expression(out, e.condition)
    _expression(out, e.then)
    _expression(out, e.otherwise)


def _expression(out: _Writer, e: ir.Expression) -> None:
    match e:
        case ir.InputRef():
            _input(out, e)
        case ir.Binary():
            _binary(out, e)
        case ir.Number():
            out.line(f"v {format_number(e.value)}")
        case ir.ParameterRef():
            out.line(f"p {e.param}")
        case ir.OutputRef():
            out.line(f"o {e.symbol}")
        case ir.EnumLiteral():
            out.line(f"v {e.element} ")
        case ir.Logical():
            _logical(out, e)
        case ir.Unary():
            _unary(out, e)
        case ir.Constant():
            out.line(f"c {e.text}")
        case ir.BooleanLiteral():
            out.line(f"v {'true' if e.value else 'false'}")
        case ir.Conditional():
            _conditional(out, e)
        case ir.StateTime():
            out.line("s")
        case ir.OptionTime() | ir.ActionDone():
            out.line("t")
        case ir.Conflict():
            out.line("x")
        case _:
            assert_never(e)


def _action(out: _Writer, action: ir.Action) -> None:
    if isinstance(action, ir.OptionCall):
        out.line(f"o {action.option}")
        _arguments(out, action.args)
    elif isinstance(action, ir.BehaviorCall):
        out.line(f"a {action.behavior}")
        _arguments(out, action.args)
    else:
        out.line(f"{action.kind.ic_code} {action.symbol}")
        _expression(out, action.value)


def _statement(out: _Writer, tree: ir.DecisionTree) -> None:
    if isinstance(tree, ir.Transition):
        out.line(f"t {tree.target}")
        return
    out.line("i")
    _expression(out, tree.condition)
    _statement(out, tree.then)
    _statement(out, tree.otherwise)


def _parameter(param: ir.Parameter) -> str:
    if param.kind is Kind.ENUM:
        return f"e {param.enum} {param.name}"
    return f"{param.kind.ic_code} {param.name}"


def _sorted(items: Iterable[_T], key: Callable[[_T], str]) -> list[_T]:
    # by lower-cased name as the original; ties by exact name so that file order cannot matter
    return sorted(items, key=lambda item: (key(item).lower(), key(item)))


def emit_ic(program: ir.Program) -> str:
    """The intermediate code of a checked program, as text with CRLF line ends."""
    out = _Writer()
    out.line(f"// Intermediate code for the agents of {program.title}")
    out.line()

    enums = _sorted(program.internal_enums, lambda e: e.name)
    out.line(str(len(enums)))
    for enum in enums:
        out.line(" ".join([enum.name, str(len(enum.elements)), *enum.elements]))

    symbols = _sorted(program.internal_symbols, lambda s: s.name)
    out.line(str(len(symbols)))
    for symbol in symbols:
        if symbol.kind is Kind.ENUM:
            out.line(f"e {symbol.enum} {symbol.name}")
        else:
            out.line(f"{symbol.kind.ic_code} {symbol.name}")
    out.line()

    options = list(program.options.values())
    out.line(str(len(options)))
    for option in options:
        out.line(" ".join([option.name, str(len(option.params)), *map(_parameter, option.params)]))
    out.line()

    for option in options:
        out.line(str(len(option.states)))
        for state in option.states:
            kind = state.coop if state.coop == "n" else f"{state.coop} {state.coop_count}"
            out.line(f"{state.name} {kind}")
        out.line()
        out.line(option.initial_state)
        for state in option.states:
            out.line("1" if state.target else "0")
            out.line(str(len(state.actions)))
            for action in state.actions:
                _action(out, action)
            _statement(out, state.decision)
        out.line()
        out.line()
        out.line()

    out.line(str(len(program.agents)))
    out.line(" ".join(f"{a.name} {a.root}" for a in program.agents))
    return out.text()
