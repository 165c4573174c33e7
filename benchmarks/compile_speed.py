"""How fast does the front end compile a realistic behavior set?

Generates (seeded, so every run compiles the same text) a behavior set the size of a real robot
soccer set: 100 options in about 200 KB of source, spread over several files with includes,
with symbols, enumerations, parameterised input symbols, deep decision trees and doc comments.
It then compiles it several times and prints the best time of each stage (parse, check from
``Compilation.timings``; IC emission timed here), their total, and the ratio against the
original Ruby compiler, which needs about 0.9 s for a real set of that size. The goal is a whole
compile (parse + check + emit) under 0.2 s.

Run::

    .venv/bin/python benchmarks/compile_speed.py            # timings
    .venv/bin/python benchmarks/compile_speed.py --profile  # plus a cProfile top 10

Never run from the test suite; ``tests/test_benchmarks_generate.py`` only checks that the
generated set compiles without errors.
"""

from __future__ import annotations

import argparse
import cProfile
import pstats
import random
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from engine.emit.ic import emit_ic  # noqa: E402
from engine.lang import Compilation, compile_file  # noqa: E402
from engine.lang.diagnostics import Diagnostics  # noqa: E402
from engine.lang.tokens import tokenize  # noqa: E402

#: the original Ruby compiler (xabsl.rb) on a real behavior set of about this size, seconds
RUBY_REFERENCE_SECONDS = 0.9
GOAL_SECONDS = 0.2
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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=7, help="compile this many times, keep the best")
    parser.add_argument("--seed", type=int, default=DEFAULT_SEED)
    parser.add_argument("--options", type=int, default=DEFAULT_OPTIONS)
    parser.add_argument("--profile", action="store_true", help="also print a cProfile top 10")
    args = parser.parse_args(argv)

    with tempfile.TemporaryDirectory(prefix="xabsl-bench-") as folder:
        agents = generate_behavior_set(Path(folder), args.seed, args.options)
        size_kb = source_size(Path(folder)) / 1024
        best, compilation = measure(agents, args.runs)
        assert compilation.program is not None
        files = len(compilation.files)
        print(
            f"behavior set: {len(compilation.program.options)} options, {files} files, {size_kb:.0f} KB "
            f"(seed {args.seed}), best of {args.runs} runs"
        )
        for stage in ("parse", "check", "emit"):
            print(f"  {stage:<6} {best[stage] * 1000:8.1f} ms")
        print(
            f"  {'total':<6} {best['total'] * 1000:8.1f} ms   (goal < {GOAL_SECONDS * 1000:.0f} ms: "
            f"{'met' if best['total'] < GOAL_SECONDS else 'MISSED'})"
        )
        ratio = RUBY_REFERENCE_SECONDS / best["total"]
        print(
            f"original Ruby compiler on a real set of this size: ~{RUBY_REFERENCE_SECONDS:.1f} s "
            f"-> this compiler is {ratio:.1f}x {'faster' if ratio >= 1 else 'slower'}"
        )
        if args.profile:
            lexing = tokenize_time(compilation, args.runs)
            print(f"  of which tokenizing {lexing * 1000:.1f} ms ({lexing / best['parse']:.0%} of parse)")
            profile(agents)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
