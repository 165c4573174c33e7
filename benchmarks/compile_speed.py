"""How fast does the front end compile a realistic behavior set, and how fast does ``xabsl`` start?

Generates (seeded, so every run compiles the same text) two behavior sets:

* **uniform**: 100 options in about 200 KB of source over 111 files, with symbols,
  enumerations, parameterised input symbols, deep decision trees and doc comments;
* **team**: shaped like the real team sets of issue 11: 180 options in 197 files (about
  880 KB), dotted names everywhere (symbols, enums, elements, parameters), many parameterized
  input symbols, long ``else if`` chains and a deep include graph (each option file includes
  the files of the options it calls).

For each set it prints the best in-process time of each stage (parse, check from
``Compilation.timings``; IC emission timed here) and the **whole process** ``xabsl compile
AGENTS --ic OUT`` (median of 5, interpreter start-up and imports included), against the original
Ruby compiler: about 0.9 s on a real set of the uniform set's size, 2.9 s on the 197-file real
set (goal: 5x faster, under 0.58 s). Last, ``xabsl --help`` against a bare ``python -c pass``,
both median of 9 in the same run (goal: at most twice).

Run::

    .venv/bin/python benchmarks/compile_speed.py                # timings, both sets
    .venv/bin/python benchmarks/compile_speed.py --set team     # only the team-shaped set
    .venv/bin/python benchmarks/compile_speed.py --profile      # plus a cProfile top 10

Never run from the test suite; ``tests/test_benchmarks_generate.py`` only checks that the
generated set compiles without errors.
"""

from __future__ import annotations

import argparse
import cProfile
import os
import pstats
import random
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from xabsl_studio.engine.emit.ic import emit_ic  # noqa: E402
from xabsl_studio.engine.lang import Compilation, compile_file  # noqa: E402
from xabsl_studio.engine.lang.diagnostics import Diagnostics  # noqa: E402
from xabsl_studio.engine.lang.tokens import tokenize  # noqa: E402

#: the original Ruby compiler (xabsl.rb) on a real behavior set of about this size, seconds
RUBY_REFERENCE_SECONDS = 0.9
GOAL_SECONDS = 0.2
#: the original Ruby compiler, whole process, on the real 197-file/180-option set (issue 11)
RUBY_TEAM_SECONDS = 2.9
#: whole-process goal on the team-shaped set: 5x faster than the Ruby compiler
TEAM_GOAL_SECONDS = RUBY_TEAM_SECONDS / 5
#: `xabsl --help` may take at most this many times a bare `python -c pass`
STARTUP_GOAL_RATIO = 2.0
DEFAULT_SEED = 1
DEFAULT_OPTIONS = 100

_WORDS = [
    "ball",
    "goal",
    "robot",
    "team",
    "mate",
    "opponent",
    "field",
    "line",
    "kick",
    "pass",
    "walk",
    "turn",
    "stand",
    "search",
    "approach",
    "defend",
    "attack",
    "keeper",
    "striker",
    "position",
    "angle",
    "distance",
    "speed",
    "time",
    "state",
    "phase",
]


class _SetWriter:
    """Writes one behavior set: every rule of xabsl-language.md §1.3/§1.4 respected."""

    def __init__(self, rnd: random.Random, options: int) -> None:
        self.rnd = rnd
        self.option_count = options
        self.enums: dict[str, list[str]] = {}
        #: readable symbols by kind ("d", "b" or an enum name); assignable ones separately
        self.readable: dict[str, list[str]] = {}
        self.assignable: dict[str, list[str]] = {}
        self.constants: list[str] = []
        #: input functions by result kind: (name, [(param, kind)])
        self.functions: dict[str, list[tuple[str, list[tuple[str, str]]]]] = {}
        self.behaviors: list[tuple[str, list[tuple[str, str]]]] = []
        self.option_params: list[list[tuple[str, str]]] = []
        self.params: list[tuple[str, str]] = []

    # -- helpers ---------------------------------------------------------------------------

    def doc(self, indent: str, p: float = 0.4) -> str:
        if self.rnd.random() >= p:
            return ""
        words = " ".join(self.rnd.choice(_WORDS) for _ in range(self.rnd.randint(4, 14)))
        return f"{indent}/** {words.capitalize()}. */\n"

    def kind(self) -> str:
        return self.rnd.choice(["d", "d", "d", "b", "b", *self.enums])

    @staticmethod
    def type_text(kind: str) -> str:
        return {"d": "float", "b": "bool"}.get(kind, f"enum {kind}")

    def number(self) -> str:
        value = self.rnd.randint(0, 3000)
        return str(value) if self.rnd.random() < 0.6 else f"{value}.{self.rnd.randint(0, 99)}"

    def param_block(self, params: list[tuple[str, str]], at: str, indent: str) -> str:
        out = []
        for name, kind in params:
            extra = f' [0..{self.rnd.randint(1, 9) * 1000}] "mm"' if kind == "d" else ""
            out.append(f"{self.doc(indent, 0.3)}{indent}{self.type_text(kind)} {at}{name}{extra};\n")
        return "".join(out)

    # -- namespaces ------------------------------------------------------------------------

    def symbols_file(self, index: int, topic: str) -> str:
        out = [f'/** Symbols about the {topic}. */\nnamespace {topic}_symbols("{topic.title()} symbols") {{\n']
        for i in range(2):
            name = f"{topic}.mode{i}"
            self.enums[name] = [f"{topic}_m{i}_{w}" for w in self.rnd.sample(_WORDS, self.rnd.randint(3, 7))]
            out.append(f"{self.doc('  ')}  enum {name} {{ {', '.join(self.enums[name])} }};\n")
        for i in range(5):
            name = f"{topic}.k{i}"
            self.constants.append(name)
            out.append(f'{self.doc("  ")}  float const {name} = {self.number()} "mm";\n')
        for block, io in enumerate(("input", "input", "output", "internal")):
            for i in range(8):
                kind = self.kind()
                name = f"{topic}.{io}.{self.rnd.choice(_WORDS)}{index}_{block}{i}"
                self.readable.setdefault(kind, []).append(name)
                if io != "input":
                    self.assignable.setdefault(kind, []).append(name)
                extra = ' [0..9000] "mm"' if kind == "d" else ""
                out.append(f"{self.doc('  ')}  {self.type_text(kind)} {io} {name}{extra};\n")
        for i in range(4):
            kind = self.rnd.choice(["d", "d", "b", *self.enums])
            params = [(f"v{j}", self.rnd.choice(["d", "d", "b"])) for j in range(self.rnd.randint(1, 3))]
            name = f"{topic}.fn{i}"
            self.functions.setdefault(kind, []).append((name, params))
            out.append(f"{self.doc('  ')}  {self.type_text(kind)} input {name} (\n")
            out.append(self.param_block(params, "", "    "))
            out.append("  );\n")
        out.append("}\n")
        return "".join(out)

    def behaviors_file(self) -> str:
        out = ['/** What the platform can do. */\nnamespace skills("Basic behaviors") {\n']
        for i in range(20):
            params = [(f"p{j}", self.kind()) for j in range(self.rnd.randint(0, 3))]
            name = f"skill.{self.rnd.choice(_WORDS)}{i}"
            self.behaviors.append((name, params))
            out.append(f"{self.doc('  ')}  behavior {name} {{\n{self.param_block(params, '', '    ')}  }}\n")
        out.append("}\n")
        return "".join(out)

    # -- typed expressions -------------------------------------------------------------------

    def leaves(self, kind: str) -> list[str]:
        found = list(self.readable.get(kind, [])) + [f"@{n}" for n, k in self.params if k == kind]
        if kind == "d":
            found += [*self.constants, "state_time", "option_time"]
        return found

    def call(self, kind: str, depth: int) -> str | None:
        functions = self.functions.get(kind)
        if not functions:
            return None
        name, params = self.rnd.choice(functions)
        return f"{name}({self.args(params, depth - 1)})"

    def args(self, params: list[tuple[str, str]], depth: int) -> str:
        return ", ".join(f"{name} = {self.expr(kind, depth)}" for name, kind in params)

    def expr(self, kind: str, depth: int) -> str:
        if kind == "d":
            return self.decimal(depth)
        if kind == "b":
            return self.boolean(depth)
        return self.enum_value(kind, depth)

    def decimal(self, depth: int) -> str:
        choice = self.rnd.randrange(8) if depth > 0 else self.rnd.randrange(2)
        if choice == 0:
            return self.number()
        if choice <= 2:
            return self.rnd.choice(self.leaves("d"))
        if choice <= 5:
            op = self.rnd.choice("+-*/")
            return f"({self.decimal(depth - 1)} {op} {self.decimal(depth - 1)})"
        if choice == 6:
            return self.call("d", depth) or self.number()
        return f"({self.boolean(depth - 1)} ? {self.decimal(depth - 1)} : {self.decimal(depth - 1)})"

    def boolean(self, depth: int) -> str:
        choice = self.rnd.randrange(9) if depth > 0 else 0
        if choice == 0:
            return self.rnd.choice(self.leaves("b") or ["true"])
        if choice == 1:
            return f"!{self.rnd.choice(self.leaves('b') or ['false'])}"
        if choice <= 3:
            op = self.rnd.choice(["&&", "||"])
            return f"({self.boolean(depth - 1)} {op} {self.boolean(depth - 1)})"
        if choice <= 5:
            op = self.rnd.choice(["<", ">", "<=", ">=", "==", "!="])
            return f"{self.decimal(depth - 1)} {op} {self.decimal(depth - 1)}"
        if choice <= 7:
            enum = self.rnd.choice(list(self.enums))
            refs = self.leaves(enum)
            if refs:
                return f"{self.rnd.choice(refs)} {self.rnd.choice(['==', '!='])} {self.enum_value(enum, 0)}"
        return self.call("b", depth) or "action_done"

    def enum_value(self, enum: str, depth: int) -> str:
        if depth > 0 and self.rnd.random() < 0.2:
            return f"({self.boolean(depth - 1)} ? {self.enum_value(enum, 0)} : {self.enum_value(enum, 0)})"
        return self.rnd.choice(self.enums[enum] + self.leaves(enum))

    # -- options ---------------------------------------------------------------------------

    def dtree(self, states: list[str], depth: int, indent: str) -> str:
        if depth <= 0 or self.rnd.random() < 0.15:
            return f"{indent}stay;\n" if self.rnd.random() < 0.3 else f"{indent}goto {self.rnd.choice(states)};\n"
        inner = indent + "  "
        return (
            f"{self.doc(indent, 0.25)}{indent}if ({self.boolean(1)}) {{\n"
            f"{self.dtree(states, depth - 1, inner)}{indent}}}\n"
            f"{self.doc(indent, 0.1)}{indent}else {{\n{self.dtree(states, depth - 1, inner)}{indent}}}\n"
        )

    def actions(self, index: int, indent: str) -> str:
        out = []
        for _ in range(self.rnd.randint(1, 2)):
            kind = self.rnd.choice([k for k in self.assignable if self.assignable[k]])
            out.append(f"{indent}{self.rnd.choice(self.assignable[kind])} = {self.expr(kind, 1)};\n")
        callees = range(index + 1, self.option_count)
        if callees and self.rnd.random() < 0.8:
            callee = self.rnd.choice(callees)
            out.append(f"{indent}opt{callee:03d}({self.args(self.option_params[callee], 1)});\n")
        else:
            name, params = self.rnd.choice(self.behaviors)
            out.append(f"{indent}{name}({self.args(params, 2)});\n")
        return "".join(out)

    def option_file(self, index: int) -> str:
        self.params = self.option_params[index]
        states = [f"{self.rnd.choice(_WORDS)}_{i}" for i in range(self.rnd.randint(2, 4))]
        common = self.rnd.random() < 0.4
        out = [self.doc("", 1.0), f"option opt{index:03d} {{\n", self.param_block(self.params, "@", "  ")]
        if common:
            out.append("  common decision {\n")
            out.append(f"    if ({self.boolean(2)}) goto {states[0]};\n")
            out.append(f"    else if ({self.boolean(2)}) {{\n{self.dtree(states, 2, '      ')}    }}\n  }}\n")
        for i, state in enumerate(states):
            flags = ("initial " if i == 0 else "") + ("target " if i == len(states) - 1 else "")
            out.append(f"  {flags}state {state} {{\n    decision {{\n")
            if common:
                out.append("      else\n")
            # mostly shallow trees, now and then a deep one
            out.append(self.dtree(states, self.rnd.choice([1, 1, 1, 1, 2, 2, 4]), "      "))
            out.append(f"    }}\n    action {{\n{self.actions(index, '      ')}    }}\n  }}\n")
        out.append("}\n")
        return "".join(out)

    def write(self, root: Path) -> Path:
        topics = ["ball", "robot", "team", "game"]
        files = {f"symbols/{t}.xabsl": self.symbols_file(i, t) for i, t in enumerate(topics)}
        files["skills.xabsl"] = self.behaviors_file()
        self.option_params = [
            [(f"a{j}", self.kind()) for j in range(self.rnd.randint(0, 3))] for _ in range(self.option_count)
        ]
        groups: dict[int, list[str]] = {}
        for index in range(self.option_count):
            files[f"options/g{index % 5}/opt{index:03d}.xabsl"] = self.option_file(index)
            groups.setdefault(index % 5, []).append(f"g{index % 5}/opt{index:03d}.xabsl")
        # group files hold only includes, as real sets do
        for group, members in groups.items():
            files[f"options/group{group}.xabsl"] = "".join(f'include "{m}";\n' for m in members)
        includes = [
            *(f"symbols/{t}.xabsl" for t in topics),
            "skills.xabsl",
            *(f"options/group{g}.xabsl" for g in groups),
        ]
        roots = ["opt000", *(f"opt{i:03d}" for i in range(1, self.option_count) if i % 20 == 0)]
        files["agents.xabsl"] = (
            "/*** Title: Benchmark set\n     Platform: any\n     Software-Environment: compile_speed.py\n*/\n"
            + "".join(f'include "{i}";\n' for i in includes)
            + "".join(f'/** Agent {i}. */\nagent agent{i}("Agent {i}", {r});\n' for i, r in enumerate(roots))
        )
        for name, text in files.items():
            path = root / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")
        return root / "agents.xabsl"


#: topics of the team-shaped set's symbol namespaces (one file each)
_TEAM_TOPICS = [
    "ball",
    "robot_pose",
    "game",
    "team",
    "motion",
    "head",
    "sound",
    "obstacles",
    "goal",
    "fieldlines",
    "kick",
    "role",
]
#: option folders of the team-shaped set
_TEAM_AREAS = ["soccer", "striker", "keeper", "defender", "supporter", "search", "kicks", "standard", "tools"]
#: declared parameter names of input functions, basic behaviors and options (dots as real sets have)
_PARAM_NAMES = [
    "x",
    "y",
    "angle",
    "robot.x",
    "robot.y",
    "offset.x",
    "offset.y",
    "value",
    "min",
    "max",
    "speed.max",
    "distance.min",
    "time.out",
    "target.x",
    "state.hold",
]


class _TeamSetWriter(_SetWriter):
    """A set shaped like real team sets (issue 11): dotted names everywhere, many parameterized
    input symbols, long ``else if`` chains, and a deep include graph in which every option file
    includes the files of the options it calls (reached from the agents file through them)."""

    def __init__(self, rnd: random.Random, options: int) -> None:
        super().__init__(rnd, options)
        self.internal_enums: dict[str, list[str]] = {}
        self.names: list[str] = []

    def enum_value(self, enum: str, depth: int) -> str:
        elements = self.enums.get(enum) or self.internal_enums[enum]
        if depth > 0 and self.rnd.random() < 0.2:
            return f"({self.boolean(depth - 1)} ? {self.enum_value(enum, 0)} : {self.enum_value(enum, 0)})"
        if self.rnd.random() < 0.2:  # written in full now and then
            return f"{enum}.{self.rnd.choice(elements)}"
        return self.rnd.choice(elements + self.leaves(enum))

    def dotted(self, topic: str, i: int) -> str:
        parts = self.rnd.sample(_WORDS, self.rnd.randint(1, 3))
        return ".".join([topic, *parts]) + f".n{i}"

    def param_names(self, count: int) -> list[str]:
        return self.rnd.sample(_PARAM_NAMES, count)

    def symbols_file(self, index: int, topic: str) -> str:
        out = [f'/** Symbols about the {topic}. */\nnamespace {topic}_symbols("{topic.title()} symbols") {{\n']
        for i in range(3):
            name = f"{topic}.mode{i}" if i else topic.replace("_", ".") + ".state"
            words = self.rnd.sample(_ELEMENT_WORDS, self.rnd.randint(3, 7))
            elements = [w if k % 3 else f"{w}.{self.rnd.choice(_WORDS)}" for k, w in enumerate(words)]
            if i == 2:  # internal: only internal symbols have it (kept out of `kind()`)
                self.internal_enums[name] = elements
                out.append(f"{self.doc('  ')}  enum {name} internal {{ {', '.join(elements)} }};\n")
                symbol = f"{topic}.memory.phase"
                out.append(f"  enum {name} internal {symbol};\n")
                self.readable.setdefault(name, []).append(symbol)
                self.assignable.setdefault(name, []).append(symbol)
                continue
            self.enums[name] = elements
            out.append(f"{self.doc('  ')}  enum {name} {{ {', '.join(elements)} }};\n")
        for i in range(6):
            name = f"{topic}.const.{self.rnd.choice(_WORDS)}{i}"
            self.constants.append(name)
            out.append(f'{self.doc("  ")}  float const {name} = {self.number()} "mm";\n')
        for io, count in (("input", 22), ("output", 10), ("internal", 4)):
            for i in range(count):
                kind = self.kind()
                name = self.dotted(f"{topic}.{io[:2]}", i)
                self.readable.setdefault(kind, []).append(name)
                if io != "input":
                    self.assignable.setdefault(kind, []).append(name)
                extra = ' [0..9000] "mm"' if kind == "d" else ""
                out.append(f"{self.doc('  ')}  {self.type_text(kind)} {io} {name}{extra};\n")
        for i in range(9):
            kind = self.rnd.choice(["d", "d", "d", "b", *self.enums])
            names = self.param_names(self.rnd.randint(1, 4))
            params = [(n, self.rnd.choice(["d", "d", "b", *self.enums])) for n in names]
            name = self.dotted(f"{topic}.fn", i)
            self.functions.setdefault(kind, []).append((name, params))
            out.append(f"{self.doc('  ')}  {self.type_text(kind)} input {name} (\n")
            out.append(self.param_block(params, "", "    "))
            out.append("  );\n")
        out.append("}\n")
        return "".join(out)

    def behaviors_file(self, part: int = 0) -> str:
        out = [f'/** What the platform can do, part {part}. */\nnamespace skills{part}("Basic behaviors") {{\n']
        for i in range(25):
            params = [(n, self.kind()) for n in self.param_names(self.rnd.randint(0, 5))]
            name = f"skill{part}.{self.rnd.choice(_WORDS)}.{self.rnd.choice(_WORDS)}{i}"
            self.behaviors.append((name, params))
            out.append(f"{self.doc('  ')}  behavior {name} {{\n{self.param_block(params, '', '    ')}  }}\n")
        out.append("}\n")
        return "".join(out)

    def chain(self, states: list[str], branches: int, indent: str) -> str:
        """A long ``if / else if / ... / else`` chain, now and then with a braced sub-tree."""
        out = []
        for i in range(branches):
            head = "if" if i == 0 else "else if"
            condition = self.boolean(self.rnd.choice([1, 1, 1, 2]))
            out.append(f"{self.doc(indent, 0.15)}{indent}{head} ({condition})")
            if self.rnd.random() < 0.2:
                inner = indent + "  "
                out.append(f" {{\n{self.dtree(states, 2, inner)}{indent}}}\n")
            else:
                out.append(f" goto {self.rnd.choice(states)};\n")
        out.append(f"{indent}else {'stay;' if self.rnd.random() < 0.7 else 'goto ' + states[0] + ';'}\n")
        return "".join(out)

    def team_actions(self, callees: list[int], indent: str) -> str:
        out = []
        for _ in range(self.rnd.randint(1, 3)):
            kind = self.rnd.choice([k for k in self.assignable if self.assignable[k]])
            out.append(f"{indent}{self.rnd.choice(self.assignable[kind])} = {self.expr(kind, 2)};\n")
        for callee in callees:
            out.append(f"{indent}{self.names[callee]}({self.args(self.option_params[callee], 2)});\n")
        for _ in range(self.rnd.randint(0, 2)):
            name, params = self.rnd.choice(self.behaviors)
            out.append(f"{indent}{name}({self.args(params, 2)});\n")
        return "".join(out)

    def team_option(self, index: int, callees: list[int], includes: list[str]) -> str:
        self.params = self.option_params[index]
        states = [f"{self.rnd.choice(_WORDS)}_{i}" for i in range(self.rnd.randint(2, 6))]
        common = self.rnd.random() < 0.4
        out = [*(f'include "{i}";\n' for i in includes), self.doc("", 1.0)]
        out += [f"option {self.names[index]} {{\n", self.param_block(self.params, "@", "  ")]
        if common:
            # a chain without its final `else`: the common decision tree's shape
            branches = self.chain(states, self.rnd.randint(1, 4), "    ").rsplit("else", 1)[0]
            out.append(f"  common decision {{\n{branches}")
            out.append("  }\n")
        for i, state in enumerate(states):
            flags = ("initial " if i == 0 else "") + ("target " if i == len(states) - 1 else "")
            out.append(f"  {flags}state {state} {{\n    decision {{\n")
            if common:
                out.append("      else\n")
            out.append(self.chain(states, self.rnd.choice([1, 1, 2, 2, 3, 4, 5, 10]), "      "))
            # the callees spread over the states: every included option is called
            called = callees[i :: len(states)]
            out.append(f"    }}\n    action {{\n{self.team_actions(called, '      ')}    }}\n  }}\n")
        out.append("}\n")
        return "".join(out)

    def write(self, root: Path) -> Path:
        files = {f"Symbols/{t}_symbols.xabsl": self.symbols_file(i, t) for i, t in enumerate(_TEAM_TOPICS)}
        files["BasicBehaviors/skills0.xabsl"] = self.behaviors_file(0)
        files["BasicBehaviors/skills1.xabsl"] = self.behaviors_file(1)
        files["Symbols/symbols.xabsl"] = "".join(f'include "{t}_symbols.xabsl";\n' for t in _TEAM_TOPICS)
        files["BasicBehaviors/skills.xabsl"] = 'include "skills0.xabsl";\ninclude "skills1.xabsl";\n'
        count = self.option_count
        area = [_TEAM_AREAS[i * len(_TEAM_AREAS) // count] for i in range(count)]
        self.names = [f"{area[i]}_{self.rnd.choice(_WORDS)}_{i:03d}" for i in range(count)]
        self.option_params = [
            [(n, self.kind()) for n in self.param_names(self.rnd.randint(0, 5))] for _ in range(count)
        ]
        # every option but the first is called by one of the ten before it, so the include graph
        # (each option file includes its callees' files) is deep and reaches every option
        callees: list[list[int]] = [[] for _ in range(count)]
        for j in range(1, count):
            caller = callees[self.rnd.randrange(max(0, j - 10), j)]
            if j not in caller:
                caller.append(j)
            for _ in range(self.rnd.randint(0, 2)):
                extra = self.rnd.randrange(j + 1, count) if j + 1 < count else None
                if extra is not None and extra not in callees[j]:
                    callees[j].append(extra)
        for i in range(count):
            includes = [f"../{area[j]}/{self.names[j]}.xabsl" for j in callees[i]]
            if self.rnd.random() < 0.3:  # a redundant include of symbols, skipped as already read
                includes.append(f"../../Symbols/{self.rnd.choice(_TEAM_TOPICS)}_symbols.xabsl")
            files[f"Options/{area[i]}/{self.names[i]}.xabsl"] = self.team_option(i, callees[i], includes)
        roots = [0, *(i for i in range(1, count) if i % 30 == 0)]
        files["agents.xabsl"] = (
            "/*** Title: Team-shaped benchmark set\n     Platform: any\n*/\n"
            'include "Symbols/symbols.xabsl";\ninclude "BasicBehaviors/skills.xabsl";\n'
            + "".join(f'include "Options/{area[r]}/{self.names[r]}.xabsl";\n' for r in roots)
            + "".join(
                f'/** Agent {i}. */\nagent agent{i}("Agent {i}", {self.names[r]});\n' for i, r in enumerate(roots)
            )
        )
        for name, text in files.items():
            path = root / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")
        return root / "agents.xabsl"


#: enum element words: no keyword among them (``state`` is one)
_ELEMENT_WORDS = [w for w in _WORDS if w not in ("state",)] + ["idle", "ready", "playing", "finished"]

#: options of the team-shaped set (with 17 other files: 197 files, as the real set of issue 11)
TEAM_OPTIONS = 180


def generate_team_set(root: Path, seed: int = DEFAULT_SEED, options: int = TEAM_OPTIONS) -> Path:
    """Write the team-shaped behavior set into ``root``; returns its agents file.

    Shaped like real team sets: 180 options in 197 files, dotted names everywhere (symbols,
    enums, enum elements, parameters), many parameterized input symbols, long ``else if`` chains
    and a deep include graph. The same seed always writes the same files.
    """
    return _TeamSetWriter(random.Random(seed), options).write(root)


def generate_behavior_set(root: Path, seed: int = DEFAULT_SEED, options: int = DEFAULT_OPTIONS) -> Path:
    """Write the benchmark's behavior set into ``root``.

    Args:
        root: an existing (normally empty) folder.
        seed: the random seed; the same seed always writes the same files.
        options: how many options to write (100 gives about 200 KB of source).

    Returns:
        the path of the agents file, ``root / "agents.xabsl"``.
    """
    return _SetWriter(random.Random(seed), options).write(root)


def source_size(root: Path) -> int:
    """Bytes of ``.xabsl`` source below ``root``."""
    return sum(p.stat().st_size for p in root.rglob("*.xabsl"))


def measure(agents: Path, runs: int) -> tuple[dict[str, float], Compilation]:
    """Best-of-``runs`` seconds per stage (parse, check, emit) and the last compilation."""
    best = {"parse": float("inf"), "check": float("inf"), "emit": float("inf"), "total": float("inf")}
    compilation: Compilation | None = None
    for _ in range(runs):
        compilation = compile_file(str(agents), base=str(agents.parent))
        if compilation.program is None:
            errors = "\n".join(d.format() for d in compilation.errors[:10])
            raise SystemExit(f"the generated set does not compile:\n{errors}")
        started = time.perf_counter()
        emit_ic(compilation.program)
        emit = time.perf_counter() - started
        stages = {**compilation.timings, "emit": emit}
        stages["total"] = stages["parse"] + stages["check"] + emit
        for stage, seconds in stages.items():
            best[stage] = min(best[stage], seconds)
    assert compilation is not None
    return best, compilation


def tokenize_time(compilation: Compilation, runs: int) -> float:
    """Best-of-``runs`` seconds to tokenize every source text (the share of "parse" spent lexing)."""
    texts = list(compilation.sources.items())
    best = float("inf")
    for _ in range(runs):
        started = time.perf_counter()
        for name, text in texts:
            tokenize(text, name, Diagnostics())
        best = min(best, time.perf_counter() - started)
    return best


def profile(agents: Path, top: int = 10) -> None:
    """Print the ``top`` functions by cumulative and by own time of one compile + emit."""
    profiler = cProfile.Profile()
    profiler.enable()
    compilation = compile_file(str(agents), base=str(agents.parent))
    assert compilation.program is not None
    emit_ic(compilation.program)
    profiler.disable()
    stats = pstats.Stats(profiler).strip_dirs()
    print(f"\ncProfile, top {top} by own time:")
    stats.sort_stats("tottime").print_stats(top)
    print(f"cProfile, top {top} by cumulative time:")
    stats.sort_stats("cumulative").print_stats(top)


def _environment() -> dict[str, str]:
    """The environment of the child processes: this checkout's code first on the path."""
    path = os.environ.get("PYTHONPATH", "")
    return {**os.environ, "PYTHONPATH": str(ROOT) + (os.pathsep + path if path else "")}


def xabsl_command() -> list[str]:
    """How a user starts ``xabsl``: the console script beside this interpreter, else ``-m``."""
    script = Path(sys.executable).with_name("xabsl")
    return [str(script)] if script.is_file() else [sys.executable, "-m", "xabsl_studio.engine.cli"]


def process_seconds(command: list[str], runs: int, cwd: Path | None = None) -> tuple[float, float]:
    """Median wall-clock and median CPU (user + system) seconds of ``runs`` runs of ``command``.

    Start-up included. The CPU time is the child's own, so it stays meaningful on a machine
    that other work keeps busy (where the wall clock also counts the waiting).
    """
    walls, cpus = [], []
    env = _environment()
    for _ in range(runs):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        started = time.perf_counter()
        subprocess.run(command, cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        walls.append(time.perf_counter() - started)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return statistics.median(walls), statistics.median(cpus)


def whole_compile_seconds(agents: Path, runs: int = 5) -> tuple[float, float]:
    """Median wall and CPU seconds of the whole process ``xabsl compile AGENTS --ic OUT``."""
    with tempfile.TemporaryDirectory(prefix="xabsl-bench-out-") as out:
        command = [*xabsl_command(), "compile", agents.name, "--ic", str(Path(out) / "out.ic")]
        return process_seconds(command, runs, cwd=agents.parent)


def startup_seconds(runs: int = 9) -> tuple[float, float]:
    """Median wall seconds of ``xabsl --help`` and of ``python -c pass``, measured alternately."""
    help_times, bare_times = [], []
    for _ in range(runs):
        help_times.append(process_seconds([*xabsl_command(), "--help"], 1)[0])
        bare_times.append(process_seconds([sys.executable, "-c", "pass"], 1)[0])
    return statistics.median(help_times), statistics.median(bare_times)


def report_set(name: str, agents: Path, runs: int, ruby_seconds: float, goal_seconds: float | None) -> None:
    """Print the in-process stages and the whole-process time of one generated set."""
    size_kb = source_size(agents.parent) / 1024
    best, compilation = measure(agents, runs)
    assert compilation.program is not None
    print(
        f"{name} set: {len(compilation.program.options)} options, {len(compilation.files)} files, "
        f"{size_kb:.0f} KB, best of {runs} in-process runs"
    )
    for stage in ("parse", "check", "emit"):
        print(f"  {stage:<6} {best[stage] * 1000:8.1f} ms")
    print(f"  {'total':<6} {best['total'] * 1000:8.1f} ms")
    whole, cpu = whole_compile_seconds(agents)
    ratio = ruby_seconds / whole
    verdict = (
        "" if goal_seconds is None else f", goal < {goal_seconds:.2f} s: {'met' if whole < goal_seconds else 'MISSED'}"
    )
    print(
        f"  whole process `xabsl compile --ic`: {whole * 1000:.0f} ms, CPU {cpu * 1000:.0f} ms"
        f" (medians of 5){verdict}; "
        f"the Ruby compiler ~{ruby_seconds:.1f} s -> {ratio:.1f}x {'faster' if ratio >= 1 else 'slower'}"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=7, help="compile this many times in-process, keep the best")
    parser.add_argument("--seed", type=int, default=DEFAULT_SEED)
    parser.add_argument("--options", type=int, default=DEFAULT_OPTIONS, help="options of the uniform set")
    parser.add_argument("--set", choices=("both", "uniform", "team"), default="both", help="which set to measure")
    parser.add_argument("--profile", action="store_true", help="also print a cProfile top 10 (of the last set)")
    args = parser.parse_args(argv)

    with tempfile.TemporaryDirectory(prefix="xabsl-bench-") as folder:
        last: Path | None = None
        if args.set in ("both", "uniform"):
            uniform = Path(folder) / "uniform"
            uniform.mkdir()
            last = generate_behavior_set(uniform, args.seed, args.options)
            report_set("uniform", last, args.runs, RUBY_REFERENCE_SECONDS, None)
        if args.set in ("both", "team"):
            team = Path(folder) / "team"
            team.mkdir()
            last = generate_team_set(team, args.seed)
            report_set("team-shaped", last, args.runs, RUBY_TEAM_SECONDS, TEAM_GOAL_SECONDS)
        started, bare = startup_seconds()
        ratio = started / bare
        print(
            f"start-up: `xabsl --help` {started * 1000:.0f} ms, `python -c pass` {bare * 1000:.0f} ms "
            f"(median of 9) -> {ratio:.2f}x (goal <= {STARTUP_GOAL_RATIO:g}x: "
            f"{'met' if ratio <= STARTUP_GOAL_RATIO else 'MISSED'})"
        )
        if args.profile and last is not None:
            best, compilation = measure(last, 1)
            lexing = tokenize_time(compilation, args.runs)
            print(f"  of which tokenizing {lexing * 1000:.1f} ms ({lexing / best['parse']:.0%} of parse)")
            profile(last)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
