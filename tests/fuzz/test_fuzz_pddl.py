"""Fuzz the PDDL reader through ``xabsl plan``: a plan, "no plan" or one clear line, never a traceback."""

from __future__ import annotations

import io
import random
import tempfile
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

from hypothesis import given
from hypothesis import strategies as st

from tests.fuzz.probes import fuzz_settings, mutate_many, time_bound
from xabsl_studio.engine.cli import main

PDDL = Path(__file__).resolve().parents[2] / "examples" / "errands" / "pddl"
FILES = {"domain": (PDDL / "domain.pddl").read_bytes(), "problem": (PDDL / "problem.pddl").read_bytes()}


@fuzz_settings(60)
@given(st.sampled_from(sorted(FILES)), st.randoms(use_true_random=False))
def test_mutated_pddl_plans_or_exits_with_one_line(which: str, rnd: random.Random) -> None:
    files = dict(FILES)
    files[which] = mutate_many(files[which], rnd)
    with tempfile.TemporaryDirectory() as folder:
        for name, data in files.items():
            (Path(folder) / f"{name}.pddl").write_bytes(data)
        stdout, stderr = io.StringIO(), io.StringIO()
        argv = ["plan", str(Path(folder) / "domain.pddl"), str(Path(folder) / "problem.pddl"), "--json"]
        with time_bound(), redirect_stdout(stdout), redirect_stderr(stderr):
            status = main(argv)
        err = stderr.getvalue()
        assert status in (0, 1, 2) and "Traceback" not in err, err
        if status == 2:
            assert len(err.strip().splitlines()) == 1, err
