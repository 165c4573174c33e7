"""Golden traces: every kit set, run from expected.ic and from the sources, tick by tick."""

from __future__ import annotations

import json

import pytest

from tests.kit import KIT, SETS
from tests.trace.kit_programs import MODES, lines, program
from xabsl_studio.engine.trace.conformance import TraceRunner


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("name", SETS)
def test_kit_trace(name: str, mode: str) -> None:
    runner = TraceRunner(program(name, mode))
    inputs = lines(KIT / name / "in.jsonl")
    expected = lines(KIT / name / "expected.out.jsonl")
    assert len(inputs) == len(expected)
    for number, (line, want) in enumerate(zip(inputs, expected, strict=True), start=1):
        got = runner.tick(line)
        if got != want:
            print(f"{name} ({mode}) tick {number} input {json.dumps(line)}")
            print(" got     ", json.dumps(got, sort_keys=True))
            print(" expected", json.dumps(want, sort_keys=True))
        assert got == want, f"{name} tick {number}"
