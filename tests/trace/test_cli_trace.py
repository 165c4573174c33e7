"""``xabsl trace``: golden output on kit sets and one clear line (exit 2) for every bad input."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from tests.kit import KIT
from tests.trace.kit_programs import lines
from xabsl_studio.engine.cli import main


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    status = main(list(argv))
    captured = capsys.readouterr()
    return status, captured.out, captured.err


@pytest.mark.parametrize("source", ["expected.ic", "agents.xabsl"])
def test_trace_writes_the_expected_trace(source: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = KIT / "agents"
    out = tmp_path / "out.jsonl"
    status, _, err = run(capsys, "trace", str(folder / source), "--inputs", str(folder / "in.jsonl"), "--out", str(out))
    print(err)
    assert status == 0
    assert lines(out) == lines(folder / "expected.out.jsonl")


def test_trace_to_stdout_with_declarations(capsys: pytest.CaptureFixture[str]) -> None:
    folder = KIT / "input-functions"
    status, out, err = run(
        capsys,
        "trace",
        str(folder / "expected.ic"),
        "--inputs",
        str(folder / "in.jsonl"),
        "--declarations",
        str(folder / "agents.xabsl"),
    )
    assert status == 0, err
    got = [json.loads(line) for line in out.splitlines()]
    assert got == lines(folder / "expected.out.jsonl")


def test_agent_option_selects_before_the_first_tick(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = KIT / "agents"
    (tmp_path / "in.jsonl").write_text('{"t": 0}\n')
    status, out, _ = run(
        capsys, "trace", str(folder / "expected.ic"), "--inputs", str(tmp_path / "in.jsonl"), "--agent", "other"
    )
    assert status == 0
    assert json.loads(out)["tree"][0]["option"] == "beta"


@pytest.fixture
def agents_ic(tmp_path: Path) -> Path:
    shutil.copy(KIT / "agents" / "expected.ic", tmp_path / "agents.ic")
    return tmp_path / "agents.ic"


BAD_INPUTS = {
    "unknown-symbol": ('{"t": 0, "set": {"nope": 1}}', "unknown input symbol 'nope'"),
    "wrong-type": ('{"t": 0, "set": {"x": true}}', "'x' is decimal"),
    "bool-as-number": ('{"t": 0, "set": {"hold": 1}}', "'hold' is boolean"),
    "unknown-agent": ('{"t": 0, "agent": "nobody"}', "unknown agent 'nobody'"),
    "not-json": ("{t: 0}", "not JSON"),
    "missing-time": ('{"set": {"x": 1}}', "'t' must be an integer"),
}


@pytest.mark.parametrize("case", BAD_INPUTS, ids=list(BAD_INPUTS))
def test_bad_input_exits_2_with_one_line(case: str, agents_ic: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text, message = BAD_INPUTS[case]
    inputs = agents_ic.parent / "in.jsonl"
    inputs.write_text('{"t": 0}\n' + text + "\n")
    status, out, err = run(capsys, "trace", str(agents_ic), "--inputs", str(inputs))
    print(err)
    assert status == 2
    assert out == ""
    assert len(err.strip().splitlines()) == 1 and message in err and "Traceback" not in err


def test_parameterized_and_unqualified_enum_inputs_are_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = KIT / "input-functions"
    for text, message in (
        ('{"t": 0, "set": {"f": 1}}', "has parameters"),
        ('{"t": 0, "set": {"side_in": "left"}}', "not qualified"),
        ('{"t": 0, "set": {"side_in": "side.up"}}', "not an element"),
    ):
        (tmp_path / "in.jsonl").write_text(text + "\n")
        status, _, err = run(capsys, "trace", str(folder / "agents.xabsl"), "--inputs", str(tmp_path / "in.jsonl"))
        assert status == 2 and message in err and len(err.strip().splitlines()) == 1, err


def test_missing_files_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status, _, err = run(capsys, "trace", str(tmp_path / "none.ic"), "--inputs", str(KIT / "agents" / "in.jsonl"))
    assert status == 2 and "no such file" in err and len(err.strip().splitlines()) == 1
    status, _, err = run(capsys, "trace", str(KIT / "agents" / "expected.ic"), "--inputs", str(tmp_path / "in.jsonl"))
    assert status == 2 and "no such file" in err


def test_time_going_backwards_wraps_unsigned(agents_ic: Path, capsys: pytest.CaptureFixture[str]) -> None:
    inputs = agents_ic.parent / "in.jsonl"
    inputs.write_text('{"t": 100}\n{"t": 40}\n')
    status, out, _ = run(capsys, "trace", str(agents_ic), "--inputs", str(inputs))
    assert status == 0
    second = json.loads(out.splitlines()[1])
    assert second["tree"][0]["option_time"] == 2**32 - 60


def test_malformed_ic_exits_1(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "bad.ic").write_text("0\n0\n1\nopt 0\n1 s1 n s1 0 0 t nowhere\n0\n")
    (tmp_path / "in.jsonl").write_text('{"t": 0}\n')
    status, _, err = run(capsys, "trace", str(tmp_path / "bad.ic"), "--inputs", str(tmp_path / "in.jsonl"))
    print(err)
    assert status == 1 and "line 5" in err and "nowhere" in err


def test_behavior_with_errors_exits_1(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "agents.xabsl").write_text('agent a("A", missing_option);\n')
    (tmp_path / "in.jsonl").write_text('{"t": 0}\n')
    status, _, err = run(capsys, "trace", str(tmp_path / "agents.xabsl"), "--inputs", str(tmp_path / "in.jsonl"))
    print(err)
    assert status == 1 and "error" in err


def test_trace_writes_a_computed_infinity_as_the_kit_does(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The kit's arithmetic set computes -Infinity at tick 93 from finite inputs (issue 23).

    The original engine writes it as ``-Infinity``; a computed infinity is the behavior's
    arithmetic, not bad input, so the trace carries it rather than exiting 1.
    """
    folder = KIT / "arithmetic"
    out = tmp_path / "out.jsonl"
    status, _, err = run(
        capsys, "trace", str(folder / "agents.xabsl"), "--inputs", str(folder / "in.jsonl"), "--out", str(out)
    )
    assert status == 0, err
    assert lines(out) == lines(folder / "expected.out.jsonl")
    written = out.read_text().splitlines()
    assert '"r.paren":-Infinity' in written[92] and '"r.paren":-Infinity' not in written[91]
