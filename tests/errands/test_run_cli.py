"""``xabsl run examples/errands``: flags, the --json line, usage errors."""

from __future__ import annotations

import json

import pytest

from xabsl_studio.engine.cli import main


def test_json_prints_one_line_with_the_outcome(capsys):
    assert main(["run", "examples/errands", "--seed", "2", "--duration", "90", "--json"]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1
    data = json.loads(out[0])
    assert data["completed"] is True and 55.0 < data["time_s"] < 90.0
    assert 0.9 <= data["fact_agreement"] <= 1.0
    assert data["operators"][:2] == ["goto a c", "load mug c"]
    assert data["plan_status"] == "done"


def test_no_plan_runs_the_reactive_robot(capsys):
    assert main(["run", "errands", "--no-plan", "--duration", "20", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["operators"] == [] and data["completed"] is False and data["plan_status"] == "idle"
    assert data["sim_s"] == pytest.approx(20.0)


def test_text_report_names_plan_and_outcome(capsys):
    assert main(["run", "examples/errands", "--duration", "5"]) == 0
    out = capsys.readouterr().out
    assert "plan planned: (start) goto a c | load mug c" in out
    assert "derived facts = truth on" in out


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--dt", "0.05"], "unstable at dt=0.05"),
        (["--dt", "0.03"], "must divide one second"),
        (["--duration", "0"], "--duration must be positive"),
    ],
)
def test_usage_errors_exit_2_with_one_line(capsys, argv, message):
    assert main(["run", "examples/errands", *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]


def test_plan_and_no_plan_are_exclusive(capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["run", "examples/errands", "--plan", "--no-plan"])
    assert exit_info.value.code == 2
