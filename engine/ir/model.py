"""The intermediate representation (IR): a checked XABSL 2 program as plain, typed, frozen data.

The IR is the hub of the product (architecture: "one IR"). The checker (``xabsl_studio.engine.lang.check``)
builds it from source, ``xabsl_studio.engine.ir.ic_reader`` builds it from intermediate code; the IC, JSON and
DOT emitters, the Python code generator, the reference interpreter and the studio read it.
Nothing downstream re-parses source text.

Conventions:

* Every name is the one the intermediate code uses (§1.4 "qualified domain value names"):
  option parameter ``@x`` of option ``o`` is ``"o.x"``, parameter ``v`` of input symbol ``abs`` is
  ``"abs.v"``, enum element ``e`` of enum ``E`` is ``"E.e"``.
* ``index`` fields are the integer ids the engine uses: an option's position in the IC (options
  sorted by lower-cased name, §3.3), a state's position in its option (declaration order).
* A state's ``decision`` already contains the option's common decision tree in front of the
  state's own tree (§2.4), with every leaf numbered; its ``actions`` start with the common
  action items. The option keeps the original common tree and action for documentation.
* Spans are ``None`` for programs read from intermediate code.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import TypeAlias

from xabsl_studio.engine.types import Kind, Span

# --------------------------------------------------------------------------------------------
# Expressions (§1.3 ``exp``; §3.2 ``dexp``/``bexp``/``eexp``)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Number:
    """A decimal literal, folded with any unary minus in front of it (§3.3)."""

    value: float
    span: Span | None = None
    kind: Kind = Kind.DECIMAL
    enum: str | None = None


@dataclass(frozen=True, slots=True)
class Constant:
    """A reference to a ``const``: inlined by value; ``text`` is the value as written (§3.3)."""

    name: str
    value: float
    text: str
    span: Span | None = None
    kind: Kind = Kind.DECIMAL
    enum: str | None = None


@dataclass(frozen=True, slots=True)
class BooleanLiteral:
    """``true`` or ``false``."""

    value: bool
    span: Span | None = None
    kind: Kind = Kind.BOOLEAN
    enum: str | None = None


@dataclass(frozen=True, slots=True)
class EnumLiteral:
    """An enum element, by qualified name (``"mode.walk"``)."""

    element: str
    enum: str
    span: Span | None = None
    kind: Kind = Kind.ENUM


@dataclass(frozen=True, slots=True)
class Argument:
    """One ``name = value`` of a call: ``param`` is the qualified parameter name."""

    param: str
    kind: Kind
    enum: str | None
    value: Expression
    span: Span | None = None


@dataclass(frozen=True, slots=True)
class InputRef:
    """Reading an input symbol; a parameterized one is called with ``args`` on every read."""

    symbol: str
    kind: Kind
    enum: str | None = None
    args: tuple[Argument, ...] = ()
    span: Span | None = None


@dataclass(frozen=True, slots=True)
class OutputRef:
    """Reading the current value of an output or internal symbol (write-through, §2.2)."""

    symbol: str
    kind: Kind
    enum: str | None = None
    span: Span | None = None


@dataclass(frozen=True, slots=True)
class ParameterRef:
    """Reading a parameter of the option that contains the expression (``@x`` -> ``"o.x"``)."""

    param: str
    kind: Kind
    enum: str | None = None
    span: Span | None = None


@dataclass(frozen=True, slots=True)
class StateTime:
    """``state_time``: ms since the active state of the containing option was entered."""

    span: Span | None = None
    kind: Kind = Kind.DECIMAL
    enum: str | None = None


@dataclass(frozen=True, slots=True)
class OptionTime:
    """``option_time``: ms since the containing option was activated."""

    span: Span | None = None
    kind: Kind = Kind.DECIMAL
    enum: str | None = None


@dataclass(frozen=True, slots=True)
class ActionDone:
    """``action_done``: a subsequent option of the active state sits in a target state (§2.7)."""

    span: Span | None = None
    kind: Kind = Kind.BOOLEAN
    enum: str | None = None


@dataclass(frozen=True, slots=True)
class Conflict:
    """``conflict``: more agents than the capacity execute the active cooperative state (§2.11)."""

    span: Span | None = None
    kind: Kind = Kind.BOOLEAN
    enum: str | None = None


#: Operators of :class:`Unary`.
UNARY_OPERATORS = ("-", "!")
#: Decimal arithmetic operators of :class:`Binary` (decimal result).
ARITHMETIC_OPERATORS = ("+", "-", "*", "/", "%")
#: Decimal comparisons of :class:`Binary` (boolean result).
COMPARISON_OPERATORS = ("<", "<=", ">", ">=", "==", "!=")
#: Enum comparisons of :class:`Binary` (boolean result, both operands of one enumeration).
ENUM_COMPARISON_OPERATORS = ("enum==", "enum!=")


@dataclass(frozen=True, slots=True)
class Unary:
    """``-x`` (decimal, emitted as ``0 - x``) or ``!x`` (boolean)."""

    op: str
    operand: Expression
    kind: Kind
    span: Span | None = None
    enum: str | None = None


@dataclass(frozen=True, slots=True)
class Binary:
    """Arithmetic, decimal comparison or enum comparison (``op`` from the tables above)."""

    op: str
    left: Expression
    right: Expression
    kind: Kind
    span: Span | None = None
    enum: str | None = None


@dataclass(frozen=True, slots=True)
class Logical:
    """n-ary, short-circuit ``&&``/``||`` with nested chains flattened (§2.8, §3.3)."""

    op: str
    operands: tuple[Expression, ...]
    span: Span | None = None
    kind: Kind = Kind.BOOLEAN
    enum: str | None = None


@dataclass(frozen=True, slots=True)
class Conditional:
    """``c ? a : b``: only the chosen branch is evaluated; decimal or enum valued."""

    condition: Expression
    then: Expression
    otherwise: Expression
    kind: Kind
    enum: str | None = None
    span: Span | None = None


Expression: TypeAlias = (
    Number
    | Constant
    | BooleanLiteral
    | EnumLiteral
    | InputRef
    | OutputRef
    | ParameterRef
    | StateTime
    | OptionTime
    | ActionDone
    | Conflict
    | Unary
    | Binary
    | Logical
    | Conditional
)


def children(expression: Expression) -> tuple[Expression, ...]:
    """The direct sub-expressions, in evaluation order (argument values included)."""
    match expression:
        case InputRef(args=args):
            return tuple(a.value for a in args)
        case Unary(operand=operand):
            return (operand,)
        case Binary(left=left, right=right):
            return (left, right)
        case Logical(operands=operands):
            return operands
        case Conditional(condition=c, then=t, otherwise=o):
            return (c, t, o)
        case _:
            return ()


def walk(expression: Expression) -> Iterator[Expression]:
    """All nodes of an expression, pre-order."""
    yield expression
    for child in children(expression):
        yield from walk(child)


# --------------------------------------------------------------------------------------------
# Decision trees and actions
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Transition:
    """A leaf of a decision tree: ``goto target`` or ``stay``.

    In a state's (inlined) decision ``target`` is always a state name and ``leaf`` is the leaf's
    id, unique within that state (pre-order). In an option's original common decision tree a
    ``stay`` has ``target=None`` because it means "the active state".
    """

    target: str | None
    stay: bool = False
    leaf: int = -1
    span: Span | None = None


@dataclass(frozen=True, slots=True)
class If:
    """``if (condition) then else otherwise``; ``text`` is the condition's source text."""

    condition: Expression
    then: DecisionTree
    otherwise: DecisionTree
    text: str = ""
    doc: str | None = None
    else_doc: str | None = None
    span: Span | None = None


DecisionTree: TypeAlias = Transition | If


@dataclass(frozen=True, slots=True)
class CommonBranch:
    """One ``if``/``else if`` branch of an option's common decision tree (kept for docs)."""

    condition: Expression
    tree: DecisionTree
    text: str = ""
    doc: str | None = None
    span: Span | None = None


@dataclass(frozen=True, slots=True)
class OptionCall:
    """A subsequent option: ``name(p = v, ...)``; only the assigned parameters are listed."""

    option: str
    args: tuple[Argument, ...] = ()
    span: Span | None = None


@dataclass(frozen=True, slots=True)
class BehaviorCall:
    """A subsequent basic behavior: ``name(p = v, ...)``."""

    behavior: str
    args: tuple[Argument, ...] = ()
    span: Span | None = None


@dataclass(frozen=True, slots=True)
class Assignment:
    """``symbol = value;`` to an output or internal symbol, written through at once (§2.2)."""

    symbol: str
    kind: Kind
    enum: str | None
    value: Expression
    span: Span | None = None


Action: TypeAlias = OptionCall | BehaviorCall | Assignment


def leaves(tree: DecisionTree) -> Iterator[Transition]:
    """The transitions of a decision tree in pre-order (then-branch before else-branch)."""
    if isinstance(tree, Transition):
        yield tree
    else:
        yield from leaves(tree.then)
        yield from leaves(tree.otherwise)


def leaf_path(tree: DecisionTree, leaf: int) -> list[tuple[If, bool]]:
    """The ``(if, taken_branch)`` chain from the root of ``tree`` to leaf ``leaf``.

    ``taken_branch`` is True for the then-branch. Raises KeyError for an unknown leaf id.
    """
    path: list[tuple[If, bool]] = []

    def visit(node: DecisionTree) -> bool:
        if isinstance(node, Transition):
            return node.leaf == leaf
        path.append((node, True))
        if visit(node.then):
            return True
        path[-1] = (node, False)
        if visit(node.otherwise):
            return True
        path.pop()
        return False

    if not visit(tree):
        raise KeyError(leaf)
    return path


# --------------------------------------------------------------------------------------------
# Declarations
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Enumeration:
    """``enum name [internal] { e1, e2 }``; ``elements`` are qualified (``"name.e1"``)."""

    name: str
    elements: tuple[str, ...]
    internal: bool = False
    doc: str | None = None
    span: Span | None = None


@dataclass(frozen=True, slots=True)
class Parameter:
    """A parameter of an option, a basic behavior or an input symbol (qualified ``name``).

    ``owner`` is the name of the option, basic behavior or input symbol that declares it; the
    qualified name is ``owner + "." + declared name``, and the declared name may itself contain
    dots (``"locator.rel.x.robot.x"`` is parameter ``robot.x`` of ``locator.rel.x``).
    """

    name: str
    kind: Kind
    enum: str | None = None
    range: str | None = None
    unit: str | None = None
    doc: str | None = None
    span: Span | None = None
    owner: str = ""

    @property
    def short_name(self) -> str:
        """The declared name: ``name`` without the owner's prefix, dots kept.

        ``"motion.walk.to.robot.x"`` of owner ``"motion.walk.to"`` -> ``"robot.x"``. Without an
        owner (or with a name not under it) the whole name: never a guess at the last dot.
        """
        return short_name(self.name, self.owner)


def short_name(name: str, owner: str) -> str:
    """``name`` without the prefix ``owner + "."`` (the whole ``name`` if it has no such prefix)."""
    if owner and name.startswith(owner) and name[len(owner) : len(owner) + 1] == ".":
        return name[len(owner) + 1 :]
    return name


@dataclass(frozen=True, slots=True)
class InputSymbol:
    """An input symbol provided by the host; with ``params`` it is a host function."""

    name: str
    kind: Kind
    enum: str | None = None
    params: tuple[Parameter, ...] = ()
    range: str | None = None
    unit: str | None = None
    doc: str | None = None
    namespace: str | None = None
    index: int = 0
    span: Span | None = None


@dataclass(frozen=True, slots=True)
class OutputSymbol:
    """An output symbol (host storage) or, with ``internal``, engine-owned persistent storage."""

    name: str
    kind: Kind
    enum: str | None = None
    internal: bool = False
    range: str | None = None
    unit: str | None = None
    doc: str | None = None
    namespace: str | None = None
    index: int = 0
    span: Span | None = None


@dataclass(frozen=True, slots=True)
class ConstantDecl:
    """``[float] const name = value [unit];`` (``text`` is the value as written, sign included)."""

    name: str
    value: float
    text: str
    unit: str | None = None
    doc: str | None = None
    namespace: str | None = None
    span: Span | None = None


@dataclass(frozen=True, slots=True)
class BasicBehavior:
    """A basic behavior prototype the host implements: ``behavior name { params }``."""

    name: str
    params: tuple[Parameter, ...] = ()
    doc: str | None = None
    namespace: str | None = None
    index: int = 0
    span: Span | None = None


@dataclass(frozen=True, slots=True)
class State:
    """One state of an option, with the common decision tree and common action inlined."""

    name: str
    index: int
    decision: DecisionTree
    actions: tuple[Action, ...]
    initial: bool = False
    target: bool = False
    #: ``"n"`` plain, ``"c"`` capacity, ``"s"`` synchronized (§2.11, §3.2 ``stateKind``).
    coop: str = "n"
    coop_count: int = 0
    #: True when the state wrote its own ``decision { }`` (False: implicit ``stay``).
    has_decision: bool = True
    doc: str | None = None
    span: Span | None = None

    @property
    def subsequent_options(self) -> tuple[str, ...]:
        """Options this state calls, in action order (what ``action_done`` looks at)."""
        return tuple(a.option for a in self.actions if isinstance(a, OptionCall))


@dataclass(frozen=True, slots=True)
class Option:
    """One state machine of the option graph."""

    name: str
    index: int
    params: tuple[Parameter, ...]
    states: tuple[State, ...]
    initial_state: str
    common_decision: tuple[CommonBranch, ...] = ()
    common_action: tuple[Action, ...] = ()
    doc: str | None = None
    file: str | None = None
    span: Span | None = None
    _by_name: dict[str, State] = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self) -> None:
        self._by_name.update((s.name, s) for s in self.states)

    def state(self, name: str) -> State:
        """The state called ``name`` (KeyError if there is none)."""
        return self._by_name[name]


@dataclass(frozen=True, slots=True)
class Agent:
    """``agent name("title", root_option);``."""

    name: str
    title: str
    root: str
    doc: str | None = None
    span: Span | None = None


@dataclass(frozen=True, slots=True)
class Program:
    """A whole checked behavior: every declaration of the include closure.

    Mappings are ordered: ``options`` in IC order (sorted by lower-cased name), enums, symbols,
    constants and basic behaviors in declaration order, ``agents`` in source order.
    """

    title: str
    options: dict[str, Option]
    agents: tuple[Agent, ...]
    enums: dict[str, Enumeration]
    inputs: dict[str, InputSymbol]
    outputs: dict[str, OutputSymbol]
    constants: dict[str, ConstantDecl]
    behaviors: dict[str, BasicBehavior]
    platform: str = ""
    software_environment: str = ""
    files: tuple[str, ...] = ()

    @property
    def internal_enums(self) -> list[Enumeration]:
        """The internal enumerations (engine storage), in declaration order."""
        return [e for e in self.enums.values() if e.internal]

    @property
    def internal_symbols(self) -> list[OutputSymbol]:
        """The internal symbols (engine storage), in declaration order."""
        return [s for s in self.outputs.values() if s.internal]

    def agent(self, name: str) -> Agent:
        """The agent called ``name`` (KeyError if there is none)."""
        for agent in self.agents:
            if agent.name == name:
                return agent
        raise KeyError(name)
