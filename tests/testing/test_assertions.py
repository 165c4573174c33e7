"""Each assertion kind passes and fails as it should, and a failure names the tick and the values."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from tests.testing.conftest import one_test
from xabsl_studio.engine.testing.runner import CaseResult, run_case
from xabsl_studio.engine.testing.spec import load_suite


def run(write_suite: Callable[..., Path], expect: str, extra: str = "") -> CaseResult:
    suite = load_suite(write_suite(one_test(expect, extra)))
    return run_case(suite.cases[0])


PASSING = [
    'always = true\noption = "top"',
    'never = true\noption = "helper"\nuntil = 0.45',
    'within = 0.6\noption = "top"\nstate = "busy"',
    'eventually = true\nfrom = 1.0\noption = "top"\nstate = "high"\nfor = 0.5',
    'at = 0.75\noption = "helper"\nparams = { rate = 30 }',
    'at = 0.75\nbehavior = "walk"\nparams = { speed = [9.5, 10.5], direction = 0 }',
    'within = 1.1\nbehavior = "kick"\nparams = { strength = 1 }',
    'at = 0.25\nsymbol = "mode"\nequals = "idle"',
    'at = 0.25\nsymbol = "mode"\nequals = "mode.idle"',
    'always = true\nsymbol = "mode"\nnot_equals = "busy"\nuntil = 0.45',
    'at = 1.5\nsymbol = "count"\nbetween = [19, 21]',
    'always = true\nsymbol = "level"\nbelow = 21',
    'eventually = true\nsymbol = "level"\nabove = 19',
    'always = true\nsymbol = "mode"\none_of = ["idle", "busy", "high"]',
    'max_changes = 2\nsymbol = "mode"',
    'at = 0.6\nsymbol = "go"\nequals = true',
]


@pytest.mark.parametrize("expect", PASSING)
def test_passes(write_suite: Callable[..., Path], expect: str) -> None:
    result = run(write_suite, f"[[test.expect]]\n{expect}")
    assert result.status == "passed", result.report()


# (expect, failing tick, text in the values): go comes at tick 20, the level at tick 40.
FAILING = [
    ('always = true\noption = "top"\nstate = "idle"', 20, "top in state busy"),
    ('never = true\noption = "helper"', 20, "helper in state turning (rate=30)"),
    ('within = 0.4\noption = "top"\nstate = "busy"', 16, "top in state idle"),
    ('eventually = true\noption = "top"\nstate = "busy"\nfor = 0.6', 79, "top in state high"),
    ('at = 0.25\noption = "top"\nstate = "busy"', 10, "top in state idle"),
    ('at = 0.75\nbehavior = "walk"\nparams = { speed = [11, 20] }', 30, "walk (speed=10, direction=0)"),
    ('never = true\nbehavior = "kick"', 40, "kick (strength=1)"),
    ('at = 1.25\nbehavior = "walk"', 50, "walk not called; active: top:high > kick(strength=1)"),
    ('at = 0.25\nsymbol = "mode"\nequals = "busy"', 10, "mode = mode.idle"),
    ('always = true\nsymbol = "mode"\nnot_equals = "high"', 40, "mode = mode.high"),
    ('at = 1.5\nsymbol = "count"\nbetween = [0, 10]', 60, "count = 20"),
    ('always = true\nsymbol = "level"\nbelow = 10', 40, "level = 20"),
    ('always = true\nsymbol = "level"\nabove = 10', 0, "level = 5"),
    ('always = true\nsymbol = "mode"\none_of = ["idle", "busy"]', 40, "mode = mode.high"),
    ('max_changes = 1\nsymbol = "mode"', 40, "mode changed mode.busy -> mode.high, change 2"),
    ('at = 5\nsymbol = "go"\nequals = true', 0, "the test ended before t = 5 s"),
]


@pytest.mark.parametrize(("expect", "tick", "values"), FAILING)
def test_fails_naming_tick_and_values(write_suite: Callable[..., Path], expect: str, tick: int, values: str) -> None:
    result = run(write_suite, f"[[test.expect]]\n{expect}")
    assert result.status == "failed", result.report()
    [failure] = result.failures
    assert failure.tick == tick, failure.message()
    assert values in failure.values, failure.message()
    message = failure.message()
    assert message.startswith(f"tick {tick} (t = {failure.t_ms / 1000:g} s): ")
    assert failure.expect.text in message


def test_window_eventually_must_start_in_window(write_suite: Callable[..., Path]) -> None:
    # high starts at 1.0 s: an eventually with until 0.9 fails at the window's end, not later.
    result = run(write_suite, '[[test.expect]]\neventually = true\nuntil = 0.9\noption = "top"\nstate = "high"')
    assert result.status == "failed"
    assert result.failures[0].tick == 36


def test_all_failures_are_reported(write_suite: Callable[..., Path]) -> None:
    body = (
        '[[test.expect]]\nnever = true\noption = "helper"\n[[test.expect]]\nalways = true\nsymbol = "level"\nbelow = 10'
    )
    result = run(write_suite, body)
    assert [f.tick for f in result.failures] == [20, 40]
    assert "tick 20" in result.report() and "tick 40" in result.report()


def test_forced_option_with_parameters(write_suite: Callable[..., Path]) -> None:
    body = """
[[test]]
name = "forced"
force = { option = "helper", params = { rate = -45 } }
[[test.expect]]
always = true
behavior = "turn"
params = { rate = -45 }
[[test.expect]]
never = true
option = "top"
"""
    result = run_case(load_suite(write_suite(body)).cases[0])
    assert result.status == "passed", result.report()


def test_forced_basic_behavior(write_suite: Callable[..., Path]) -> None:
    body = """
[[test]]
name = "forced"
force = { behavior = "walk", params = { speed = 100 } }
[[test.expect]]
always = true
behavior = "walk"
params = { speed = 100, direction = 0 }
"""
    result = run_case(load_suite(write_suite(body)).cases[0])
    assert result.status == "passed", result.report()


def test_selected_agent(write_suite: Callable[..., Path]) -> None:
    body = '[[test]]\nname = "a"\nagent = "helper_only"\n'
    body += '[[test.expect]]\nalways = true\noption = "helper"\nstate = "turning"'
    assert run_case(load_suite(write_suite(body)).cases[0]).ok


def test_other_robot(write_suite: Callable[..., Path]) -> None:
    # Only robot1 gets the inputs: robot2 stays idle.
    expect = '[[test.expect]]\nrobot = "robot2"\nalways = true\noption = "top"\nstate = "idle"'
    assert run(write_suite, expect).ok
    expect = '[[test.expect]]\nrobot = "robot2"\nwithin = 1\noption = "top"\nstate = "busy"'
    assert run(write_suite, expect).status == "failed"


def test_inputs_file_in_the_trace_format(write_suite: Callable[..., Path], tmp_path: Path) -> None:
    (tmp_path / "in.jsonl").write_text('{"t": 0, "set": {"go": false}}\n{"t": 250, "set": {"go": true}}\n')
    body = """
[[test]]
name = "file"
inputs_file = "in.jsonl"
[[test.expect]]
never = true
option = "top"
state = "busy"
"""
    result = run_case(load_suite(write_suite(body)).cases[0])
    assert result.status == "failed"
    assert result.failures[0].tick == 10


@pytest.mark.parametrize(
    ("body", "error"),
    [
        ('[[test.expect]]\nalways = true\noption = "nope"', "the behavior has no option nope"),
        ('[[test.expect]]\nalways = true\noption = "top"\nstate = "nope"', "option top has no state nope"),
        ('[[test.expect]]\nalways = true\nbehavior = "fly"', "no basic behavior fly"),
        ('[[test.expect]]\nalways = true\nsymbol = "nope"\nequals = 1', "the behavior has no symbol nope"),
        ('robot = "robot9"\n[[test.expect]]\nalways = true\noption = "top"', "no robot 'robot9'"),
        ('setup = { ball = [0, 0] }\n[[test.expect]]\nalways = true\noption = "top"', "offers no setup"),
        (
            'force = { option = "top", params = { x = 1 } }\n[[test.expect]]\nalways = true\noption = "top"',
            "no parameter x",
        ),
    ],
)
def test_errors_name_what_is_wrong(write_suite: Callable[..., Path], body: str, error: str) -> None:
    result = run_case(load_suite(write_suite(f'[[test]]\nname = "e"\n{body}')).cases[0])
    assert result.status == "error"
    assert error in (result.error or "")


def test_coverage_counts_what_ran(write_suite: Callable[..., Path]) -> None:
    result = run(write_suite, '[[test.expect]]\nalways = true\noption = "top"')
    assert result.coverage is not None
    figures = result.coverage.programs["behavior/behavior"].figures()
    assert figures["options"] == (2, 2)
    assert figures["states"] == (4, 4)
    # idle -> busy and busy -> high ran; high -> idle never did.
    assert figures["transitions"] == (2, 3)
    assert result.coverage.programs["behavior/behavior"].reached_transitions == {
        ("top", "idle", "busy"),
        ("top", "busy", "high"),
    }
