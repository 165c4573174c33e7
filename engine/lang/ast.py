"""The abstract syntax tree of one XABSL 2 source file (§1.3), before any name is resolved.

Nodes mirror the grammar productions; every node carries the :class:`~xabsl_studio.engine.types.Span` of
its source text and, where the grammar allows one, the doc comment in front of it. Names are
kept as written (``@dist``, ``walk``); the checker qualifies and resolves them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TypeAlias

from xabsl_studio.engine.types import Span

# ------------------------------------------------------------------------------ expressions


@dataclass(slots=True)
class Name:
    """An identifier with its span (declarations and references)."""

    text: str
    span: Span


@dataclass(slots=True)
class NumberLit:
    """A decimal literal, with its text as written."""

    text: str
    span: Span


@dataclass(slots=True)
class BoolLit:
    """``true`` or ``false``."""

    value: bool
    span: Span


@dataclass(slots=True)
class Ident:
    """An identifier in an expression: a symbol, constant, parameter or enum element."""

    name: str
    span: Span


@dataclass(slots=True)
class CallArg:
    """One ``name = value`` of a call."""

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
    """``-x`` or ``!x``."""

    op: str
    operand: Expr
    span: Span
    op_span: Span


@dataclass(slots=True)
class BinaryOp:
    """``left op right`` for an arithmetic, comparison or logical operator."""

    op: str
    left: Expr
    right: Expr
    span: Span
    op_span: Span


@dataclass(slots=True)
class CondOp:
    """``condition ? then : otherwise``."""

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
    """``goto state;``."""

    target: Name
    span: Span


@dataclass(slots=True)
class Stay:
    """``stay;``."""

    span: Span


@dataclass(slots=True)
class IfElse:
    """``if (c) then else otherwise``; ``otherwise`` is None in a common decision branch."""

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
    """``symbol = value;``."""

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
    """A parameter declaration of an option (``@name``), basic behavior or input symbol."""

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
    """``[float] const name = [-]value [unit];``."""

    name: Name
    text: str
    negative: bool
    unit: str | None
    span: Span
    doc: str | None = None


@dataclass(slots=True)
class EnumDecl:
    """``enum name [internal] { elements };``."""

    name: Name
    internal: bool
    elements: list[Name]
    span: Span
    doc: str | None = None


@dataclass(slots=True)
class SymbolDecl:
    """An input, output or internal symbol declaration (input symbols may have parameters)."""

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
    """``behavior name { params }``: a basic behavior prototype."""

    name: Name
    params: list[ParamDecl]
    span: Span
    doc: str | None = None


NamespaceItem: TypeAlias = ConstDecl | EnumDecl | SymbolDecl | BehaviorDecl


@dataclass(slots=True)
class Namespace:
    """``namespace name("title") { items }``."""

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
    """One state of an option, as written."""

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
    """``option name { params, common decision and action, states }``, as written."""

    name: Name
    params: list[ParamDecl]
    common_decision: CommonDecision | None
    common_action: list[ActionStmt] | None
    states: list[StateDecl]
    span: Span
    doc: str | None = None


@dataclass(slots=True)
class AgentDecl:
    """``agent name("title", root_option);``."""

    name: Name
    title: str
    root: Name
    span: Span
    doc: str | None = None


@dataclass(slots=True)
class Include:
    """``include "path";``."""

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
