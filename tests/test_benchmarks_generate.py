"""The compile-speed benchmark measures a behavior set that really compiles (no timings here)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

from xabsl_studio.engine.lang import compile_file

BENCHMARK = Path(__file__).resolve().parents[1] / "benchmarks" / "compile_speed.py"


def load_benchmark() -> ModuleType:
    """Import ``benchmarks/compile_speed.py`` by path (benchmarks/ is no package)."""
    spec = importlib.util.spec_from_file_location("compile_speed_benchmark", BENCHMARK)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def test_generated_benchmark_set_compiles_without_errors(tmp_path: Path) -> None:
    benchmark = load_benchmark()
    agents = benchmark.generate_behavior_set(tmp_path)
    compilation = compile_file(str(agents), base=str(tmp_path))
    assert not compilation.errors, "\n".join(d.format() for d in compilation.errors[:10])
    assert compilation.program is not None
    assert len(compilation.program.options) == benchmark.DEFAULT_OPTIONS
    # the benchmark is about a set of realistic size: about 200 KB in several files
    assert 150 * 1024 <= benchmark.source_size(tmp_path) <= 300 * 1024
    assert len(compilation.files) > 10


def test_generator_is_deterministic(tmp_path: Path) -> None:
    benchmark = load_benchmark()
    first, second = tmp_path / "first", tmp_path / "second"
    first.mkdir()
    second.mkdir()
    benchmark.generate_behavior_set(first, options=10)
    benchmark.generate_behavior_set(second, options=10)
    texts = [{p.relative_to(root): p.read_bytes() for p in root.rglob("*.xabsl")} for root in (first, second)]
    assert texts[0] == texts[1]


def test_team_shaped_set_compiles_without_errors(tmp_path: Path) -> None:
    benchmark = load_benchmark()
    agents = benchmark.generate_team_set(tmp_path)
    compilation = compile_file(str(agents), base=str(tmp_path))
    assert not compilation.errors, "\n".join(d.format() for d in compilation.errors[:10])
    program = compilation.program
    assert program is not None
    # shaped like the 197-file/180-option real set of issue 11
    assert len(program.options) == benchmark.TEAM_OPTIONS == 180
    assert len(compilation.files) == 197
    # every option is included through the options that call it, and called
    assert not [d for d in compilation.warnings if d.code == "unreachable-option"]
    # dotted names everywhere: parameters, enum elements, symbols
    assert any("." in p.short_name for o in program.options.values() for p in o.params)
    assert any("." in p.short_name for s in program.inputs.values() for p in s.params)
    assert any("." in e.removeprefix(n + ".") for n, enum in program.enums.items() for e in enum.elements)
    assert sum(bool(s.params) for s in program.inputs.values()) >= 100
    # long else-if chains
    depth = max(_chain(s.decision) for o in program.options.values() for s in o.states)
    assert depth >= 10


def _chain(tree: object) -> int:
    from xabsl_studio.engine import ir

    length = 0
    while isinstance(tree, ir.If):
        tree, length = tree.otherwise, length + 1
    return length
