"""The small, safe arithmetic language of Dual Dynamics model files (doc §1.5, §4.1).

This module owns parsing, validating and compiling the expressions a DD model writes as strings:
activation drives (``"0.9*ν_a + 0.3*α_approach_a - 1.2*f"``), target dynamics
(``"0.8*(1 - abs(φ_a))**2 * (1 - 1.5*o_max)"``), helpers and slow-variable rates. Model files are
data that users edit in the studio, so they are never handed to ``eval``: this module parses them
into its own tree, checks every name and function against what the model declares, and emits
Python source from that tree only (in the manner of sqlglot's executor and our codegen), which
the model compiles once.

Grammar (precedence low to high; comparisons yield 1.0 or 0.0, like the Iverson brackets of §1.5)::

    expr   := sum [('<' | '<=' | '>' | '>=' | '==' | '!=') sum]
    sum    := prod (('+' | '-') prod)*
    prod   := unary (('*' | '/') unary)*
    unary  := ('-' | '+') unary | power
    power  := atom ['**' unary]
    atom   := NUMBER | NAME | NAME '(' expr (',' expr)* ')' | '(' expr ')'

Names are Unicode identifiers (``φ_a``, ``γ_book``, ``α_roam``). Functions: see :data:`FUNCTIONS`.
Numbers are finite doubles. A tree deeper than :data:`MAX_DEPTH` (nested parentheses, a chain of
thousands of ``+``) is refused at the column where it gets too deep, so every later walk over the
tree, and the Python source it compiles to, stay well inside the interpreter's limits.

:func:`linear_terms` splits an expression into bias, activation and "feature" terms; the model
uses it to turn each drive into a row of the vectorised form T = S(k·(B@s + W@α − θ)) of §4.1.
"""

from __future__ import annotations

import math
import re
import reprlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from xabsl_studio.engine.errors import DynamicsError

#: The deepest expression tree accepted (a real drive or target is under 10 levels deep). The
#: generated Python nests one parenthesis per level, and CPython's parser stops at 200.
MAX_DEPTH = 64

#: Function name -> (minimum arity, maximum arity or None for variadic, Python spelling).
FUNCTIONS: Mapping[str, tuple[int, int | None, str]] = {
    "max": (1, None, "_max"),
    "min": (1, None, "_min"),
    "abs": (1, 1, "_abs"),
    "clip": (3, 3, "_clip"),
    "sqrt": (1, 1, "_sqrt"),
    "exp": (1, 1, "_exp"),
    "tanh": (1, 1, "_tanh"),
    "sigmoid": (1, 1, "_sigmoid"),
    "where": (3, 3, "_where"),
    "sign": (1, 1, "_sign"),
}


def _sigmoid(x: float) -> float:
    # Split by sign so exp never overflows for steep drives.
    if x >= 0.0:
        return 1.0 / (1.0 + math.exp(-x))
    e = math.exp(x)
    return e / (1.0 + e)


def _clip(x: float, lo: float, hi: float) -> float:
    return lo if x < lo else hi if x > hi else x


def _sqrt(x: float) -> float:
    return math.sqrt(x) if x > 0.0 else 0.0  # a model must not crash the tick on -1e-17


def _div(a: float, b: float) -> float:
    # A model dividing by a sensor that reads exactly 0 gets inf/nan, not a crashed tick.
    return a / b if b != 0.0 else (math.copysign(math.inf, a) if a else math.nan)


def _pow(a: float, b: float) -> float:
    try:
        r = a**b
    except (OverflowError, ZeroDivisionError):
        return math.inf
    return r if isinstance(r, float) else float(r) if not isinstance(r, complex) else math.nan


#: The only globals generated code sees; ``__builtins__`` is emptied on purpose.
RUNTIME: Mapping[str, object] = {
    "__builtins__": {},
    "_max": max,
    "_min": min,
    "_abs": abs,
    "_clip": _clip,
    "_sqrt": _sqrt,
    "_exp": lambda x: math.exp(min(x, 700.0)),
    "_tanh": math.tanh,
    "_sigmoid": _sigmoid,
    "_where": lambda c, a, b: a if c != 0.0 else b,
    "_sign": lambda x: (x > 0.0) - (x < 0.0),
    "_div": _div,
    "_pow": _pow,
}


class ExprError(DynamicsError, ValueError):
    """A malformed expression or an unknown name; the message shows the text and a caret."""

    def __init__(self, message: str, text: str, col: int | None = None) -> None:
        self.text = text
        self.col = col
        self.reason = message
        where = f" at column {col + 1}" if col is not None else ""
        shown, at = _window(text, col if col is not None else 0)
        caret = f"\n    {shown}\n    {' ' * at}^" if col is not None else f"\n    {shown}"
        super().__init__(f"{message}{where}{caret}")


def _window(text: str, col: int, width: int = 50) -> tuple[str, int]:
    """At most ``width`` characters of ``text`` either side of ``col``, and col's place in them."""
    start = max(0, col - width)
    shown = text[start : col + width]
    prefix = "..." if start > 0 else ""
    suffix = "..." if col + width < len(text) else ""
    return prefix + shown + suffix, len(prefix) + col - start


# --- tree ----------------------------------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Num:
    """A numeric literal."""

    value: float
    col: int = 0


@dataclass(frozen=True, slots=True)
class Name:
    """A reference to a sensor, parameter, helper, slow variable, activation or let binding."""

    id: str
    col: int = 0


@dataclass(frozen=True, slots=True)
class Unary:
    """``-x`` (unary plus is dropped by the parser)."""

    op: str
    operand: Node
    col: int = 0


@dataclass(frozen=True, slots=True)
class Binary:
    """An arithmetic operator or a comparison."""

    op: str
    left: Node
    right: Node
    col: int = 0


@dataclass(frozen=True, slots=True)
class Call:
    """A call of one of the :data:`FUNCTIONS`."""

    fn: str
    args: tuple[Node, ...]
    col: int = 0


Node = Num | Name | Unary | Binary | Call

_COMPARE = ("<=", ">=", "==", "!=", "<", ">")
_TOKEN = re.compile(
    r"\s*(?:(?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)|(?P<name>[^\W\d]\w*)"
    r"|(?P<op>\*\*|<=|>=|==|!=|[-+*/(),<>]))"
)


def _tokenize(text: str) -> list[tuple[str, str, int]]:
    out: list[tuple[str, str, int]] = []
    pos = 0
    while pos < len(text):
        if text[pos:].strip() == "":
            break
        m = _TOKEN.match(text, pos)
        if m is None:
            col = pos + (len(text[pos:]) - len(text[pos:].lstrip()))
            raise ExprError(f"unexpected character {text[col]!r}", text, col)
        kind = m.lastgroup or ""
        out.append((kind, m.group(kind), m.start(kind)))
        pos = m.end()
    out.append(("end", "", len(text)))
    return out


class _Parser:
    def __init__(self, text: str) -> None:
        self.text = text
        self.toks = _tokenize(text)
        self.i = 0
        self.depth = 0  # recursion depth of unary/power/atom, bounded by MAX_DEPTH

    def enter(self) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise ExprError(f"nested too deeply (over {MAX_DEPTH} levels)", self.text, self.peek()[2])

    def peek(self) -> tuple[str, str, int]:
        return self.toks[self.i]

    def take(self) -> tuple[str, str, int]:
        tok = self.toks[self.i]
        self.i += 1
        return tok

    def fail(self, expected: str) -> ExprError:
        kind, value, col = self.peek()
        found = "end of expression" if kind == "end" else repr(value)
        return ExprError(f"syntax error: expected {expected}, found {found}", self.text, col)

    def expect(self, op: str) -> None:
        if self.peek()[1] != op or self.peek()[0] != "op":
            raise self.fail(repr(op))
        self.take()

    def parse(self) -> Node:
        if self.peek()[0] == "end":
            raise ExprError("empty expression", self.text, 0)
        node = self.expr()
        if self.peek()[0] != "end":
            raise self.fail("an operator or the end")
        return node

    def expr(self) -> Node:
        left = self.sum()
        kind, value, col = self.peek()
        if kind == "op" and value in _COMPARE:
            self.take()
            right = self.sum()
            if self.peek()[0] == "op" and self.peek()[1] in _COMPARE:
                raise self.fail("no second comparison (write two terms instead)")
            return Binary(value, left, right, col)
        return left

    def sum(self) -> Node:
        node = self.prod()
        while self.peek()[0] == "op" and self.peek()[1] in "+-":
            _, op, col = self.take()
            node = Binary(op, node, self.prod(), col)
        return node

    def prod(self) -> Node:
        node = self.unary()
        while self.peek()[0] == "op" and self.peek()[1] in ("*", "/"):
            _, op, col = self.take()
            node = Binary(op, node, self.unary(), col)
        return node

    def unary(self) -> Node:
        kind, value, col = self.peek()
        if kind == "op" and value in "+-":
            self.take()
            self.enter()
            inner = self.unary()
            self.depth -= 1
            return inner if value == "+" else Unary("-", inner, col)
        return self.power()

    def power(self) -> Node:
        base = self.atom()
        if self.peek()[0] == "op" and self.peek()[1] == "**":
            _, _, col = self.take()
            self.enter()
            exponent = self.unary()
            self.depth -= 1
            return Binary("**", base, exponent, col)
        return base

    def atom(self) -> Node:
        kind, value, col = self.peek()
        if kind == "num":
            self.take()
            number = float(value)
            if not math.isfinite(number):
                raise ExprError(
                    f"number {value[:20]}{'...' if len(value) > 20 else ''} is out of range", self.text, col
                )
            return Num(number, col)
        if kind == "name":
            self.take()
            if self.peek()[0] == "op" and self.peek()[1] == "(":
                return self.call(value, col)
            return Name(value, col)
        if kind == "op" and value == "(":
            self.take()
            self.enter()
            node = self.expr()
            self.expect(")")
            self.depth -= 1
            return node
        raise self.fail("a number, a name or '('")

    def call(self, fn: str, col: int) -> Node:
        if fn not in FUNCTIONS:
            known = ", ".join(sorted(FUNCTIONS))
            raise ExprError(f"unknown function {fn!r} (known: {known})", self.text, col)
        self.expect("(")
        self.enter()
        args = [self.expr()]
        while self.peek()[0] == "op" and self.peek()[1] == ",":
            self.take()
            args.append(self.expr())
        self.expect(")")
        self.depth -= 1
        lo, hi, _ = FUNCTIONS[fn]
        if len(args) < lo or (hi is not None and len(args) > hi):
            want = f"{lo}" if lo == hi else f"at least {lo}" if hi is None else f"{lo}..{hi}"
            raise ExprError(f"{fn}() takes {want} argument(s), got {len(args)}", self.text, col)
        return Call(fn, tuple(args), col)


def parse(text: str) -> Node:
    """Parse one expression; raise :class:`ExprError` with the column of the fault.

    The tree is at most :data:`MAX_DEPTH` deep (else "nested too deeply" at the column where it
    gets too deep) and its numbers are finite.
    """
    if not isinstance(text, str):
        raise ExprError(f"expected an expression string, got {type(text).__name__}", short_repr(text))
    node = _Parser(text).parse()
    _check_depth(node, text)
    return node


def _bounded_repr() -> reprlib.Repr:
    r = reprlib.Repr()
    r.maxlevel, r.maxstring, r.maxother, r.maxlist, r.maxdict, r.maxlong = 3, 60, 60, 6, 6, 40
    return r


_REPR = _bounded_repr()


def short_repr(value: object) -> str:
    """A bounded ``repr`` for messages (a model value may be a huge or deeply nested JSON value)."""
    return _REPR.repr(value)


def _check_depth(node: Node, text: str) -> None:
    """Refuse a tree deeper than MAX_DEPTH (chains like ``1+1+...+1`` parse without recursion)."""
    stack: list[tuple[Node, int]] = [(node, 1)]
    while stack:
        n, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise ExprError(f"nested too deeply (over {MAX_DEPTH} levels)", text, n.col)
        if isinstance(n, Unary):
            stack.append((n.operand, depth + 1))
        elif isinstance(n, Binary):
            stack.append((n.left, depth + 1))
            stack.append((n.right, depth + 1))
        elif isinstance(n, Call):
            stack.extend((a, depth + 1) for a in n.args)


# --- analysis ------------------------------------------------------------------------------------


def names(node: Node) -> list[Name]:
    """Every name reference in ``node``, in source order."""
    if isinstance(node, Name):
        return [node]
    if isinstance(node, Unary):
        return names(node.operand)
    if isinstance(node, Binary):
        return names(node.left) + names(node.right)
    if isinstance(node, Call):
        return [n for a in node.args for n in names(a)]
    return []


def constants(node: Node) -> list[Num]:
    """Every numeric literal in ``node`` (after folding: every constant part), in source order."""
    if isinstance(node, Num):
        return [node]
    if isinstance(node, Unary):
        return constants(node.operand)
    if isinstance(node, Binary):
        return constants(node.left) + constants(node.right)
    if isinstance(node, Call):
        return [c for a in node.args for c in constants(a)]
    return []


def check_names(node: Node, text: str, known: Callable[[str], bool], what: str = "name") -> None:
    """Raise :class:`ExprError` at the first name for which ``known`` is false."""
    for n in names(node):
        if not known(n.id):
            raise ExprError(f"unknown {what} {n.id!r}", text, n.col)


def substitute(node: Node, env: Mapping[str, Node]) -> Node:
    """Replace names found in ``env`` (parameters become numbers this way)."""
    if isinstance(node, Name):
        return env.get(node.id, node)
    if isinstance(node, Unary):
        return Unary(node.op, substitute(node.operand, env), node.col)
    if isinstance(node, Binary):
        return Binary(node.op, substitute(node.left, env), substitute(node.right, env), node.col)
    if isinstance(node, Call):
        return Call(node.fn, tuple(substitute(a, env) for a in node.args), node.col)
    return node


def fold(node: Node) -> Node:
    """Constant-fold: any subtree without names becomes a :class:`Num`."""
    if isinstance(node, Unary):
        inner = fold(node.operand)
        return Num(-inner.value, node.col) if isinstance(inner, Num) else Unary("-", inner, node.col)
    if isinstance(node, Binary):
        a, b = fold(node.left), fold(node.right)
        if isinstance(a, Num) and isinstance(b, Num):
            return Num(_eval_binary(node.op, a.value, b.value), node.col)
        return Binary(node.op, a, b, node.col)
    if isinstance(node, Call):
        args = tuple(fold(a) for a in node.args)
        if all(isinstance(a, Num) for a in args):
            fn = RUNTIME[FUNCTIONS[node.fn][2]]
            return Num(float(fn(*(a.value for a in args))), node.col)  # type: ignore[operator, union-attr]
        return Call(node.fn, args, node.col)
    return node


def _eval_binary(op: str, a: float, b: float) -> float:
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if op == "/":
        return a / b if b != 0.0 else math.copysign(math.inf, a) if a else math.nan
    if op == "**":
        return _pow(a, b)
    return float({"<": a < b, "<=": a <= b, ">": a > b, ">=": a >= b, "==": a == b, "!=": a != b}[op])


def evaluate(node: Node, env: Mapping[str, float]) -> float:
    """Evaluate a tree directly (editor previews, tests); the model uses compiled code instead."""
    if isinstance(node, Num):
        return node.value
    if isinstance(node, Name):
        return float(env[node.id])
    if isinstance(node, Unary):
        return -evaluate(node.operand, env)
    if isinstance(node, Binary):
        a, b = evaluate(node.left, env), evaluate(node.right, env)
        if node.op == "/":
            return _div(a, b)
        if node.op == "**":
            return _pow(a, b)
        return _eval_binary(node.op, a, b)
    fn = RUNTIME[FUNCTIONS[node.fn][2]]
    return float(fn(*(evaluate(a, env) for a in node.args)))  # type: ignore[operator]


def unparse(node: Node) -> str:
    """Canonical text of a tree (fully parenthesised where it matters); used as a feature key."""
    if isinstance(node, Num):
        return repr(node.value)
    if isinstance(node, Name):
        return node.id
    if isinstance(node, Unary):
        return f"(-{unparse(node.operand)})"
    if isinstance(node, Binary):
        return f"({unparse(node.left)} {node.op} {unparse(node.right)})"
    return f"{node.fn}({', '.join(unparse(a) for a in node.args)})"


def to_python(node: Node, local: Mapping[str, str]) -> str:
    """Emit Python source for ``node``; names map to Python identifiers through ``local``.

    Only tree nodes are emitted (numbers through ``repr``), so no user text reaches the compiler.
    """
    if isinstance(node, Num):
        return repr(node.value) if math.isfinite(node.value) else f"float({str(node.value)!r})"
    if isinstance(node, Name):
        return local[node.id]
    if isinstance(node, Unary):
        return f"(-{to_python(node.operand, local)})"
    if isinstance(node, Binary):
        a, b = to_python(node.left, local), to_python(node.right, local)
        if node.op in _COMPARE:
            return f"(1.0 if {a} {node.op} {b} else 0.0)"
        if node.op == "/":
            safe = isinstance(node.right, Num) and node.right.value != 0.0
            return f"({a} / {b})" if safe else f"_div({a}, {b})"
        if node.op == "**":
            return f"_pow({a}, {b})"
        return f"({a} {node.op} {b})"
    return f"{FUNCTIONS[node.fn][2]}({', '.join(to_python(a, local) for a in node.args)})"


#: Key of a linear term: ``None`` for the bias, else the name or the canonical feature text.
LinearKey = tuple[str, str] | None


def linear_terms(node: Node, is_linear_name: Callable[[str], bool]) -> dict[LinearKey, tuple[float, Node | None]]:
    """Split ``node`` into Σ coef·term with numeric coefficients (parameters already folded).

    Names for which ``is_linear_name`` holds (the activations) become ``("name", id)`` keys; any
    other non-constant subterm becomes a ``("feature", canonical text)`` key carrying its tree.
    Sums, differences, negation and multiplication or division by constants are distributed, so
    ``-1.2*(α_b + α_c)`` gives two activation terms.

    Example: ``1 - 1.2*max(α_a, α_b) + 1.5*f`` →
    ``{None: 1.0, ("feature", "max(α_a, α_b)"): -1.2, ("feature", "f"): 1.5}``.
    """
    out: dict[LinearKey, tuple[float, Node | None]] = {}

    def add(key: LinearKey, coef: float, term: Node | None) -> None:
        old = out.get(key, (0.0, term))[0]
        out[key] = (old + coef, term)

    def walk(n: Node, scale: float) -> None:
        if isinstance(n, Num):
            add(None, scale * n.value, None)
        elif isinstance(n, Unary):
            walk(n.operand, -scale)
        elif isinstance(n, Binary) and n.op in "+-":
            walk(n.left, scale)
            walk(n.right, scale if n.op == "+" else -scale)
        elif isinstance(n, Binary) and n.op == "*":
            # Pull every constant factor of a product chain out as the coefficient.
            factors = _factors(n)
            coef = math.prod(f.value for f in factors if isinstance(f, Num))
            rest = [f for f in factors if not isinstance(f, Num)]
            if not rest:
                add(None, scale * coef, None)
            elif len(rest) == 1:
                walk(rest[0], scale * coef)
            else:
                prod = rest[0]
                for f in rest[1:]:
                    prod = Binary("*", prod, f, f.col)
                add(("feature", unparse(prod)), scale * coef, prod)
        elif isinstance(n, Binary) and n.op == "/" and isinstance(n.right, Num) and n.right.value != 0:
            walk(n.left, scale / n.right.value)
        elif isinstance(n, Name) and is_linear_name(n.id):
            add(("name", n.id), scale, n)
        else:
            add(("feature", unparse(n)), scale, n)

    walk(fold(node), 1.0)
    return {k: v for k, v in out.items() if v[0] != 0.0 or k is None}


def _factors(node: Node) -> list[Node]:
    if isinstance(node, Binary) and node.op == "*":
        return _factors(node.left) + _factors(node.right)
    return [node]
