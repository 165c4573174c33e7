"""The bench file: ``bench.toml`` beside a behavior says what the bench computes and what moves.

Three tables, every value an expression (docs/bench.md):

* ``[functions]``: input functions by expression over their parameters' declared names
  (``"locator.distance" = "hypot(x - robot.x, y - robot.y)"``);
* ``[inputs]``: plain inputs that follow the bench robot or ball
  (``"robot_pose.planned.x" = "robot.x"``);
* ``[pose]``: what drives the bench robot each tick, from the behavior's output symbols:
  ``forward`` and ``sideways`` (mm/s, robot frame), ``turn`` (deg/s), and ``when`` (the others
  apply only while it is true).

Expressions are arithmetic in Python's syntax, parsed with :mod:`ast` and turned into closures
(never ``eval``): numbers, ``true``/``false``, dotted names, ``+ - * / % **``, comparisons,
``and or not``, ``a if c else b`` and the functions of :data:`FUNCTIONS` (angles in degrees).
The names an expression may use depend on its table (:func:`BenchFile.bind`); an unknown name, a
construct outside this list or a symbol the behavior does not declare is an error naming
``bench.toml:LINE``.
"""

from __future__ import annotations

import ast
import math
import operator
import re
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from xabsl_studio.engine.codegen.support import divide
from xabsl_studio.engine.host import ExampleError
from xabsl_studio.engine.worlds.benchmath import normalize_degrees

#: The file the bench reads beside an agents file.
BENCH_FILE = "bench.toml"
#: The longest expression a bench file may hold (characters): a formula, not a program.
MAX_EXPRESSION = 2000
#: Deepest expression tree. Checked on the parsed tree, so the refusal does not depend on the
#: process's recursion limit (which another thread's compile, or a test runner, may have raised).
MAX_DEPTH = 200
#: The keys of ``[pose]``.
POSE_KEYS = ("forward", "sideways", "turn", "when")

Scalar = float | bool | int


class BenchFileError(ExampleError):
    """A bench file that does not read, or does not fit the behavior (message: ``file:line: …``)."""


def _guard(function: Callable[..., float]) -> Callable[..., float]:
    def guarded(*args: float) -> float:
        try:
            return function(*args)
        except (ValueError, OverflowError, ZeroDivisionError):
            return math.nan

    return guarded


#: Functions an expression may call (angles in degrees, as the bench's pose).
FUNCTIONS: dict[str, tuple[int, Callable[..., float]]] = {
    "abs": (1, abs),
    "min": (2, min),
    "max": (2, max),
    "sqrt": (1, _guard(math.sqrt)),
    "sin": (1, lambda a: math.sin(math.radians(a))),
    "cos": (1, lambda a: math.cos(math.radians(a))),
    "tan": (1, lambda a: math.tan(math.radians(a))),
    "atan2": (2, lambda y, x: math.degrees(math.atan2(y, x))),
    "hypot": (2, math.hypot),
    "clip": (3, lambda v, lo, hi: lo if v < lo else hi if v > hi else v),
    "normalize": (1, normalize_degrees),
}

#: A context an expression is evaluated in: the robot (``BenchAgent``), a function's arguments, the engine.
Context = Any
Getter = Callable[[Context], Scalar]
#: How a table resolves a name: a getter, or None for an unknown name.
Resolver = Callable[[str], Getter | None]

_BINARY: dict[type[ast.operator], Callable[[Any, Any], Any]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: divide,  # XABSL's: a zero divisor is 1e-7, as in the behavior
    ast.Mod: lambda a, b: math.fmod(a, b) if b else math.nan,
    ast.Pow: _guard(lambda a, b: float(a) ** float(b)),
}
_COMPARE: dict[type[ast.cmpop], Callable[[Any, Any], bool]] = {
    ast.Lt: operator.lt,
    ast.LtE: operator.le,
    ast.Gt: operator.gt,
    ast.GtE: operator.ge,
    ast.Eq: operator.eq,
    ast.NotEq: operator.ne,
}


class ExpressionError(BenchFileError):
    """An expression that does not compile (the caller adds file and line)."""


def dotted(node: ast.expr) -> str | None:
    """``a.b.c`` as a string (None for anything but a name or attribute chain)."""
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        base = dotted(node.value)
        return None if base is None else f"{base}.{node.attr}"
    return None


def compile_expression(text: str, resolve: Resolver) -> Getter:
    """``text`` as a function of a context (see the module docstring for the syntax).

    Raises:
        ExpressionError: a syntax error, an unknown name or function, a construct not allowed.
    """
    if len(text) > MAX_EXPRESSION:
        raise ExpressionError(f"an expression of at most {MAX_EXPRESSION} characters")
    try:
        tree = ast.parse(text.strip(), mode="eval")
        _check_depth(tree.body)
        return _compile(tree.body, resolve)
    except SyntaxError as error:
        raise ExpressionError(f"not an expression: {error.msg} in {text!r}") from None
    except RecursionError:
        raise ExpressionError("an expression nested too deeply") from None


def _check_depth(node: ast.AST) -> None:
    """Raise RecursionError for a tree deeper than :data:`MAX_DEPTH` (walked without recursion)."""
    stack = [(node, 1)]
    while stack:
        current, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise RecursionError(f"an expression nested deeper than {MAX_DEPTH}")
        stack.extend((child, depth + 1) for child in ast.iter_child_nodes(current))


def _compile(node: ast.expr, resolve: Resolver) -> Getter:
    name = dotted(node)
    if name is not None:
        if name in ("true", "false"):
            constant = name == "true"
            return lambda c: constant
        getter = resolve(name)
        if getter is None:
            raise ExpressionError(f"unknown name {name!r}")
        return getter
    if isinstance(node, ast.Constant) and isinstance(node.value, int | float) and not isinstance(node.value, complex):
        value: Scalar = node.value
        return lambda c: value
    if isinstance(node, ast.UnaryOp):
        operand = _compile(node.operand, resolve)
        if isinstance(node.op, ast.USub):
            return lambda c: -operand(c)
        if isinstance(node.op, ast.UAdd):
            return operand
        if isinstance(node.op, ast.Not):
            return lambda c: not operand(c)
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        op = _BINARY[type(node.op)]
        left, right = _compile(node.left, resolve), _compile(node.right, resolve)
        return lambda c: op(left(c), right(c))
    if isinstance(node, ast.BoolOp):
        parts = [_compile(v, resolve) for v in node.values]
        if isinstance(node.op, ast.And):
            return lambda c: all(bool(p(c)) for p in parts)
        return lambda c: any(bool(p(c)) for p in parts)
    if isinstance(node, ast.Compare) and len(node.ops) == 1 and type(node.ops[0]) in _COMPARE:
        compare = _COMPARE[type(node.ops[0])]
        left, right = _compile(node.left, resolve), _compile(node.comparators[0], resolve)
        return lambda c: compare(left(c), right(c))
    if isinstance(node, ast.IfExp):
        test, body, orelse = (_compile(n, resolve) for n in (node.test, node.body, node.orelse))
        return lambda c: body(c) if test(c) else orelse(c)
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and not node.keywords:
        known = FUNCTIONS.get(node.func.id)
        if known is None:
            raise ExpressionError(f"unknown function {node.func.id!r} (known: {', '.join(FUNCTIONS)})")
        arity, function = known
        if len(node.args) != arity:
            raise ExpressionError(f"{node.func.id} takes {arity} argument{'s' if arity > 1 else ''}")
        args = [_compile(a, resolve) for a in node.args]
        return lambda c: function(*(a(c) for a in args))
    raise ExpressionError(f"not allowed in a bench expression: {ast.unparse(node)!r}")


@dataclass(frozen=True, slots=True)
class Entry:
    """One ``key = "expression"`` of a table, with the line it is on."""

    key: str
    text: str
    line: int


@dataclass(frozen=True, slots=True)
class BenchFile:
    """A read bench file: its entries by table (checked against a program in :meth:`bind`)."""

    path: Path
    functions: tuple[Entry, ...]
    inputs: tuple[Entry, ...]
    pose: tuple[Entry, ...]

    @classmethod
    def read(cls, path: Path) -> BenchFile:
        """Read and check the form of ``path`` (names are checked against the program later).

        Raises:
            BenchFileError: no such file, not TOML, an unknown table or pose key, a value that is
                not a string, an expression that does not parse.
        """
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as error:
            raise BenchFileError(f"{path}: {error}") from None
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as error:
            found = re.search(r"\(at line (\d+), column (\d+)\)", str(error))
            where = f"{path}:{found.group(1)}:{found.group(2)}" if found else str(path)
            message = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(error))
            raise BenchFileError(f"{where}: not TOML: {message}") from None
        lines = _key_lines(text)
        unknown = sorted(set(data) - {"functions", "inputs", "pose"})
        if unknown:
            raise BenchFileError(
                f"{path}:{lines.get(('', unknown[0]), 1)}: unknown table {unknown[0]!r} (functions, inputs, pose)"
            )
        tables: dict[str, tuple[Entry, ...]] = {}
        for table in ("functions", "inputs", "pose"):
            raw = data.get(table, {})
            if not isinstance(raw, dict):
                raise BenchFileError(f"{path}:{lines.get(('', table), 1)}: {table} must be a table")
            entries = []
            for key, value in _flatten(raw):
                line = lines.get((table, key), 1)
                if not isinstance(value, str):
                    raise BenchFileError(f"{path}:{line}: {table}.{key}: the value is an expression in quotes")
                if table == "pose" and key not in POSE_KEYS:
                    raise BenchFileError(f"{path}:{line}: unknown pose key {key!r} ({', '.join(POSE_KEYS)})")
                try:  # the syntax now; names once the program is known
                    if len(value) > MAX_EXPRESSION:
                        raise BenchFileError(f"{path}:{line}: {table}.{key}: over {MAX_EXPRESSION} characters")
                    ast.parse(value.strip(), mode="eval")
                except (SyntaxError, RecursionError, MemoryError) as error:
                    reason = error.msg if isinstance(error, SyntaxError) else "nested too deeply"
                    raise BenchFileError(f"{path}:{line}: {table}.{key}: not an expression: {reason}") from None
                entries.append(Entry(key, value, line))
            tables[table] = tuple(entries)
        return cls(path, tables["functions"], tables["inputs"], tables["pose"])

    def error(self, entry: Entry, message: str) -> BenchFileError:
        """An error naming the file and the entry's line."""
        return BenchFileError(f"{self.path}:{entry.line}: {entry.key}: {message}")

    def compiled(self, entry: Entry, resolve: Resolver) -> Getter:
        """``entry``'s expression compiled with ``resolve`` (errors name the line)."""
        try:
            return compile_expression(entry.text, resolve)
        except ExpressionError as error:
            raise self.error(entry, str(error)) from None


def _flatten(table: Mapping[str, Any], prefix: str = "") -> list[tuple[str, Any]]:
    """Bare dotted keys (``robot_pose.x = …``) are nested tables in TOML: join them back."""
    items: list[tuple[str, Any]] = []
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            items.extend(_flatten(value, name + "."))
        else:
            items.append((name, value))
    return items


_HEADER = re.compile(r"^\s*\[\s*([A-Za-z0-9_.-]+)\s*\]")
_KEY = re.compile(r"""^\s*("(?P<dq>[^"]*)"|'(?P<sq>[^']*)'|(?P<bare>[A-Za-z0-9_.\- ]+?))\s*=""")


def _key_lines(text: str) -> dict[tuple[str, str], int]:
    """The line of every ``key =`` by (table, key); tables as keys of the root ``('', name)``."""
    found: dict[tuple[str, str], int] = {}
    table = ""
    for number, line in enumerate(text.splitlines(), start=1):
        header = _HEADER.match(line)
        if header:
            table = header.group(1)
            found.setdefault(("", table), number)
            continue
        key = _KEY.match(line)
        if key:
            name = key.group("dq") if key.group("dq") is not None else key.group("sq") or key.group("bare") or ""
            name = ".".join(part.strip().strip("\"'") for part in name.split(".")) if key.group("bare") else name
            found.setdefault((table, name), number)
    return found


def find_bench_file(agents_file: Path) -> Path | None:
    """The bench file beside ``agents_file``, if there is one."""
    candidate = agents_file.parent / BENCH_FILE
    return candidate if candidate.is_file() else None
