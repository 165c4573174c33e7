"""Fixtures of the behavior-test tool's tests: suites on the bench world over a hand-made behavior."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

BEHAVIOR = Path(__file__).resolve().parent / "behavior"

#: go at 500 ms (tick 20 at 40 Hz): idle -> busy; level 20 at 1000 ms (tick 40): busy -> high.
HEAD = f"""
[suite]
name = "fixture"
path = "{BEHAVIOR}"
seed = 1
duration = 2
"""

INPUTS = (
    "inputs = [{ t = 0, set = { go = false, level = 5 } }, { t = 500, set = { go = true } }, "
    "{ t = 1000, set = { level = 20 } }]"
)


@pytest.fixture
def write_suite(tmp_path: Path) -> Callable[..., Path]:
    """``write_suite(body, name=...)``: a test file with the fixture head and ``body``."""

    def write(body: str, name: str = "fixture.xabsl-test.toml", head: str = HEAD) -> Path:
        path = tmp_path / name
        path.write_text(head + body, encoding="utf-8")
        return path

    return write


def one_test(expect: str, extra: str = "") -> str:
    """A suite body with one test driven by :data:`INPUTS` and the given expect tables."""
    return f"""
[[test]]
name = "t"
{INPUTS}
{extra}
{expect}
"""
