"""``xabsl plan DOMAIN PROBLEM``: the layered plan as text and JSON, no plan, bad PDDL."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from xabsl_studio.engine.cli import main

ERRANDS = Path(__file__).resolve().parents[2] / "examples" / "errands" / "pddl"
DOMAIN, PROBLEM = str(ERRANDS / "domain.pddl"), str(ERRANDS / "problem.pddl")
PAPER_LAYERS = [["goto a c"], ["load mug c"], ["goto c b"], ["load book b"], ["goto b a"],
                ["unload book a", "unload mug a"]]  # fmt: skip


def test_json_layers_are_the_papers_plan(capsys):
    assert main(["plan", DOMAIN, PROBLEM, "--json"]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1
    assert json.loads(out[0]) == {"layers": PAPER_LAYERS}


def test_text_lists_one_step_per_line(capsys):
    assert main(["plan", DOMAIN, PROBLEM, "--stats"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].split() == ["1", "goto", "a", "c"]
    assert out[5] == " 6  unload book a ∥ unload mug a"
    assert out[6].startswith("7 actions in 6 steps")
    assert out[7].startswith("level")


def test_unsolvable_problem_exits_1_with_the_reason(tmp_path, capsys):
    text = Path(PROBLEM).read_text().replace("(connected c b)", "").replace("(connected c a)", "")
    problem = tmp_path / "p.pddl"
    problem.write_text(text)
    assert main(["plan", DOMAIN, str(problem), "--json"]) == 1
    data = json.loads(capsys.readouterr().out)
    assert data["layers"] is None and data["reason"].startswith("no plan")


@pytest.mark.parametrize(
    "domain_text, message",
    [
        ("(define (domain x", r"d.pddl:1:17: syntax error: unexpected end of file; expected RPAR"),
        (
            "(define (domain x) (:requirements :strips) (:predicates (p)) (:action a :parameters () "
            ":precondition (or (p) (p)) :effect (p)))",
            "d.pddl: ",
        ),
        ("(define (domain x) ;; \x00", "d.pddl:1:"),
    ],
)
def test_bad_pddl_exits_2_with_one_clear_line(tmp_path, capsys, domain_text, message):
    domain = tmp_path / "d.pddl"
    domain.write_text(domain_text)
    assert main(["plan", str(domain), PROBLEM]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("xabsl plan: ") and message in err[0]


def test_missing_file_exits_2(capsys):
    assert main(["plan", "no/such/domain.pddl", PROBLEM]) == 2
    assert capsys.readouterr().err.strip() == "xabsl plan: no such file: no/such/domain.pddl"


@pytest.mark.parametrize("kind", ["/dev/zero", "fifo", "folder", "too large", "latin-1"])
def test_unreadable_inputs_exit_2_with_one_line(tmp_path, capsys, kind):
    import os

    from xabsl_studio.engine.planning.strips import MAX_PDDL_BYTES

    path = tmp_path / "p.pddl"
    if kind == "/dev/zero":
        path = Path("/dev/zero")  # read without bound before: a MemoryError
    elif kind == "fifo":
        os.mkfifo(path)  # blocked forever before
    elif kind == "folder":
        path.mkdir()
    elif kind == "too large":
        with open(path, "wb") as handle:
            handle.truncate(MAX_PDDL_BYTES + 1)
    else:
        path.write_bytes(b"(define (problem caf\xe9))")
    assert main(["plan", DOMAIN, str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(path) in err, err
