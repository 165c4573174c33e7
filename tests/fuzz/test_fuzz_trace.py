"""Fuzz ``xabsl trace`` input: odd values and broken lines exit 2 naming the line, never a traceback;
whatever is written is JSON as the original engine's traces are (a value the behavior computed
as an infinity or NaN is written as ``Infinity``/``-Infinity``/``NaN``, nothing else)."""

from __future__ import annotations

import io
import json
import random
import tempfile
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path
from typing import Any

from hypothesis import given
from hypothesis import strategies as st

from tests.fuzz.probes import fuzz_settings, mutate_many, splice_odd_value, time_bound
from tests.kit import KIT, SETS
from xabsl_studio.engine.cli import main

TRACED = [name for name in SETS if (KIT / name / "in.jsonl").is_file() and (KIT / name / "expected.ic").is_file()]
#: Sets whose IC needs the declarations from the sources (enum order, input parameter order).
NEEDS_DECLARATIONS = {"declarations", "dotted-names", "input-functions"}


def _strict(text: str) -> Any:
    def refuse(constant: str) -> Any:
        if constant in ("Infinity", "-Infinity", "NaN"):  # computed by the behavior (the kit's format)
            return float(constant)
        raise AssertionError(f"{constant} in the output")

    return json.loads(text, parse_constant=refuse)


@fuzz_settings(80)
@given(st.sampled_from(TRACED), st.randoms(use_true_random=False))
def test_mutated_input_traces_give_a_trace_or_one_clear_line(name: str, rnd: random.Random) -> None:
    lines = (KIT / name / "in.jsonl").read_text().splitlines()
    i = rnd.randrange(len(lines))
    if rnd.random() < 0.7:
        lines[i] = splice_odd_value(json.loads(lines[i]), rnd)
        data = "\n".join(lines).encode()
    else:
        data = mutate_many("\n".join(lines).encode(), rnd)
    with tempfile.TemporaryDirectory() as folder:
        inputs, out = Path(folder) / "in.jsonl", Path(folder) / "out.jsonl"
        inputs.write_bytes(data)
        stdout, stderr = io.StringIO(), io.StringIO()
        argv = ["trace", str(KIT / name / "expected.ic"), "--inputs", str(inputs), "--out", str(out)]
        if name in NEEDS_DECLARATIONS:
            argv += ["--declarations", str(KIT / name / "agents.xabsl")]
        with time_bound(), redirect_stdout(stdout), redirect_stderr(stderr):
            status = main(argv)
        err = stderr.getvalue()
        assert status in (0, 1, 2) and "Traceback" not in err, err
        if status == 0:
            for line in out.read_text().splitlines():
                _strict(line)
        else:
            assert not out.exists(), "a failed trace writes nothing"
        if status == 2:
            assert len(err.strip().splitlines()) == 1, err
