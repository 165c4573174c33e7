"""``xabsl test``: exit status, -k, --junit, --jobs, and the recording a failure leaves."""

from __future__ import annotations

import subprocess
import sys
import tomllib
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.testing.conftest import INPUTS
from xabsl_studio.engine.cli import ENGINE_COMMANDS
from xabsl_studio.engine.record import Recording
from xabsl_studio.engine.runtime.activation import OptionNode
from xabsl_studio.engine.testing.cli import collect, main, run_cases
from xabsl_studio.engine.testing.report import KeywordError, keyword_matcher

ROOT = Path(__file__).resolve().parents[2]

SUITE = f"""
[[test]]
name = "goes busy"
{INPUTS}
[[test.expect]]
within = 0.6
option = "top"
state = "busy"

[[test]]
name = "stays idle"
{INPUTS}
[[test.expect]]
never = true
option = "top"
state = "busy"

[[test]]
name = "kicks when high"
{INPUTS}
[[test.expect]]
within = 1.2
behavior = "kick"
"""


@pytest.fixture
def suite(write_suite: Callable[..., Path]) -> Path:
    return write_suite(SUITE)


def test_exit_status_and_output(suite: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([str(suite), "-k", "busy and not idle", "--no-recordings"]) == 0
    assert main([str(suite), "--no-recordings"]) == 1
    out = capsys.readouterr().out
    assert "fixture::stays idle: FAILED" in out
    assert "tick 20 (t = 0.5 s): never in 0 s..end: option top in state busy active failed: top in state busy" in out
    assert "2 passed, 1 failed, 0 errors" in out
    assert "coverage of behavior/behavior: options 2/2 (100%), states 4/4 (100%), transitions 2/3 (67%)" in out


def test_usage_errors(suite: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([str(tmp_path / "missing.xabsl-test.toml")]) == 2
    assert main([str(suite), "-k", "a and"]) == 2
    assert main([str(suite), "-k", "nothing-matches"]) == 1
    assert main([str(suite), "--jobs", "0"]) == 2
    err = capsys.readouterr().err
    assert "no such test file or folder" in err and "no tests selected" in err


def test_junit_is_valid(suite: Path, tmp_path: Path) -> None:
    out = tmp_path / "junit.xml"
    main([str(suite), "--junit", str(out), "--no-recordings", "-q"])
    root = ET.parse(out).getroot()
    assert root.tag == "testsuites"
    [testsuite] = list(root)
    assert (
        testsuite.attrib["tests"] == "3" and testsuite.attrib["failures"] == "1" and testsuite.attrib["errors"] == "0"
    )
    cases = {c.attrib["name"]: c for c in testsuite.iter("testcase")}
    assert set(cases) == {"goes busy", "stays idle", "kicks when high"}
    [failure] = cases["stays idle"].findall("failure")
    assert failure.attrib["message"].startswith("tick 20 (t = 0.5 s)")
    assert all(float(c.attrib["time"]) >= 0 for c in cases.values())
    assert not cases["goes busy"].findall("failure")


def test_jobs_give_the_same_results(suite: Path, write_suite: Callable[..., Path]) -> None:
    cases = collect([suite]) * 2
    one = run_cases(cases, jobs=1)
    two = run_cases(cases, jobs=2)
    assert [(r.id, r.status, [f.message() for f in r.failures], r.ticks) for r in one] == [
        (r.id, r.status, [f.message() for f in r.failures], r.ticks) for r in two
    ]


def test_failure_leaves_a_recording_at_the_failing_tick(suite: Path, tmp_path: Path) -> None:
    [result] = run_cases([c for c in collect([suite]) if c.name == "stays idle"], recordings=tmp_path / "rec")
    assert result.recording is not None and result.recording_tick == 20
    with Recording(result.recording) as recording:
        view = recording.tick(result.recording_tick)
        [root] = view.agents["robot1"].tree()
        assert isinstance(root, OptionNode) and (root.option, root.state) == ("top", "busy")
        before = recording.tick(result.recording_tick - 1).agents["robot1"].tree()[0]
        assert isinstance(before, OptionNode) and before.state == "idle"
        kinds = [e["kind"] for e in recording.events]
        assert "override" in kinds


def test_record_all_keeps_every_run_in_the_one_run_it_makes(
    suite: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = tmp_path / "rec"
    cases = collect([suite])
    results = run_cases(cases, recordings=folder, record_all=True)
    assert [r.status for r in results] == ["passed", "failed", "passed"]
    assert sorted(p.name for p in folder.iterdir()) == sorted(Path(r.recording or "").name for r in results)
    for result, case in zip(results, cases, strict=True):
        assert result.recording is not None
        with Recording(result.recording) as recording:
            # the whole test, not a second past a failure: every tick the test observed
            assert len(recording) == result.ticks
            assert any(case.id in e["data"].get("text", "") for e in recording.events)
    failed = results[1]
    assert failed.recording_tick == 20
    # the same verdicts as without recordings: recording changes nothing the test sees
    assert [r.status for r in run_cases(cases)] == ["passed", "failed", "passed"]
    assert main([str(suite), "--record-all", "--recordings", str(tmp_path / "cli")]) == 1
    out = capsys.readouterr().out
    assert out.count("; recording ") == 2  # the passed ones say where theirs is; the failure's report too
    assert main([str(suite), "--record-all", "--no-recordings"]) == 2


def test_keyword_expressions() -> None:
    match = keyword_matcher("(goalie or striker) and not kick")
    assert match("soccer::Goalie clears")  # type: ignore[operator]
    assert not match("soccer::striker kicks off")  # type: ignore[operator]
    with pytest.raises(KeywordError):
        keyword_matcher("goalie or")


def test_registered_as_xabsl_test_and_pytest_plugin() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert ENGINE_COMMANDS["test"][0] == "xabsl_studio.engine.testing.cli"
    assert "test" not in project["entry-points"]["xabsl.commands"]
    assert (
        project["entry-points"]["pytest11"]["xabsl_studio.engine.testing.plugin"]
        == "xabsl_studio.engine.testing.plugin"
    )


def test_module_entry_point_runs(suite: Path, tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.testing", str(suite), "-k", "kicks", "-q"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        check=False,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "1 passed, 0 failed" in done.stdout


def test_register_adds_the_subcommand(suite: Path) -> None:
    import argparse

    from xabsl_studio.engine.testing.cli import register

    parser = argparse.ArgumentParser(prog="xabsl")
    register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["test", str(suite), "-k", "busy", "--jobs", "2", "--no-recordings", "-q"])
    assert (args.keyword, args.jobs, args.no_recordings) == ("busy", 2, True)
    assert args.func(args) == 0


def test_the_command_line_names_test_files_as_the_format_does() -> None:
    # xabsl_studio.engine.testing.cli keeps its own copy so that registering `xabsl test` loads no TOML.
    from xabsl_studio.engine.testing import cli, spec

    assert cli.SUFFIX == spec.SUFFIX
