"""Long and deep expressions: long sums run; what CPython cannot compile is a LoadError, not a crash."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from tests.runtime.helpers import Host
from xabsl_studio.engine.lang import Compilation
from xabsl_studio.engine.runtime import LoadError

SYMBOLS = 'namespace s("S") { float input a; float output o; }\n'
AGENTS = 'include "s.xabsl";\ninclude "o.xabsl";\nagent x("X", o);\n'


def option(expression: str) -> str:
    return f"option o {{ initial state s {{ action {{ o = {expression}; }} }} }}\n"


def test_a_sum_of_400_terms_runs(compile_sources: Callable[..., Compilation]) -> None:
    # the parser builds a left-deep tree 400 levels deep; the generated code writes it flat
    compilation = compile_sources(
        {"agents.xabsl": AGENTS, "s.xabsl": SYMBOLS, "o.xabsl": option(" + ".join(["a"] * 400))}
    )
    assert compilation.program is not None
    host = Host(compilation.program)
    host.values["a"] = 0.5
    host.engine.execute(0)
    assert host.engine.output("o") == 200.0


def test_left_deep_mixed_chain_keeps_evaluation_order(compile_sources: Callable[..., Compilation]) -> None:
    compilation = compile_sources(
        {"agents.xabsl": AGENTS, "s.xabsl": SYMBOLS, "o.xabsl": option("a - 1 + 2 - a * 3 * 2")}
    )
    assert compilation.program is not None
    host = Host(compilation.program)
    host.values["a"] = 10.0
    host.engine.execute(0)
    assert host.engine.output("o") == 10.0 - 1 + 2 - 60.0


def test_nesting_beyond_cpython_is_a_load_error(compile_sources: Callable[..., Compilation]) -> None:
    deep = "(1 - " * 300 + "a" + ")" * 300  # right-nested: every level needs its parentheses
    compilation = compile_sources({"agents.xabsl": AGENTS, "s.xabsl": SYMBOLS, "o.xabsl": option(deep)})
    assert compilation.program is not None
    with pytest.raises(LoadError, match="nested too deeply"):
        Host(compilation.program)
