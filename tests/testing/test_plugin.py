"""The pytest plugin collects *.xabsl-test.toml files and reports failures with tick and values."""

from __future__ import annotations

import pytest

from tests.testing.conftest import HEAD, one_test

pytest_plugins = ["pytester"]


def test_collects_and_reports(pytester: pytest.Pytester) -> None:
    body = one_test('[[test.expect]]\nwithin = 0.6\noption = "top"\nstate = "busy"').replace(
        'name = "t"', 'name = "ok"'
    )
    body += one_test('[[test.expect]]\nnever = true\nbehavior = "kick"').replace('name = "t"', 'name = "no kick"')
    pytester.makefile(".xabsl-test.toml", team=HEAD + body)
    pytester.makefile(".toml", ignored=HEAD + body)  # not a behavior test file name
    result = pytester.runpytest(
        "-p", "xabsl_studio.engine.testing.plugin", "-v", "--xabsl-recordings", str(pytester.path / "rec")
    )
    result.assert_outcomes(passed=1, failed=1)
    result.stdout.fnmatch_lines(
        [
            "*team.xabsl-test.toml::ok PASSED*",
            "*team.xabsl-test.toml::no kick FAILED*",
            "*tick 40 (t = 1 s): never in 0 s..end: basic behavior kick called failed: kick (strength=1)*",
            "*recording: *rec/fixture--no_kick.mcap (tick 40)*",
            "*xabsl behavior test coverage*",
            "coverage of behavior/behavior: options 2/2*",
        ]
    )
    assert (pytester.path / "rec" / "fixture--no_kick.mcap").is_file()


def test_bad_file_is_a_collection_error(pytester: pytest.Pytester) -> None:
    pytester.makefile(".xabsl-test.toml", bad=HEAD + "[[test]]\nname = 'x'\n")
    result = pytester.runpytest("-p", "xabsl_studio.engine.testing.plugin")
    result.assert_outcomes(errors=1)
    assert "bad.xabsl-test.toml: test 'x': a test needs at least one [[test.expect]] table" in result.stdout.str()
