"""The lint codes are one table: the compiler's, and the studio's copy that hides them."""

from __future__ import annotations

import re
from pathlib import Path

from xabsl_studio.engine.lang.diagnostics import CODES, LINT_CODES, Severity

WEB = Path(__file__).resolve().parents[2] / "web" / "src" / "panels" / "lintfilter.ts"


def test_the_studio_hides_the_codes_the_compiler_calls_lint() -> None:
    text = WEB.read_text()
    found = re.search(r"export const LINT_CODES[^=]*= new Set\(\[([^\]]*)\]\)", text)
    assert found, "LINT_CODES not found in lintfilter.ts"
    assert set(re.findall(r'"([a-z-]+)"', found.group(1))) == set(LINT_CODES)


def test_lint_is_what_the_original_compiler_does_not_print() -> None:
    # naming and parameter-missing are the original's own warnings, which it never prints
    assert {"naming", "parameter-missing"} <= LINT_CODES
    assert all(CODES[code][0] is Severity.WARNING for code in LINT_CODES)
    # the warnings it does print stay whatever --no-lint says
    assert not LINT_CODES & {"empty-namespace", "decision-must-start-with-else", "range-on-non-decimal"}
