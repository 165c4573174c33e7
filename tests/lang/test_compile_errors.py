"""Golden tests: every compile-error case of the kit fails, writes nothing, and reports its first
error in the stated file at the stated line, with the original compiler's error number."""

from __future__ import annotations

import pytest

from tests.kit import ERROR_CASES, KIT, expected_error
from xabsl_studio.engine.lang import compile_file


@pytest.mark.parametrize("case", ERROR_CASES)
def test_first_error_at_expected_line(case: str, monkeypatch: pytest.MonkeyPatch) -> None:
    expected = expected_error(case)
    monkeypatch.chdir(KIT / "compile-errors" / case)
    compilation = compile_file("main.xabsl")
    print("\n".join(d.format() for d in compilation.diagnostics))
    assert compilation.program is None
    first = compilation.errors[0]
    assert first.file == expected["file"]
    if expected["line"] != "none":
        assert first.span is not None and first.span.line == int(expected["line"])
    assert first.original_code == expected["error"]


def test_kit_has_twenty_cases() -> None:
    assert len(ERROR_CASES) == 20
