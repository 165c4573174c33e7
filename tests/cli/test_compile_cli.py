"""``xabsl compile``: exit statuses, output files, text and JSON diagnostics."""

from __future__ import annotations

import io
import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.kit import KIT
from xabsl_studio.engine.cli import main

DEMO = Path(__file__).resolve().parents[2] / "examples" / "demo" / "agents.xabsl"


def test_clean_compile_writes_ic_and_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    ic, doc = tmp_path / "out.ic", tmp_path / "out.json"
    assert main(["compile", str(KIT / "demo-approach" / "agents.xabsl"), "--ic", str(ic), "--json", str(doc)]) == 0
    assert ic.read_bytes() == (KIT / "demo-approach" / "expected.ic").read_bytes()
    data = json.loads(doc.read_text())
    approach = data["options"][0]
    assert approach["name"] == "approach" and approach["params"][0]["name"] == "approach.stop_at"
    transition = next(t for t in approach["transitions"] if t["from"] == "go" and t["to"] == "arrived")
    # The conditions leading to the leaf are its path in the state's decision tree.
    decision = next(s for s in approach["states"] if s["name"] == "go")["decision"]
    assert (decision["if"], decision["else"]["if"]) == ("robot.fallen", "ball.distance < @stop_at")
    assert decision["else"]["then"] == {**decision["else"]["then"], "to": "arrived", "leaf": transition["leaf"]}
    summary = capsys.readouterr().out.strip().splitlines()[-1]
    assert summary.startswith("ok: 4 files, 1 option, 0 errors, 0 warnings in ")


def test_errors_exit_1_and_write_nothing(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    ic = tmp_path / "out.ic"
    case = KIT / "compile-errors" / "10-unknown-symbol" / "main.xabsl"
    assert main(["compile", str(case), "--ic", str(ic)]) == 1
    assert not ic.exists()
    lines = capsys.readouterr().out.splitlines()
    error = next(line for line in lines if ": error: " in line)
    assert error.endswith("[no-matching-symbol]") and ":6:17: error: no matching symbol found for 'distance'" in error
    assert lines[-1].startswith("failed: ")


def test_werror_turns_warnings_into_failure(tmp_path: Path) -> None:
    source = tmp_path / "agents.xabsl"
    (tmp_path / "s.xabsl").write_text('namespace s("S") { float input unused_input; float output o; }\n')
    (tmp_path / "main.xabsl").write_text("option main { initial state s { action { o = 1; } } }\n")
    source.write_text('include "s.xabsl"; include "main.xabsl"; agent a("A", main);\n')
    assert main(["compile", str(source)]) == 0
    assert main(["compile", str(source), "--werror"]) == 1
    assert main(["compile", str(source), "--werror", "--no-lint"]) == 0


def test_json_format(capsys: pytest.CaptureFixture[str]) -> None:
    case = KIT / "compile-errors" / "13-two-initial-states" / "main.xabsl"
    assert main(["compile", str(case), "--format", "json"]) == 1
    report = json.loads(capsys.readouterr().out)
    assert report["ok"] is False and report["summary"]["errors"] == 1
    error = next(d for d in report["diagnostics"] if d["severity"] == "error")
    assert (error["code"], error["original_code"], error["span"]["line"]) == ("multiple-initial-states", "X5327", 8)


def test_missing_file_is_one_line_exit_2() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "compile", "no/such/agents.xabsl"],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 2
    assert result.stderr.strip() == "xabsl compile: no such file: no/such/agents.xabsl"


def test_usage_error_exit_2() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "compile"], capture_output=True, text=True
    )
    assert result.returncode == 2 and "AGENTS_FILE" in result.stderr


def test_unwritable_output_is_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["compile", str(DEMO), "--ic", str(tmp_path / "missing" / "out.ic")]) == 2
    assert "cannot write output" in capsys.readouterr().err


def test_demo_example_compiles_cleanly(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["compile", str(DEMO), "--werror"]) == 0


def test_a_deep_decision_tree_writes_its_json(tmp_path: Path) -> None:
    # orjson refuses documents nested deeper than 255 levels ("Recursion limit reached"): a
    # 400-level else-if chain, well within the language's limit, crashed --json with a traceback.
    levels = 400
    chain = "if (state_time > 1) stay; else " * levels + "stay;"
    (tmp_path / "o.xabsl").write_text(f"option o {{ initial state s {{ decision {{ {chain} }} action {{ }} }} }}\n")
    source = tmp_path / "agents.xabsl"
    source.write_text('include "o.xabsl";\nagent a("A", o);\n')
    doc = tmp_path / "out.json"
    assert main(["compile", str(source), "--json", str(doc)]) == 0
    tree = json.loads(doc.read_text())["options"][0]["states"][0]["decision"]
    depth = 0
    while "if" in tree:
        tree, depth = tree["else"], depth + 1
    assert depth == levels and tree["stay"] is True


def noisy_team(root: Path) -> Path:
    """A small behavior set with every kind of warning a team's set had in numbers (issue 23).

    The original compiler prints none of them: ``naming`` and ``parameter-missing`` it defines but
    never prints, the rest are lint of our own. File names with ``-`` are common in team sets.
    """
    (root / "Options").mkdir()
    (root / "basic-behaviors.xabsl").write_text(
        'namespace basic_behaviors("Skills") {\n  behavior walk {\n    float speed;\n    float turn;\n  }\n'
        "  behavior spare {\n  }\n}\n"
    )
    (root / "symbols.xabsl").write_text(
        'namespace symbols("S") {\n  float input x;\n  float input never_read;\n  float output o;\n}\n'
    )
    (root / "Options" / "go-to.xabsl").write_text(
        "option go_to {\n  initial state walking {\n    decision {\n      if (x > 1)\n        goto done;\n"
        "      else\n        stay;\n    }\n    action {\n      walk(speed = 1);\n    }\n  }\n"
        "  target state done {\n    decision {\n      stay;\n    }\n    action {\n      o = 1;\n    }\n  }\n"
        "  state never {\n    decision {\n      stay;\n    }\n    action {\n    }\n  }\n}\n"
    )
    (root / "Options" / "kick_ball.xabsl").write_text(
        "option kick {\n  initial state s {\n    decision {\n      stay;\n    }\n"
        "    action {\n      go_to();\n    }\n  }\n}\n"
    )
    agents = root / "agents.xabsl"
    agents.write_text(
        'include "basic-behaviors.xabsl";\ninclude "symbols.xabsl";\ninclude "Options/go-to.xabsl";\n'
        'include "Options/kick_ball.xabsl";\nagent team("Team", kick);\n'
    )
    return agents


def test_no_lint_leaves_what_the_original_compiler_prints(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    agents = noisy_team(tmp_path)
    assert main(["compile", str(agents), "--format", "json"]) == 0
    report = json.loads(capsys.readouterr().out)
    codes = sorted(d["code"] for d in report["diagnostics"])
    assert codes == ["naming", "parameter-missing", "unreachable-state", "unused-behavior", "unused-symbol"]
    assert all(d["lint"] for d in report["diagnostics"])  # none of them is the original compiler's
    assert main(["compile", str(agents), "--no-lint"]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert out == [out[-1]] and out[-1].startswith("ok: 5 files, 2 options, 0 errors, 0 warnings in ")


def test_no_warning_asks_for_a_name_the_language_cannot_express(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """`basic-behaviors.xabsl` asked for a namespace `basic-behaviors`: a syntax error."""
    agents = noisy_team(tmp_path)
    # from the team's folder, so that the file names printed do not depend on where the checkout lies
    monkeypatch.chdir(tmp_path)
    assert main(["compile", str(agents)]) == 0
    naming = [line for line in capsys.readouterr().out.splitlines() if "[naming]" in line]
    assert naming == [
        "Options/kick_ball.xabsl:1:8: warning: option 'kick' should be named like its file 'kick_ball' [naming]"
    ]


def test_the_summary_counts_in_the_singular_too(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    source = tmp_path / "agents.xabsl"
    (tmp_path / "s.xabsl").write_text('namespace s("S") { float input unused_input; float output o; }\n')
    (tmp_path / "main.xabsl").write_text("option main { initial state s { action { o = 1; } } }\n")
    source.write_text('include "s.xabsl"; include "main.xabsl"; agent a("A", main);\n')
    assert main(["compile", str(source)]) == 0
    summary = capsys.readouterr().out.strip().splitlines()[-1]
    assert summary.startswith("ok: 3 files, 1 option, 0 errors, 1 warning in "), summary


class _GoneReader(io.StringIO):
    """Standard output whose reader went away (``xabsl … | head`` after head exits)."""

    def write(self, text: str) -> int:
        raise BrokenPipeError(32, "Broken pipe")


def test_a_reader_that_goes_away_is_no_failure_and_no_traceback(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys, "stdout", _GoneReader())
    case = KIT / "logic"
    assert main(["trace", str(case / "agents.xabsl"), "--inputs", str(case / "in.jsonl")]) == 0


def test_an_output_named_dash_is_standard_output(tmp_path: Path) -> None:
    """``--ic -`` pipes the intermediate code (a file named ``-`` was written before)."""
    case = KIT / "demo-approach"
    done = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "compile", str(case / "agents.xabsl"), "--ic", "-"],
        capture_output=True,
        cwd=tmp_path,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout == (case / "expected.ic").read_bytes()
    assert done.stderr.decode().startswith("ok: 4 files, 1 option")
    assert list(tmp_path.iterdir()) == []


def test_only_one_output_can_be_standard_output(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["compile", str(DEMO), "--ic", "-", "--json", "-"]) == 2
    assert "only one of --ic and --json" in capsys.readouterr().err
