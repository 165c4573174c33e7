"""A boolean XABSL expression on its own, checked against a compiled program's symbols.

What a breakpoint's condition is (``ball.distance < 300 && robot.role == role.striker``): one
expression, parsed by the XABSL parser and checked by the same checker as an option's
conditions (:class:`xabsl_studio.engine.lang.check.OptionChecker`), against the symbols, constants and
enumerations of a checked :class:`xabsl_studio.engine.ir.Program`. It belongs to no option, so option
parameters, ``state_time``, ``option_time``, ``action_done`` and ``conflict`` have no meaning in it
and are refused. Diagnostics name the file ``<condition>`` with line and column *in the
expression's text* (1-based), like a source file's.

The expression is parsed inside a one-state option wrapped around it (the parser's public entry
point reads whole files); spans are mapped back into the expression's text.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

from xabsl_studio.engine import ir
from xabsl_studio.engine.lang import ast
from xabsl_studio.engine.lang.check import OptionChecker
from xabsl_studio.engine.lang.diagnostics import Diagnostic, Diagnostics
from xabsl_studio.engine.lang.parser import parse_file
from xabsl_studio.engine.lang.symbols import OptionHeader, SymbolTable
from xabsl_studio.engine.lang.tokens import TokenType, tokenize
from xabsl_studio.engine.types import Kind, Span

__all__ = ["CONDITION_FILE", "CheckedCondition", "check_condition"]

#: The file name of a condition's diagnostics and spans.
CONDITION_FILE = "<condition>"
#: Longest condition text accepted (a condition is one expression, not a file).
MAX_CONDITION = 2000

_PREFIX = "option breakpoint_condition { initial state s { decision { if (\n"
_SUFFIX = "\n) stay; else stay; } action { } } }\n"
_NOT_HERE = {
    ir.StateTime: "state_time",
    ir.OptionTime: "option_time",
    ir.ActionDone: "action_done",
    ir.Conflict: "conflict",
}


@dataclass(frozen=True)
class CheckedCondition:
    """A checked condition: its IR (None when there are errors) and the diagnostics."""

    text: str
    expression: ir.Expression | None
    diagnostics: list[Diagnostic] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when the condition can be evaluated (no errors)."""
        return self.expression is not None

    def message(self) -> str:
        """The errors as one line each, ``line:col: message``."""
        return "; ".join(
            f"{d.span.line}:{d.span.col}: {d.message}" if d.span else d.message for d in self.diagnostics if d.is_error
        )


def _table(program: ir.Program) -> SymbolTable:
    """The symbol table of a checked program (what the checker resolves names in)."""
    elements = {element: enum.name for enum in program.enums.values() for element in enum.elements}
    return SymbolTable(
        enums=dict(program.enums),
        elements=elements,
        inputs=dict(program.inputs),
        outputs=dict(program.outputs),
        constants=dict(program.constants),
        behaviors=dict(program.behaviors),
    )


def check_condition(program: ir.Program, text: str) -> CheckedCondition:
    """Parse and check ``text`` as a boolean expression over ``program``'s symbols."""
    diagnostics = Diagnostics()
    if not text.strip():
        diagnostics.add("syntax-error", "the condition is empty; expected an expression", _span(text, 0, 0))
        return CheckedCondition(text, None, diagnostics.sorted())
    if len(text) > MAX_CONDITION:
        diagnostics.add(
            "syntax-error", f"the condition is longer than {MAX_CONDITION} characters", _span(text, 0, len(text))
        )
        return CheckedCondition(text, None, diagnostics.sorted())
    unmatched = _unmatched_paren(text)
    if unmatched is not None:
        # the wrapper's own ')' would close the text's extra one and blame the end of the text
        diagnostics.add("syntax-error", "syntax error: unexpected ')': no '(' to close", unmatched)
        return CheckedCondition(text, None, diagnostics.sorted())
    wrapped = _PREFIX + text + _SUFFIX
    parsed = Diagnostics()
    source = parse_file(CONDITION_FILE, wrapped, parsed)
    decision = _condition_node(source)
    for d in parsed:
        diagnostics.items.append(_moved(d, text))
    if diagnostics.errors or decision is None or source.option is None:
        if not diagnostics.errors:
            diagnostics.add("syntax-error", "expected one expression", _span(text, 0, len(text)))
        return CheckedCondition(text, None, diagnostics.sorted())
    header = OptionHeader(source.option, ast.SourceFile(CONDITION_FILE, wrapped))
    checked = Diagnostics()
    expression = OptionChecker(_table(program), header, checked, set()).expression(decision)
    for d in checked:
        diagnostics.items.append(_moved(d, text))
    if expression is not None:
        for node in ir.walk(expression):
            name = _NOT_HERE.get(type(node))
            if name is not None:
                diagnostics.add(
                    "no-matching-symbol",
                    f"'{name}' belongs to an option's state and has no meaning in a condition over symbols",
                    _moved_span(node.span, text) if node.span else _span(text, 0, len(text)),
                )
        if expression.kind is not Kind.BOOLEAN and not diagnostics.errors:
            kind = f"enum '{expression.enum}'" if expression.kind is Kind.ENUM else expression.kind.value
            diagnostics.add("type-mismatch", f"a condition must be boolean, found {kind}", _span(text, 0, len(text)))
    if diagnostics.errors:
        expression = None
    elif expression is not None:
        expression = _rebase(expression, text)
    return CheckedCondition(text, expression, diagnostics.sorted())


def _unmatched_paren(text: str) -> Span | None:
    """The span of the first ')' of ``text`` that closes no '(' (None: there is none)."""
    depth = 0
    for token in tokenize(text, CONDITION_FILE, Diagnostics()):
        if token.type is not TokenType.OPERATOR:
            continue
        if token.text == "(":
            depth += 1
        elif token.text == ")":
            depth -= 1
            if depth < 0:
                return token.span
    return None


def _condition_node(source: ast.SourceFile) -> ast.Expr | None:
    option = source.option
    if option is None or len(option.states) != 1:
        return None
    tree = option.states[0].decision
    return tree.condition if isinstance(tree, ast.IfElse) else None


def _span(text: str, start: int, end: int) -> Span:
    """The span of ``text[start:end]`` with 1-based line and column."""
    start = max(0, min(start, len(text)))
    end = max(start, min(end, len(text)))
    line = text.count("\n", 0, start) + 1
    col = start - (text.rfind("\n", 0, start) + 1) + 1
    end_line = text.count("\n", 0, end) + 1
    end_col = end - (text.rfind("\n", 0, end) + 1) + 1
    return Span(CONDITION_FILE, line, col, end_line, end_col, start, end)


def _moved_span(span: Span, text: str) -> Span:
    """A span of the wrapped file as a span of the condition's text (clamped to it)."""
    offset = len(_PREFIX)
    return _span(text, span.start - offset, span.end - offset)


def _moved(diagnostic: Diagnostic, text: str) -> Diagnostic:
    span = _moved_span(diagnostic.span, text) if diagnostic.span is not None else None
    message = diagnostic.message.replace("end of file", "end of the condition")
    if diagnostic.span is not None and diagnostic.span.start - len(_PREFIX) >= len(text):
        # the wrapper's own tokens after the text: the condition ended too early or has extra text
        message = message.replace("unexpected ')'", "unexpected end of the condition")
    return Diagnostic(diagnostic.severity, diagnostic.code, message, span, CONDITION_FILE, ())


def _rebase(expression: ir.Expression, text: str) -> ir.Expression:
    """``expression`` with every span moved into the condition's text (for operand display)."""

    def visit(node: ir.Expression) -> ir.Expression:
        changes: dict[str, Any] = {}
        if node.span is not None:
            changes["span"] = _moved_span(node.span, text)
        for f in dataclasses.fields(node):
            value = getattr(node, f.name)
            if f.name in ("left", "right", "operand", "condition", "then", "otherwise"):
                changes[f.name] = visit(value)
            elif f.name == "operands":
                changes[f.name] = tuple(visit(v) for v in value)
            elif f.name == "args":
                changes[f.name] = tuple(
                    dataclasses.replace(a, value=visit(a.value), span=_moved_span(a.span, text) if a.span else None)
                    for a in value
                )
        return dataclasses.replace(node, **changes)

    return visit(expression)
