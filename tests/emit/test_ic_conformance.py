"""Golden tests: every set of the conformance kit compiles to its expected.ic byte for byte."""

from __future__ import annotations

import os

import pytest

from tests.kit import KIT, SETS
from xabsl_studio.engine.emit.ic import emit_ic
from xabsl_studio.engine.lang import compile_file


@pytest.mark.parametrize("name", SETS)
def test_intermediate_code_is_byte_identical(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(KIT / name)
    compilation = compile_file("agents.xabsl")
    assert [d.format() for d in compilation.errors] == []
    assert compilation.program is not None
    produced = emit_ic(compilation.program).encode("utf-8")
    expected = (KIT / name / "expected.ic").read_bytes()
    if produced != expected:  # show a readable diff before failing
        import difflib

        diff = difflib.unified_diff(
            expected.decode().splitlines(), produced.decode().splitlines(), "expected.ic", "produced", lineterm=""
        )
        print("\n".join(list(diff)[:60]))
    assert produced == expected


#: every behavior set of the kit: a set that disappears (or a new one nobody looked at) fails
KIT_SETS = {
    "activation",
    "agents",
    "arithmetic",
    "cooperative",
    "decisions",
    "declarations",
    "demo-approach",
    "dotted-names",
    "input-functions",
    "logic",
    "outputs",
    "parameters",
}


def test_kit_has_all_twelve_sets() -> None:
    assert set(SETS) == KIT_SETS


def test_compiling_twice_gives_the_same_bytes(monkeypatch: pytest.MonkeyPatch) -> None:
    for name in SETS:
        monkeypatch.chdir(KIT / name)
        first = compile_file("agents.xabsl")
        second = compile_file(os.path.abspath("agents.xabsl"))
        assert first.program is not None and second.program is not None
        assert emit_ic(first.program) == emit_ic(second.program)
