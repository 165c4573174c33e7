"""Hostile behavior test files through the real ``xabsl test`` (issue 25, item 8).

Each case runs the command line in its own process with a time bound: a device or a FIFO where a
file is expected, nesting that would exhaust Python's stack, integers beyond what a world takes,
names a file system or an XML reader cannot hold. Every one ends with a clear message and exit
status 2 (a bad file or ``-k``), or 1 (a test that could not run), within seconds and without a
traceback; nothing is read from ``/dev/zero`` beyond its first bytes.
"""

from __future__ import annotations

import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.testing.conftest import INPUTS

#: What a crash would print (each is a bug, never a message for the user).
CRASHES = ("MemoryError", "RecursionError", "OSError", "ValueError", "TypeError", "KeyError")
#: Seconds a hostile case may take (a hang or reading /dev/zero takes until killed).
BOUND = 60

PASSING = f"""
[[test]]
name = "goes busy"
{INPUTS}
[[test.expect]]
within = 0.6
option = "top"
state = "busy"
"""


def xabsl_test(*args: str | Path, cwd: Path) -> subprocess.CompletedProcess[str]:
    """``xabsl test ARGS`` in a fresh process; fails the test on a hang."""
    command = [sys.executable, "-m", "xabsl_studio.engine.cli", "test", *map(str, args)]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    return subprocess.run(command, capture_output=True, text=True, cwd=cwd, timeout=BOUND, env=env, check=False)


def refused(done: subprocess.CompletedProcess[str], status: int, *words: str) -> str:
    """The run's whole output after asserting a clean refusal with ``status``, naming ``words``."""
    output = done.stdout + done.stderr
    assert done.returncode == status, output
    assert "Traceback" not in output, output
    assert not [kind for kind in CRASHES if kind in output], output
    for word in words:
        assert word in output, output
    return output


def test_inputs_file_from_dev_zero_is_refused(write_suite: Callable[..., Path], tmp_path: Path) -> None:
    suite = write_suite(PASSING.replace("[[test.expect]]", 'inputs_file = "/dev/zero"\n[[test.expect]]'))
    refused(xabsl_test(suite, "--no-recordings", cwd=tmp_path), 2, "/dev/zero", "not a regular file")


def test_a_dev_zero_link_named_as_a_test_file_is_refused(tmp_path: Path) -> None:
    folder = tmp_path / "suites"
    folder.mkdir()
    (folder / "zero.xabsl-test.toml").symlink_to("/dev/zero")
    refused(xabsl_test(folder, "--no-recordings", cwd=tmp_path), 2, "zero.xabsl-test.toml", "not a regular file")
    refused(xabsl_test(folder / "zero.xabsl-test.toml", cwd=tmp_path), 2, "zero.xabsl-test.toml")


def test_a_fifo_as_inputs_file_or_test_file_does_not_hang(write_suite: Callable[..., Path], tmp_path: Path) -> None:
    os.mkfifo(tmp_path / "inputs.jsonl")
    suite = write_suite(PASSING.replace("[[test.expect]]", 'inputs_file = "inputs.jsonl"\n[[test.expect]]'))
    refused(xabsl_test(suite, "--no-recordings", cwd=tmp_path), 2, "inputs.jsonl", "not a regular file")
    folder = tmp_path / "suites"
    folder.mkdir()
    os.mkfifo(folder / "pipe.xabsl-test.toml")
    refused(xabsl_test(folder, cwd=tmp_path), 2, "pipe.xabsl-test.toml", "not a regular file")


def test_a_fifo_as_the_recording_to_start_from_does_not_hang(write_suite: Callable[..., Path], tmp_path: Path) -> None:
    os.mkfifo(tmp_path / "run.mcap")
    body = '[[test]]\nname = "from a pipe"\nfrom = { recording = "run.mcap", tick = 3 }\n'
    suite = write_suite(body + '[[test.expect]]\nalways = true\noption = "top"\n')
    refused(xabsl_test(suite, "--no-recordings", cwd=tmp_path), 1, "run.mcap", "not a regular file", "1 errors")


def test_deep_nesting_in_a_test_file_is_a_clear_error(write_suite: Callable[..., Path], tmp_path: Path) -> None:
    deep = "inputs = " + "[" * 5000 + "]" * 5000 + "\n"
    suite = write_suite(PASSING.replace(INPUTS, deep))
    refused(xabsl_test(suite, cwd=tmp_path), 2, "nested")
    inline = "setup = " + "{ a = " * 3000 + "1" + " }" * 3000 + "\n"
    suite = write_suite(PASSING.replace(INPUTS, inline), name="inline.xabsl-test.toml")
    refused(xabsl_test(suite, cwd=tmp_path), 2, "nested")


@pytest.mark.parametrize(
    "expression",
    ["(" * 5000 + "busy" + ")" * 5000, "(" * 5000, "busy and (" * 3000 + "busy" + ")" * 3000],
)
def test_a_deeply_nested_k_expression_is_a_usage_error(
    write_suite: Callable[..., Path], tmp_path: Path, expression: str
) -> None:
    suite = write_suite(PASSING)
    refused(xabsl_test(suite, "-k", expression, cwd=tmp_path), 2, "-k")


def test_a_long_flat_k_expression_still_selects(write_suite: Callable[..., Path], tmp_path: Path) -> None:
    suite = write_suite(PASSING)
    long_and = " and ".join(["busy"] * 5000)
    done = xabsl_test(suite, "-k", long_and, "--no-recordings", cwd=tmp_path)
    assert done.returncode == 0 and "1 passed" in done.stdout, done.stdout + done.stderr
    long_or = " or ".join(["nothing"] * 5000 + ["busy"])
    done = xabsl_test(suite, "-k", long_or, "--no-recordings", cwd=tmp_path)
    assert done.returncode == 0 and "1 passed" in done.stdout, done.stdout + done.stderr
    done = xabsl_test(suite, "-k", "not " * 5000 + "busy", "--no-recordings", cwd=tmp_path)
    assert done.returncode == 0 and "1 passed" in done.stdout, done.stdout + done.stderr
    refused(xabsl_test(suite, "-k", "not " * 5001 + "busy", cwd=tmp_path), 1, "no tests selected")


@pytest.mark.parametrize("seed", [-(2**63), -1, 2**32, 2**63 - 1])
def test_a_seed_no_world_takes_is_refused_in_the_file(
    write_suite: Callable[..., Path], tmp_path: Path, seed: int
) -> None:
    suite = write_suite(PASSING.replace("[[test.expect]]", f"seed = {seed}\n[[test.expect]]"))
    refused(xabsl_test(suite, cwd=tmp_path), 2, "seed", "0..4294967295")


def test_a_long_test_name_still_leaves_its_recording(write_suite: Callable[..., Path], tmp_path: Path) -> None:
    name = "n" * 300
    body = f'[[test]]\nname = "{name}"\n{INPUTS}\n[[test.expect]]\nnever = true\noption = "top"\nstate = "busy"\n'
    suite = write_suite(body)
    done = xabsl_test(suite, "--recordings", tmp_path / "rec", cwd=tmp_path)
    output = refused(done, 1, "FAILED", "recording:")
    [recording] = (tmp_path / "rec").iterdir()
    assert len(recording.name.encode()) <= 255 and recording.suffix == ".mcap"
    assert str(recording) in output


def test_control_characters_in_names_give_junit_xml_that_parses(
    write_suite: Callable[..., Path], tmp_path: Path
) -> None:
    odd = "\\u0001\\u0008\\u000b\\u001b[31m\\u007f\\ufffe"
    body = (
        f'[[test]]\nname = "busy {odd}"\n{INPUTS}\n[[test.expect]]\nwithin = 0.6\noption = "top"\nstate = "busy"\n'
        f'[[test]]\nname = "idle {odd}"\n{INPUTS}\n[[test.expect]]\nnever = true\noption = "top"\nstate = "busy"\n'
        f'name = "never busy {odd}"\n'
    )
    head = f'[suite]\nname = "suite {odd}"\npath = "{Path(__file__).parent / "behavior"}"\nduration = 2\n'
    suite = write_suite(body, head=head)
    junit = tmp_path / "junit.xml"
    done = xabsl_test(suite, "--junit", junit, "--no-recordings", cwd=tmp_path)
    output = refused(done, 1, "1 passed, 1 failed")
    assert "\x1b" not in output and "\x01" not in output  # nor into the terminal
    root = ET.parse(junit).getroot()
    names = [case.attrib["name"] for case in root.iter("testcase")]
    assert names == ["busy \\x01\\x08\\x0b\\x1b[31m\\x7f\\ufffe", "idle \\x01\\x08\\x0b\\x1b[31m\\x7f\\ufffe"]
    [failure] = root.iter("failure")
    assert "never busy \\x01" in failure.attrib["message"]
