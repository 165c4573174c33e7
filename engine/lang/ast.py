"""The abstract syntax tree of one XABSL 2 source file (§1.3), before any name is resolved.

Nodes mirror the grammar productions; every node carries the :class:`~engine.types.Span` of
its source text and, where the grammar allows one, the doc comment in front of it. Names are
kept as written (``@dist``, ``walk``); the checker qualifies and resolves them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TypeAlias

from engine.types import Span

# ------------------------------------------------------------------------------ expressions


@dataclass(slots=True)
class Name:
    """An identifier with its span (declarations and references)."""

    text: str
    span: Span


@dataclass(slots=True)
class NumberLit:
    text: str
    span: Span


@dataclass(slots=True)
class BoolLit:
    value: bool
    span: Span


@dataclass(slots=True)
class Ident:
    """An identifier in an expression: a symbol, constant, parameter or enum element."""

    name: str
    span: Span


@dataclass(slots=True)
class CallArg:
    name: Name
    value: Expr
    span: Span


@dataclass(slots=True)
class Call:
    """``name(p = v, ...)`` in an expression: a parameterized input symbol."""

    name: Name
    args: list[CallArg]
    span: Span


@dataclass(slots=True)
class Builtin:
    """``state_time``, ``option_time``, ``action_done`` or ``conflict``."""

    name: str
    span: Span


@dataclass(slots=True)
class UnaryOp:
    op: str
    operand: Expr
    span: Span
    op_span: Span


@dataclass(slots=True)
class BinaryOp:
    op: str
    left: Expr
    right: Expr
    span: Span
    op_span: Span


@dataclass(slots=True)
class CondOp:
    condition: Expr
    then: Expr
    otherwise: Expr
    span: Span
    op_span: Span


@dataclass(slots=True)
class Paren:
    """``( e )``: kept so spans and the ``&&`` flattening through parentheses are exact."""

    inner: Expr
    span: Span


Expr: TypeAlias = NumberLit | BoolLit | Ident | Call | Builtin | UnaryOp | BinaryOp | CondOp | Paren

# ------------------------------------------------------------------------------ decisions


@dataclass(slots=True)
class Goto:
    target: Name
    span: Span


@dataclass(slots=True)
class Stay:
    span: Span


@dataclass(slots=True)
class IfElse:
    condition: Expr
    then: DTree
    otherwise: DTree | None
    span: Span
    doc: str | None = None
    else_doc: str | None = None


DTree: TypeAlias = Goto | Stay | IfElse

# ------------------------------------------------------------------------------ actions


@dataclass(slots=True)
class Assign:
    target: Name
    value: Expr
    span: Span


@dataclass(slots=True)
class CallAction:
    """``name [option|behavior] (p = v, ...);`` calling a subsequent option or basic behavior."""

    name: Name
    args: list[CallArg]
    span: Span
    explicit: str | None = None


ActionStmt: TypeAlias = Assign | CallAction

# ------------------------------------------------------------------------------ declarations


@dataclass(slots=True)
class TypeRef:
    """``float``, ``bool``, ``enum name`` or nothing (decimal)."""

    kind: str
    enum: Name | None
    span: Span | None


@dataclass(slots=True)
class ParamDecl:
    type: TypeRef
    name: Name
    range: str | None
    unit: str | None
    span: Span
    doc: str | None = None
    range_span: Span | None = None
    unit_span: Span | None = None


@dataclass(slots=True)
class ConstDecl:
    name: Name
    text: str
    negative: bool
    unit: str | None
    span: Span
    doc: str | None = None


@dataclass(slots=True)
class EnumDecl:
    name: Name
    internal: bool
    elements: list[Name]
    span: Span
    doc: str | None = None


@dataclass(slots=True)
class SymbolDecl:
    type: TypeRef
    io: str
    name: Name
    range: str | None
    unit: str | None
    params: list[ParamDecl] | None
    span: Span
    doc: str | None = None
    range_span: Span | None = None
    unit_span: Span | None = None


@dataclass(slots=True)
class BehaviorDecl:
    name: Name
    params: list[ParamDecl]
    span: Span
    doc: str | None = None


NamespaceItem: TypeAlias = ConstDecl | EnumDecl | SymbolDecl | BehaviorDecl


@dataclass(slots=True)
class Namespace:
    name: Name
    title: str
    items: list[NamespaceItem]
    span: Span
    doc: str | None = None


@dataclass(slots=True)
class CommonDecision:
    """The ``if``/``else if`` chain of a common decision tree, without a final ``else``."""

    branches: list[IfElse]
    span: Span


@dataclass(slots=True)
class StateDecl:
    name: Name
    initial: bool
    target: bool
    coop: str
    coop_count: int
    decision: DTree | None
    leading_else: bool
    decision_span: Span | None
    actions: list[ActionStmt]
    span: Span
    coop_count_given: bool = False


@dataclass(slots=True)
class OptionDecl:
    name: Name
    params: list[ParamDecl]
    common_decision: CommonDecision | None
    common_action: list[ActionStmt] | None
    states: list[StateDecl]
    span: Span
    doc: str | None = None


@dataclass(slots=True)
class AgentDecl:
    name: Name
    title: str
    root: Name
    span: Span
    doc: str | None = None


@dataclass(slots=True)
class Include:
    path: str
    span: Span


@dataclass(slots=True)
class SourceFile:
    """One parsed file: includes, then exactly one of namespace / option / agents (or nothing)."""

    path: str
    text: str
    title_comment: str | None = None
    includes: list[Include] = field(default_factory=list)
    namespace: Namespace | None = None
    option: OptionDecl | None = None
    agents: list[AgentDecl] = field(default_factory=list)
