"""Paths of the conformance kit (tests/conformance: the original toolchain's golden files)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
KIT = ROOT / "tests" / "conformance"
assert KIT.is_dir(), f"the conformance kit is missing: {KIT}"

#: behavior sets with agents.xabsl, expected.ic and traces
SETS = sorted(p.name for p in KIT.iterdir() if (p / "agents.xabsl").is_file())
#: single-mistake programs
ERROR_CASES = sorted(p.name for p in (KIT / "compile-errors").iterdir() if (p / "expected.txt").is_file())


def expected_error(case: str) -> dict[str, str]:
    """The header of a compile-error case: file, line ("none" or a number), error."""
    header = (KIT / "compile-errors" / case / "expected.txt").read_text().split("\n\n", 1)[0]
    return dict(line.split(": ", 1) for line in header.splitlines())
