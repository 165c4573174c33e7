"""Property tests of the XABSL 2 front end (§1.2 lexical structure, §1.3 grammar, §1.4 typing).

A small generator kept in this module writes *valid* behavior sets as source text: a symbols
namespace (decimal/bool/enum inputs, parameterised input functions, outputs, internal symbols,
enumerations, constants), a basic-behavior namespace, options whose calls form a DAG, and an
agents file including everything. Expressions are built as small trees and printed with the
precedence table of §1.3, either with as few parentheses as the grammar needs or with
parentheses around every subexpression. The properties:

* a generated set compiles without errors, and compiling it twice gives the same IC and the
  same diagnostics (also in other processes with other hash seeds); permuting the include
  lines of the agents file does not change the IC;
* the IC does not depend on redundant parentheses (the IC has none, and ``&&``/``||`` chains
  are flattened through parentheses, §3.3);
* mutated sources (generated sets and the conformance kit's behavior sets) never make
  ``compile_file`` raise or hang, a failed compilation always carries an error, and every
  diagnostic has a known code and a span inside its file, consistent with its offsets;
* the tokenizer never raises, and token positions never go backwards.

Examples are derandomized so CI runs are reproducible.
"""

from __future__ import annotations

import json
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TypeVar

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.kit import KIT, SETS
from xabsl_studio.engine.emit.ic import emit_ic
from xabsl_studio.engine.lang import Compilation, compile_file
from xabsl_studio.engine.lang.diagnostics import CODES, Diagnostics
from xabsl_studio.engine.lang.tokens import TokenType, tokenize
from xabsl_studio.engine.types import Span

# --------------------------------------------------------------------------------------------
# expression trees and their printer


#: Precedence levels of §1.3 (higher binds looser); atoms are 0, unary operators 1.
LEVEL = {"*": 2, "/": 2, "%": 2, "+": 3, "-": 3, "<": 4, ">": 4, "<=": 4, ">=": 4, "==": 4, "!=": 4, "&&": 5, "||": 6}
CONDITIONAL_LEVEL = 7


@dataclass(frozen=True)
class Atom:
    """A literal, a symbol, a parameter or a built-in such as ``state_time``."""

    text: str


@dataclass(frozen=True)
class Call:
    """An input function call ``f(a = x, b = y)``."""

    name: str
    args: tuple[tuple[str, Expr], ...]


@dataclass(frozen=True)
class Unary:
    op: str
    operand: Expr


@dataclass(frozen=True)
class Binary:
    op: str
    left: Expr
    right: Expr


@dataclass(frozen=True)
class Conditional:
    cond: Expr
    then: Expr
    other: Expr


Expr = Atom | Call | Unary | Binary | Conditional


def level(e: Expr) -> int:
    """How loosely ``e`` binds: 0 for atoms and calls, 7 for ``?:``."""
    if isinstance(e, Unary):
        return 1
    if isinstance(e, Binary):
        return LEVEL[e.op]
    if isinstance(e, Conditional):
        return CONDITIONAL_LEVEL
    return 0


def render(e: Expr, all_parens: bool = False) -> str:
    """Print ``e`` as XABSL source.

    With ``all_parens`` every subexpression is parenthesised; otherwise only where the grammar
    needs it: a looser operand, the right operand of a left-associative operator at the same
    level, any operand of the non-associative comparisons and of ``?:`` (nested conditionals
    need parentheses, §1.3).
    """

    def sub(child: Expr, needed: bool) -> str:
        text = render(child, all_parens)
        return f"({text})" if needed or all_parens else text

    if isinstance(e, Atom):
        return e.text
    if isinstance(e, Call):
        return f"{e.name}({', '.join(f'{name} = {sub(value, False)}' for name, value in e.args)})"
    if isinstance(e, Unary):
        operand = sub(e.operand, level(e.operand) > 1)
        # "- -x", never "--x"; both are fine for the tokenizer but keep the text readable
        return f"{e.op} {operand}" if operand.startswith("-") else f"{e.op}{operand}"
    if isinstance(e, Binary):
        own = LEVEL[e.op]
        if own == LEVEL["<"]:
            left, right = sub(e.left, level(e.left) >= own), sub(e.right, level(e.right) >= own)
        else:
            left, right = sub(e.left, level(e.left) > own), sub(e.right, level(e.right) >= own)
        return f"{left} {e.op} {right}"
    parts = (sub(part, level(part) >= CONDITIONAL_LEVEL) for part in (e.cond, e.then, e.other))
    return "{} ? {} : {}".format(*parts)


# --------------------------------------------------------------------------------------------
# the behavior-set generator

T = TypeVar("T")


@dataclass
class Param:
    """A parameter of an option, an input function or a basic behavior: type and short name."""

    name: str
    kind: str  # "d", "b" or an enum name


@dataclass
class Symbols:
    """Everything the symbols namespace declares, by type."""

    enums: dict[str, list[str]] = field(default_factory=dict)
    internal_enums: set[str] = field(default_factory=set)
    constants: list[str] = field(default_factory=list)
    #: readable symbols (inputs, outputs, internals) without parameters, by kind
    readable: dict[str, list[str]] = field(default_factory=dict)
    #: assignable symbols (outputs, internals), by kind
    assignable: dict[str, list[str]] = field(default_factory=dict)
    #: input functions, by result kind: (name, parameters)
    functions: dict[str, list[tuple[str, list[Param]]]] = field(default_factory=dict)
    behaviors: list[tuple[str, list[Param]]] = field(default_factory=list)


@dataclass
class GeneratedSet:
    """A behavior set as files of text fragments; expressions are printed at render time."""

    files: dict[str, list[str | Expr]]
    #: include lines of the agents file, in order
    includes: list[str]

    def render(self, all_parens: bool = False, includes: list[str] | None = None) -> dict[str, str]:
        """File name -> source text; ``includes`` replaces the agents file's include order."""
        out: dict[str, str] = {}
        for name, parts in self.files.items():
            text = "".join(p if isinstance(p, str) else render(p, all_parens) for p in parts)
            if name == "agents.xabsl":
                lines = "".join(f'include "{i}";\n' for i in (includes or self.includes))
                text = text.replace("@@INCLUDES@@\n", lines)
            out[name] = text
        return out


class Generator:
    """Draws a valid behavior set from ``rnd`` (a ``random.Random`` or Hypothesis' ``randoms()``).

    Sizes are kept small so that a test example compiles in milliseconds; every rule of §1.3
    and §1.4 that makes a program invalid is respected on purpose (see the module docstring).
    """

    def __init__(self, rnd: random.Random, options: int = 4, max_depth: int = 3) -> None:
        self.rnd = rnd
        self.option_count = options
        self.max_depth = max_depth
        self.symbols = Symbols()
        self.params: list[Param] = []
        self.in_state = False
        self.option_params: list[list[Param]] = []

    # -- small helpers ---------------------------------------------------------------------

    def chance(self, p: float) -> bool:
        return self.rnd.random() < p

    def pick(self, items: Sequence[T]) -> T:
        return items[self.rnd.randrange(len(items))]

    def kinds(self) -> list[str]:
        """The value kinds usable as symbol or parameter types: ``d``, ``b`` and enum names."""
        return ["d", "b", *[e for e in self.symbols.enums if e not in self.symbols.internal_enums]]

    def doc(self, indent: str = "") -> str:
        if not self.chance(0.3):
            return ""
        words = ["decides", "the", "ball", "robot", "état", "mm", "// not a comment", "* star"]
        text = " ".join(self.pick(words) for _ in range(self.rnd.randint(1, 6)))
        return f"{indent}/** {text} */\n"

    @staticmethod
    def type_text(kind: str) -> str:
        return {"d": "float", "b": "bool"}.get(kind, f"enum {kind}")

    def number(self) -> Atom:
        form = self.rnd.randrange(4)
        value = self.rnd.randint(0, 5000)
        if form == 0:
            return Atom(str(value))
        if form == 1:
            return Atom(f"{value}.{self.rnd.randint(0, 99)}")
        if form == 2:
            return Atom(f"{value}.")
        return Atom(f"0.{self.rnd.randint(0, 999):03d}")

    # -- the symbols and basic-behavior namespaces --------------------------------------------

    def params_decl(self, count: int, prefix: str) -> list[Param]:
        return [Param(f"{prefix}{i}", self.pick(self.kinds())) for i in range(count)]

    def param_lines(self, params: list[Param], at: str, indent: str, closer: str = ";") -> str:
        lines = []
        for p in params:
            extra = ' [0..100] "mm"' if p.kind == "d" and self.chance(0.4) else ""
            lines.append(f"{self.doc(indent)}{indent}{self.type_text(p.kind)} {at}{p.name}{extra}{closer}\n")
        return "".join(lines)

    def symbols_file(self) -> str:
        s = self.symbols
        out = ['/** The world as the generated agents see it. */\nnamespace symbols("Generated symbols") {\n']
        for i in range(self.rnd.randint(1, 3)):
            name = f"color{i}" if i % 2 else f"game.mode{i}"
            internal = self.chance(0.25)
            s.enums[name] = [f"c{i}_v{j}" for j in range(self.rnd.randint(1, 4))]
            if internal:
                s.internal_enums.add(name)
            io = " internal" if internal else ""
            out.append(f"{self.doc('  ')}  enum {name}{io} {{ {', '.join(s.enums[name])} }};\n")
        for i in range(self.rnd.randint(0, 3)):
            name = f"k.c{i}"
            s.constants.append(name)
            unit = ' "mm"' if self.chance(0.5) else ""
            sign = "-" if self.chance(0.2) else ""
            typ = "float " if self.chance(0.5) else ""
            out.append(f"{self.doc('  ')}  {typ}const {name} = {sign}{self.number().text}{unit};\n")
        count = 0
        for io in ("input", "output", "internal"):
            for _ in range(self.rnd.randint(1, 4)):
                count += 1
                if io == "internal":
                    kind = self.pick(["d", "b", *s.enums])
                else:
                    kind = self.pick(self.kinds())
                # an enum input may share the name of its enumeration (real behaviors do this)
                if io == "input" and kind in s.enums and self.chance(0.3):
                    name = kind
                else:
                    name = f"{io[:3]}.{kind if kind in ('d', 'b') else 'e'}{count}"
                    if name in s.enums:  # pragma: no cover - names never collide by construction
                        continue
                if name in s.readable.get(kind, []):
                    continue
                s.readable.setdefault(kind, []).append(name)
                if io != "input":
                    s.assignable.setdefault(kind, []).append(name)
                extra = ' [0..9000] "mm"' if kind == "d" and self.chance(0.3) else ""
                out.append(f"{self.doc('  ')}  {self.type_text(kind)} {io} {name}{extra};\n")
        for i in range(self.rnd.randint(0, 3)):
            kind = self.pick(self.kinds())
            params = self.params_decl(self.rnd.randint(1, 3), "x")
            name = f"fn.f{i}"
            s.functions.setdefault(kind, []).append((name, params))
            out.append(f"{self.doc('  ')}  {self.type_text(kind)} input {name} (\n")
            out.append(self.param_lines(params, "", "    "))
            out.append("  );\n")
        out.append("}\n")
        return "".join(out)

    def behaviors_file(self) -> str:
        out = ['/** Skills. */\nnamespace skills("Generated basic behaviors") {\n']
        for i in range(self.rnd.randint(1, 3)):
            params = self.params_decl(self.rnd.randint(0, 3), "p")
            name = f"bb.skill{i}"
            self.symbols.behaviors.append((name, params))
            out.append(f"{self.doc('  ')}  behavior {name} {{\n{self.param_lines(params, '', '    ')}  }}\n")
        out.append("}\n")
        return "".join(out)

    # -- typed expressions (§1.4) ----------------------------------------------------------

    def args(self, params: list[Param], depth: int) -> tuple[tuple[str, Expr], ...]:
        """Named arguments for every parameter (sometimes leaving one out: only a warning)."""
        chosen = [p for p in params if not self.chance(0.1)]
        self.rnd.shuffle(chosen)
        return tuple((p.name, self.expr(p.kind, depth - 1)) for p in chosen)

    def leaves(self, kind: str) -> list[Expr]:
        s = self.symbols
        found: list[Expr] = [Atom(n) for n in s.readable.get(kind, [])]
        found += [Atom(f"@{p.name}") for p in self.params if p.kind == kind]
        if kind == "d":
            found += [Atom(c) for c in s.constants]
            found += [Atom("state_time"), Atom("option_time")]
        elif kind == "b":
            found += [Atom("true"), Atom("false")]
            if self.in_state:
                found.append(Atom("action_done"))
        return found

    def expr(self, kind: str, depth: int) -> Expr:
        """An expression of ``kind`` (``d``, ``b`` or an enum name, the latter in enum context)."""
        if kind == "d":
            return self.decimal(depth)
        if kind == "b":
            return self.boolean(depth)
        return self.enum_value(kind, depth)

    def call(self, kind: str, depth: int) -> Expr | None:
        functions = self.symbols.functions.get(kind, [])
        if not functions or depth <= 0:
            return None
        name, params = self.pick(functions)
        return Call(name, self.args(params, depth))

    def decimal(self, depth: int) -> Expr:
        choice = self.rnd.randrange(10) if depth > 0 else 0
        if choice <= 2:
            leaves = self.leaves("d")
            return self.number() if self.chance(0.3) else self.pick(leaves)
        if choice <= 6:
            op = self.pick(["+", "-", "*", "/", "%"])
            return Binary(op, self.decimal(depth - 1), self.decimal(depth - 1))
        if choice == 7:
            return Unary("-", self.decimal(depth - 1))
        if choice == 8:
            return self.call("d", depth) or self.decimal(depth - 1)
        return Conditional(self.boolean(depth - 1), self.decimal(depth - 1), self.decimal(depth - 1))

    def enum_refs(self) -> list[tuple[str, Expr]]:
        """Qualified enum-typed references usable as the left side of ``==``/``!=``."""
        refs: list[tuple[str, Expr]] = []
        for enum in self.symbols.enums:
            refs += [(enum, leaf) for leaf in self.leaves(enum)]
        return refs

    def boolean(self, depth: int) -> Expr:
        choice = self.rnd.randrange(10) if depth > 0 else 0
        if choice <= 1:
            return self.pick(self.leaves("b"))
        if choice == 2:
            return Unary("!", self.boolean(depth - 1))
        if choice <= 4:
            op = self.pick(["&&", "||"])
            return Binary(op, self.boolean(depth - 1), self.boolean(depth - 1))
        if choice <= 6:
            op = self.pick(["<", ">", "<=", ">=", "==", "!="])
            return Binary(op, self.decimal(depth - 1), self.decimal(depth - 1))
        if choice <= 8:
            refs = self.enum_refs()
            if refs:
                enum, left = self.pick(refs)
                return Binary(self.pick(["==", "!="]), left, self.enum_value(enum, depth - 1))
        return self.call("b", depth) or self.boolean(depth - 1)

    def enum_value(self, enum: str, depth: int) -> Expr:
        """An expression of enumeration ``enum`` where an enum is expected (literals resolve)."""
        choice = self.rnd.randrange(6) if depth > 0 else 0
        if choice <= 2 or choice == 5:
            candidates: list[Expr] = [Atom(e) for e in self.symbols.enums[enum]] + self.leaves(enum)
            return self.pick(candidates)
        if choice == 3:
            return self.call(enum, depth) or self.enum_value(enum, depth - 1)
        return Conditional(self.boolean(depth - 1), self.enum_value(enum, depth - 1), self.enum_value(enum, depth - 1))

    def depth(self) -> int:
        return self.rnd.randint(0, self.max_depth)

    # -- options ---------------------------------------------------------------------------

    def dtree(self, states: list[str], depth: int, indent: str) -> list[str | Expr]:
        """A state decision tree: every ``if`` has an ``else`` (§1.3 note c)."""
        if depth <= 0 or self.chance(0.3):
            leaf = "stay;" if self.chance(0.3) else f"goto {self.pick(states)};"
            if self.chance(0.1):
                return [f"{{ {leaf} }}"]
            return [leaf]
        inner = indent + "  "
        then = self.dtree(states, depth - 1, inner)
        other = self.dtree(states, depth - 1, inner)
        if self.chance(0.6):
            then = ["{\n", inner, *then, f"\n{indent}}}"]
            other = ["{\n", inner, *other, f"\n{indent}}}"]
        else:  # braces are optional: with a mandatory else, nested ifs never dangle
            then = ["\n", inner, *then]
            other = ["\n", inner, *other]
        return [
            f"\n{self.doc(indent)}{indent}if (",
            self.boolean(self.depth()),
            ") ",
            *then,
            f"\n{self.doc(indent)}{indent}else ",
            *other,
        ]

    def common_tree(self, states: list[str], indent: str) -> list[str | Expr]:
        """A common decision tree: an ``if``/``else if`` chain without a final ``else``."""
        parts: list[str | Expr] = []
        for i in range(self.rnd.randint(1, 3)):
            prefix = f"{indent}else " if i else indent
            parts += [
                f"{self.doc(indent)}{prefix}if (",
                self.boolean(self.depth()),
                ")\n",
                indent,
                "  ",
                *self.dtree(states, self.rnd.randint(0, 2), indent + "  "),
                "\n",
            ]
        return parts

    def actions(self, index: int, indent: str) -> list[str | Expr]:
        parts: list[str | Expr] = []
        for _ in range(self.rnd.randint(0, 3)):
            kinds = [k for k, names in self.symbols.assignable.items() if names]
            if not kinds:
                break
            kind = self.pick(kinds)
            target = self.pick(self.symbols.assignable[kind])
            parts += [f"{indent}{target} = ", self.expr(kind, self.depth()), ";\n"]
        callees = list(range(index + 1, self.option_count))
        self.rnd.shuffle(callees)
        for callee in callees[: self.rnd.randint(0, 2)]:
            keyword = " option" if self.chance(0.2) else ""
            call = Call(f"opt{callee}{keyword}", self.args(self.option_params[callee], self.depth() + 1))
            parts += [indent, call, ";\n"]
        if self.symbols.behaviors and self.chance(0.5):
            name, params = self.pick(self.symbols.behaviors)
            keyword = " behavior" if self.chance(0.2) else ""
            parts += [indent, Call(f"{name}{keyword}", self.args(params, self.depth() + 1)), ";\n"]
        return parts

    def option_file(self, index: int) -> list[str | Expr]:
        name = f"opt{index}"
        self.params = self.option_params[index]
        states = [f"s{i}" for i in range(self.rnd.randint(1, 4))]
        initial = self.rnd.randrange(len(states))
        parts: list[str | Expr] = []
        if self.chance(0.3):
            parts.append('include "../symbols.xabsl";\n')
        parts += [self.doc(), f"option {name} {{\n", self.param_lines(self.params, "@", "  ")]
        self.in_state = False
        common = self.chance(0.4)
        if common:
            parts += ["  common decision {\n", *self.common_tree(states, "    "), "  }\n"]
        if self.chance(0.3):
            parts += ["  common action {\n", *self.actions(index, "    "), "  }\n"]
        self.in_state = True
        for i, state in enumerate(states):
            flags = ("initial " if i == initial else "") + ("target " if self.chance(0.3) else "")
            parts.append(f"  {flags}state {state} {{\n")
            if self.chance(0.85):
                tree = self.dtree(states, self.rnd.randint(0, 3), "      ")
                lead = f"{self.doc('      ')}      else\n" if common else ""
                parts += ["    decision {\n", lead, "      ", *tree, "\n    }\n"]
            parts += ["    action {\n", *self.actions(index, "      "), "    }\n  }\n"]
        parts.append("}\n")
        return parts

    def generate(self) -> GeneratedSet:
        """The whole set: ``agents.xabsl`` (the entry), namespaces and ``options/opt<i>.xabsl``."""
        files: dict[str, list[str | Expr]] = {
            "symbols.xabsl": [self.symbols_file()],
            "skills.xabsl": [self.behaviors_file()],
        }
        self.option_params = [self.params_decl(self.rnd.randint(0, 3), "q") for _ in range(self.option_count)]
        for index in range(self.option_count):
            files[f"options/opt{index}.xabsl"] = self.option_file(index)
        includes = ["symbols.xabsl", "skills.xabsl", *(f"options/opt{i}.xabsl" for i in range(self.option_count))]
        roots = ["opt0", *(f"opt{i}" for i in range(1, self.option_count) if self.chance(0.3))]
        agents = "".join(f'{self.doc()}agent a{i}("Agent {i}", {root});\n' for i, root in enumerate(roots))
        files["agents.xabsl"] = ["/*** Title: Generated\n     Platform: hypothesis\n*/\n@@INCLUDES@@\n", agents]
        return GeneratedSet(files, includes)


# --------------------------------------------------------------------------------------------
# helpers


@contextmanager
def behavior_folder(files: dict[str, str] | dict[str, bytes]) -> Iterator[Path]:
    """A temporary folder holding ``files`` (text or raw bytes), removed afterwards."""
    root = Path(tempfile.mkdtemp(prefix="xabsl-prop-"))
    try:
        for name, content in files.items():
            path = root / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(content.encode("utf-8") if isinstance(content, str) else content)
        yield root
    finally:
        shutil.rmtree(root, ignore_errors=True)


def compile_folder(root: Path) -> Compilation:
    return compile_file(str(root / "agents.xabsl"), base=str(root))


def fingerprint(compilation: Compilation) -> tuple[str | None, list[str]]:
    """What must be identical between two compilations: the IC text and the diagnostics."""
    ic = emit_ic(compilation.program) if compilation.program is not None else None
    return ic, [d.format() for d in compilation.diagnostics]


def position(text: str, offset: int) -> tuple[int, int]:
    """1-based (line, column) of a character offset, lines ending at LF (as the tokenizer)."""
    line = text.count("\n", 0, offset) + 1
    col = offset - (text.rfind("\n", 0, offset) + 1) + 1
    return line, col


def check_span(span: Span, texts: dict[str, str], where: str) -> None:
    """A span lies inside its file and its line/column agree with its offsets."""
    assert span.file in texts, f"{where}: span names an unknown file {span.file!r}"
    text = texts[span.file]
    assert 0 <= span.start <= span.end <= len(text), f"{where}: offsets outside the file ({len(text)})"
    assert span.line >= 1 and span.col >= 1, where
    assert (span.line, span.col) == position(text, span.start), f"{where}: line/col vs start"
    assert (span.end_line, span.end_col) == position(text, span.end), f"{where}: end line/col vs end"


#: codes that may come without a span: problems with a whole file
FILE_LEVEL_CODES = frozenset({"unreadable-file"})


def check_diagnostics(compilation: Compilation) -> None:
    """The invariants every compilation keeps, whatever the source."""
    if compilation.program is None:
        assert compilation.errors, "no program but no error diagnostic"
    else:
        assert not compilation.errors, "a program despite errors"
    for d in compilation.diagnostics:
        where = d.format()
        assert d.code in CODES, where
        assert d.message, where
        if d.span is None:
            assert d.code in FILE_LEVEL_CODES, f"{where}: no span"
        else:
            assert d.file == d.span.file, where
            check_span(d.span, compilation.sources, where)
        for _, span in d.related:
            check_span(span, compilation.sources, f"{where} (related)")


# --------------------------------------------------------------------------------------------
# valid programs

#: Each property is a separate budget; the file as a whole stays well under a minute.
VALID = settings(
    max_examples=60,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


@st.composite
def behavior_sets(draw: st.DrawFn) -> GeneratedSet:
    """A generated valid behavior set (Hypothesis drives the generator's random choices)."""
    rnd = draw(st.randoms(use_true_random=False))
    options = draw(st.integers(min_value=1, max_value=6))
    return Generator(rnd, options=options).generate()


def assert_clean(compilation: Compilation, files: dict[str, str]) -> None:
    errors = [d.format() for d in compilation.errors]
    listing = "\n\n".join(f"== {name}\n{text}" for name, text in files.items())
    assert not errors, "\n".join(errors) + "\n" + listing
    assert compilation.program is not None


@VALID
@given(behavior_sets())
def test_generated_program_compiles_without_errors_and_deterministically(generated: GeneratedSet) -> None:
    files = generated.render()
    with behavior_folder(files) as root:
        first = compile_folder(root)
        assert_clean(first, files)
        check_diagnostics(first)
        second = compile_folder(root)
    assert fingerprint(first) == fingerprint(second)
    assert sorted(first.option_names) == sorted(n for n in first.program.options)


@VALID
@given(behavior_sets(), st.randoms(use_true_random=False))
def test_include_order_does_not_change_the_ic(generated: GeneratedSet, rnd: random.Random) -> None:
    reordered = list(generated.includes)
    rnd.shuffle(reordered)
    with behavior_folder(generated.render()) as root:
        original = compile_folder(root)
    with behavior_folder(generated.render(includes=reordered)) as root:
        shuffled = compile_folder(root)
    assert original.program is not None and shuffled.program is not None
    assert emit_ic(original.program) == emit_ic(shuffled.program), reordered


@VALID
@given(behavior_sets())
def test_redundant_parentheses_do_not_change_the_ic(generated: GeneratedSet) -> None:
    plain_files, paren_files = generated.render(), generated.render(all_parens=True)
    with behavior_folder(plain_files) as root:
        plain = compile_folder(root)
    with behavior_folder(paren_files) as root:
        parenthesised = compile_folder(root)
    assert_clean(plain, plain_files)
    assert_clean(parenthesised, paren_files)
    assert emit_ic(plain.program) == emit_ic(parenthesised.program)


def test_printer_parenthesises_only_where_the_grammar_needs_it() -> None:
    """The printer itself, on the cases §1.3 singles out (so the properties above mean something)."""
    a, b, c = Atom("a"), Atom("b"), Atom("c")
    assert render(Binary("-", a, Binary("-", b, c))) == "a - (b - c)"
    assert render(Binary("-", Binary("-", a, b), c)) == "a - b - c"
    assert render(Binary("<", Binary("<", a, b), c)) == "(a < b) < c"
    assert render(Conditional(a, Conditional(a, b, c), c)) == "a ? (a ? b : c) : c"
    assert render(Unary("-", Binary("*", a, b))) == "-(a * b)"
    assert render(Unary("-", Unary("-", a))) == "- -a"
    assert render(Binary("*", a, b), all_parens=True) == "(a) * (b)"


# --------------------------------------------------------------------------------------------
# mutations

_TOKEN = re.compile(rb"@?[A-Za-z_][A-Za-z0-9_.]*|[0-9]+(?:\.[0-9]*)?|&&|\|\||[<>=!]=|\s+|.", re.DOTALL)
_NOISE = [
    b"{",
    b"}",
    b"(",
    b")",
    b";",
    b"/*",
    b"/**",
    b"*/",
    b"//",
    b'"',
    b"[",
    b"@",
    b"?",
    b":",
    b"\xff",
    b"\xc3",
    "é".encode(),
    "→".encode(),
    b"\x00",
    b"\r",
    b"\t",
    b"#",
    b"$",
    b"`",
    b"\\",
    b"else",
    b"if",
    b"state",
    b"option",
    b"include",
    b"1.5E3",
    b"-",
    b"!",
    b"==",
    b"&&",
]
_NAMES = [
    b"state_time",
    b"action_done",
    b"goto",
    b"stay",
    b"enum",
    b"input",
    b"x",
    b"@p",
    b"initial",
    b"agent",
    b"common",
    b"decision",
    b"namespace",
    b"behavior",
    b"s0",
    b"opt1",
    b"true",
]


def mutate(data: bytes, rnd: random.Random) -> bytes:
    """One random edit: characters, tokens, braces, identifiers, line ends or truncation."""
    if not data:
        return bytes(rnd.choice(_NOISE))
    kind = rnd.randrange(10)
    at = rnd.randrange(len(data) + 1)
    if kind == 0:  # delete characters
        return data[:at] + data[at + rnd.randint(1, 3) :]
    if kind == 1:  # duplicate a slice
        end = min(len(data), at + rnd.randint(1, 40))
        return data[:end] + data[at:end] + data[end:]
    if kind == 2:  # insert noise, non-ASCII bytes included
        return data[:at] + b"".join(rnd.choice(_NOISE) for _ in range(rnd.randint(1, 3))) + data[at:]
    if kind == 3:  # truncate
        return data[:at]
    if kind == 4:  # drop a brace or a parenthesis
        positions = [i for i, byte in enumerate(data) if byte in b"{}()"]
        if positions:
            i = rnd.choice(positions)
            return data[:i] + data[i + 1 :]
        return data
    if kind == 5:  # line ends: LF -> CRLF, CRLF -> LF, or a lone CR
        return rnd.choice([data.replace(b"\n", b"\r\n"), data.replace(b"\r\n", b"\n"), data[:at] + b"\r" + data[at:]])
    tokens = _TOKEN.findall(data)
    i = rnd.randrange(len(tokens))
    if kind == 6:  # delete a token
        del tokens[i]
    elif kind == 7:  # duplicate a token
        tokens.insert(i, tokens[i])
    elif kind == 8:  # swap two tokens
        j = rnd.randrange(len(tokens))
        tokens[i], tokens[j] = tokens[j], tokens[i]
    else:  # replace an identifier by another name or keyword
        names = [k for k, t in enumerate(tokens) if re.fullmatch(rb"@?[A-Za-z_][A-Za-z0-9_.]*", t)]
        if names:
            k = rnd.choice(names)
            others = [t for t in tokens if re.fullmatch(rb"@?[A-Za-z_][A-Za-z0-9_.]*", t)]
            tokens[k] = rnd.choice(others + _NAMES)
    return b"".join(tokens)


def kit_set(name: str) -> dict[str, bytes]:
    """The ``.xabsl`` files of one conformance-kit behavior set, by relative path."""
    root = KIT / name
    return {str(p.relative_to(root)): p.read_bytes() for p in sorted(root.rglob("*.xabsl"))}


KIT_SETS = {name: kit_set(name) for name in SETS}
#: a compile of a small mutated set takes milliseconds; this only catches hangs
HANG_GUARD_SECONDS = 2.0
MUTATIONS = settings(
    max_examples=200,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


def check_mutant(files: dict[str, bytes], rnd: random.Random) -> None:
    """Mutate one to three files of ``files`` and check the compilation invariants."""
    mutated = dict(files)
    for _ in range(rnd.randint(1, 3)):
        name = rnd.choice(sorted(mutated))
        for _ in range(rnd.randint(1, 3)):
            mutated[name] = mutate(mutated[name], rnd)
    with behavior_folder(mutated) as root:
        started = time.perf_counter()
        compilation = compile_folder(root)
        elapsed = time.perf_counter() - started
        check_diagnostics(compilation)
        for d in compilation.diagnostics:
            d.format()
        again = compile_folder(root)
    assert elapsed < HANG_GUARD_SECONDS, f"compile took {elapsed:.2f} s"
    assert fingerprint(compilation) == fingerprint(again)


@MUTATIONS
@given(st.sampled_from(sorted(KIT_SETS)), st.randoms(use_true_random=False))
def test_mutated_kit_sets_give_diagnostics_not_exceptions(name: str, rnd: random.Random) -> None:
    check_mutant(KIT_SETS[name], rnd)


@settings(MUTATIONS, max_examples=120)
@given(behavior_sets(), st.randoms(use_true_random=False))
def test_mutated_generated_sets_give_diagnostics_not_exceptions(generated: GeneratedSet, rnd: random.Random) -> None:
    files = {name: text.encode("utf-8") for name, text in generated.render().items()}
    check_mutant(files, rnd)


def fingerprints_for_seeds(count: int) -> str:
    """JSON of the fingerprints of ``count`` generated sets (every other one mutated) and the kit.

    Run in a subprocess by the hash-seed test below, hence plain ``random.Random`` seeds.
    """
    results: dict[str, tuple[str | None, list[str]]] = {}
    for seed in range(count):
        rnd = random.Random(seed)
        generated = Generator(rnd, options=rnd.randint(1, 6)).generate()
        files = {name: text.encode("utf-8") for name, text in generated.render().items()}
        if seed % 2:
            name = rnd.choice(sorted(files))
            files[name] = mutate(files[name], rnd)
        with behavior_folder(files) as root:
            results[f"generated-{seed}"] = fingerprint(compile_folder(root))
    for name, kit_files in KIT_SETS.items():
        with behavior_folder(kit_files) as root:
            results[name] = fingerprint(compile_folder(root))
    return json.dumps(results, sort_keys=True)


def test_output_does_not_depend_on_the_hash_seed() -> None:
    """Compiling twice in one process cannot see set-iteration order; other hash seeds can."""
    expected = fingerprints_for_seeds(20)
    root = Path(__file__).resolve().parents[2]
    for hash_seed in ("1", "12345"):
        script = "from tests.lang.test_properties import fingerprints_for_seeds as f; print(f(20))"
        result = subprocess.run(
            [sys.executable, "-c", script],
            cwd=root,
            env={**os.environ, "PYTHONHASHSEED": hash_seed},
            capture_output=True,
            text=True,
            check=True,
        )
        assert result.stdout.strip() == expected, f"PYTHONHASHSEED={hash_seed} changes the output"


# --------------------------------------------------------------------------------------------
# the tokenizer

_LEXEMES = [
    "option",
    "state",
    "@p",
    "a.b",
    "state_time-500",
    "1.5E3",
    "007",
    "1.",
    "/**/",
    "/***",
    "/*",
    "*/",
    "//",
    "\n",
    "\r\n",
    " ",
    '"',
    "[",
    "]",
    "&&",
    "||",
    "<=",
    "!",
    "é",
    "\x00",
    "\ufeff",
    "#",
    "{",
    "}",
    ";",
    "-",
    "/",
]


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.one_of(st.text(), st.lists(st.sampled_from(_LEXEMES)).map("".join)))
def test_tokenizer_never_raises_and_positions_never_go_back(text: str) -> None:
    diagnostics = Diagnostics()
    tokens = tokenize(text, "f.xabsl", diagnostics)
    assert tokens and tokens[-1].type is TokenType.EOF
    previous_end = 0
    for token in tokens:
        check_span(token.span, {"f.xabsl": text}, repr(token))
        assert token.span.start >= previous_end, f"{token!r} starts before {previous_end}"
        assert text[token.span.start : token.span.end] == token.text
        previous_end = token.span.end
    for d in diagnostics:
        assert d.code in CODES and d.span is not None
        check_span(d.span, {"f.xabsl": text}, d.format())
