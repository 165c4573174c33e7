"""``xabsl trace`` input reading (issue 18): non-finite and out-of-range numbers, odd files."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from tests.kit import KIT
from xabsl_studio.engine.cli import main


@pytest.fixture
def agents_ic(tmp_path: Path) -> Path:
    shutil.copy(KIT / "agents" / "expected.ic", tmp_path / "agents.ic")
    return tmp_path / "agents.ic"


@pytest.mark.parametrize(
    ("value", "what"),
    [
        ("NaN", "NaN"),
        ("Infinity", "Infinity"),
        ("-Infinity", "-Infinity"),
        ("1e999", "1e999"),
        ("-1e400", "-1e400"),
        ("1" + "0" * 400, "out of range"),
        ("9" * 5000, "out of range"),  # a ValueError (4,300 digits) from json.loads before
    ],
)
def test_non_finite_numbers_exit_2_naming_the_tick(
    agents_ic: Path, capsys: pytest.CaptureFixture[str], value: str, what: str
) -> None:
    inputs = agents_ic.parent / "in.jsonl"
    inputs.write_text('{"t": 0}\n\n{"t": 50, "set": {"x": ' + value + "}}\n")
    out = agents_ic.parent / "out.jsonl"
    status = main(["trace", str(agents_ic), "--inputs", str(inputs), "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 2, err
    assert f"{inputs}:3: tick 2:" in err and what in err and len(err.strip().splitlines()) == 1, err
    assert not out.exists(), "nothing is written"


def test_a_non_finite_time_is_refused_too(agents_ic: Path, capsys: pytest.CaptureFixture[str]) -> None:
    inputs = agents_ic.parent / "in.jsonl"
    inputs.write_text('{"t": NaN}\n')
    assert main(["trace", str(agents_ic), "--inputs", str(inputs)]) == 2
    assert "tick 1" in capsys.readouterr().err


@pytest.mark.parametrize("kind", ["fifo", "/dev/zero", "latin-1", "deep"])
def test_unreadable_inputs_exit_2_with_one_line(agents_ic: Path, capsys: pytest.CaptureFixture[str], kind: str) -> None:
    inputs = agents_ic.parent / "in.jsonl"
    if kind == "fifo":
        os.mkfifo(inputs)
    elif kind == "/dev/zero":
        inputs = Path("/dev/zero")
    elif kind == "latin-1":
        inputs.write_bytes(b'{"t": 0, "agent": "caf\xe9"}\n')
    else:
        inputs.write_text('{"t": 0, "set": {"x": ' + "[" * 100_000 + "]" * 100_000 + "}}\n")
    status = main(["trace", str(agents_ic), "--inputs", str(inputs)])
    err = capsys.readouterr().err
    assert status == 2 and str(inputs) in err and len(err.strip().splitlines()) == 1, err


def test_a_computed_infinity_is_written_as_the_kit_writes_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Finite inputs whose sums and products overflow: the behavior's arithmetic, not bad input.

    The original engine and the kit's expected traces write ``Infinity``/``-Infinity``/``NaN``
    (issue 23: this used to exit 1).
    """
    import json
    import math

    folder = KIT / "arithmetic"
    lines = (folder / "in.jsonl").read_text().splitlines()
    first = json.loads(lines[0])
    decimals = [k for k, v in first.get("set", {}).items() if isinstance(v, float | int) and not isinstance(v, bool)]
    assert decimals, first
    first["set"] = {k: 1.7e308 for k in decimals}  # finite, but sums and products overflow
    inputs = tmp_path / "in.jsonl"
    inputs.write_text(json.dumps(first) + "\n")
    out = tmp_path / "out.jsonl"
    status = main(["trace", str(folder / "expected.ic"), "--inputs", str(inputs), "--out", str(out)])
    err = capsys.readouterr().err
    assert status == 0, err
    outputs = json.loads(out.read_text())["outputs"]
    assert any(isinstance(v, float) and not math.isfinite(v) for v in outputs.values()), outputs
    assert "Infinity" in out.read_text()
