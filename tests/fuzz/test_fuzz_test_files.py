"""Fuzz behavior test files through ``xabsl test``: results or one clear error, never a traceback or a hang.

A real suite (the tests/testing fixture behavior, an ``inputs_file`` beside it) is mutated as bytes
(deep nesting, odd numbers, NUL, truncation...) or gets an odd TOML value spliced in; the command
runs it in-process under the time bound. Exit 0 or 1 (tests ran), or 2 with one message naming
the file; whatever ran leaves a JUnit XML that parses. ``-k`` expressions get the same treatment.
"""

from __future__ import annotations

import io
import random
import re
import tempfile
import xml.etree.ElementTree as ET
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

from hypothesis import given
from hypothesis import strategies as st

from tests.fuzz.probes import fuzz_settings, mutate_many, time_bound
from tests.testing.conftest import HEAD, INPUTS
from xabsl_studio.engine.testing.cli import main
from xabsl_studio.engine.testing.report import KeywordError, keyword_matcher

SUITE = (
    HEAD
    + f"""
[[test]]
name = "goes busy"
{INPUTS}
[[test.expect]]
within = 0.6
option = "top"
state = "busy"

[[test]]
name = "from the file"
inputs_file = "inputs.jsonl"
[[test.expect]]
always = true
symbol = "level"
between = [0, 100]
[[test.expect]]
name = "kicks"
within = 1.2
behavior = "kick"
params = {{ strength = [0, 10] }}
"""
)
INPUTS_FILE = '{"t": 0, "set": {"go": true, "level": 5}}\n{"t": 500, "set": {"level": 20}}\n'
#: TOML values that broke readers before, spliced in where a number was.
ODD_TOML = [
    "nan", "inf", "-inf", "1e999", "9" * 400, "-9223372036854775808", "9223372036854775807", '"\\u0000"',
    '""', "[]", "{}", "[" * 3000 + "]" * 3000, "{ a = " * 400 + "1" + " }" * 400, '"' + "x" * 5000 + '"',
    "-0.0", "0x7fffffffffffffff", "1979-05-27T07:32:00Z", "true",
]  # fmt: skip
_NUMBER = re.compile(rb"(?<![\w.])\d+(?:\.\d+)?(?![\w.])")


def _run(folder: Path, *argv: str) -> tuple[int, str]:
    stdout, stderr = io.StringIO(), io.StringIO()
    with time_bound(), redirect_stdout(stdout), redirect_stderr(stderr):
        status = main([*argv])
    return status, stdout.getvalue() + stderr.getvalue()


@fuzz_settings(80)
@given(st.randoms(use_true_random=False), st.booleans())
def test_mutated_test_files_run_or_give_one_clear_error(rnd: random.Random, in_inputs: bool) -> None:
    suite, inputs = SUITE.encode(), INPUTS_FILE.encode()
    if in_inputs:
        inputs = mutate_many(inputs, rnd)
    elif rnd.random() < 0.5:
        spots = list(_NUMBER.finditer(suite))
        spot = rnd.choice(spots)
        suite = suite[: spot.start()] + rnd.choice(ODD_TOML).encode() + suite[spot.end() :]
    else:
        suite = mutate_many(suite, rnd)
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        (folder / "s.xabsl-test.toml").write_bytes(suite)
        (folder / "inputs.jsonl").write_bytes(inputs)
        junit = folder / "junit.xml"
        status, output = _run(folder, str(folder), "--junit", str(junit), "--recordings", str(folder / "rec"), "-q")
        assert status in (0, 1, 2) and "Traceback" not in output, output
        if status == 2:
            [line] = output.strip().splitlines()
            assert line.startswith("xabsl test: "), line
            assert "s.xabsl-test.toml" in line or "inputs.jsonl" in line, line
        elif junit.exists():
            ET.parse(junit)
        for recording in (folder / "rec").glob("*") if (folder / "rec").is_dir() else ():
            assert len(recording.name.encode()) <= 255


_WORDS = st.sampled_from(["and", "or", "not", "(", ")", "busy", "goes", "::", "fixture", "((((", "))))", ""])


@fuzz_settings(200)
@given(st.lists(st.one_of(_WORDS, st.text(max_size=8)), max_size=60), st.integers(0, 3000))
def test_k_expressions_select_or_are_refused(words: list[str], nesting: int) -> None:
    expression = "(" * nesting + " ".join(words) + ")" * nesting
    with time_bound():
        try:
            matcher = keyword_matcher(expression)
        except KeywordError as error:
            assert str(error).startswith("-k")
            return
        assert isinstance(matcher("fixture::goes busy"), bool)  # type: ignore[operator]
