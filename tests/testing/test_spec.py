"""The test file format: a bad file is a SpecError naming the file and the key."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.testing.conftest import HEAD
from xabsl_studio.engine.testing.spec import SpecError, load_suite, parse_suite

FILE = Path("/tmp/x.xabsl-test.toml")


def parse(body: str) -> object:
    return parse_suite(HEAD + body, FILE)


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ('[[test]]\nname = "a"\n', "test 'a': a test needs at least one [[test.expect]] table"),
        ("", "a suite needs at least one [[test]] table"),
        (
            '[[test]]\nname = "a"\nbogus = 1\n[[test.expect]]\nalways = true\noption = "top"',
            "test[1]: unknown key(s) bogus",
        ),
        ('[[test]]\n[[test.expect]]\noption = "top"', "give exactly one of always, never"),
        ('[[test]]\n[[test.expect]]\nalways = true\nnever = true\noption = "top"', "give exactly one of always"),
        ('[[test]]\n[[test.expect]]\nalways = false\noption = "top"', "expect[1].always: write it as `= true`"),
        ("[[test]]\n[[test.expect]]\nalways = true", "give exactly one of option, behavior, symbol"),
        ('[[test]]\n[[test.expect]]\nalways = true\nsymbol = "x"', "a symbol needs exactly one of equals"),
        ('[[test]]\n[[test.expect]]\nalways = true\nstate = "s"\nbehavior = "b"', "a state belongs to an option"),
        ('[[test]]\n[[test.expect]]\nwithin = -1\noption = "top"', "expect[1].within: expected seconds"),
        ('[[test]]\n[[test.expect]]\nwithin = nan\noption = "top"', "expected a finite number"),
        ('[[test]]\n[[test.expect]]\nat = 1\nfor = 1\noption = "top"', "`for` (hold so long) goes with eventually"),
        ('[[test]]\n[[test.expect]]\nalways = true\nfrom = 2\nuntil = 1\noption = "top"', "until is before from"),
        ('[[test]]\n[[test.expect]]\nalways = true\nbehavior = "b"\nparams = { p = [3, 1] }', "empty range"),
        ('[[test]]\n[[test.expect]]\nmax_changes = -1\nsymbol = "m"', "max_changes = N"),
        (
            '[[test]]\nforce = { option = "a", behavior = "b" }\n[[test.expect]]\nalways = true\noption = "a"',
            "exactly one of option, behavior",
        ),
        ('[[test]]\ninputs = [{ t = -5 }]\n[[test.expect]]\nalways = true\noption = "a"', "must be >= 0"),
        (
            '[[test]]\nname = "a"\n[[test.expect]]\nalways = true\noption = "a"\n' * 2,
            "two tests are named 'a'",
        ),
        ("[[test]\n", "not valid TOML"),
    ],
)
def test_bad_files(body: str, message: str) -> None:
    with pytest.raises(SpecError) as error:
        parse(body)
    assert str(error.value).startswith(f"{FILE}: ")
    assert message in str(error.value)


def test_within_is_eventually_with_until() -> None:
    suite = parse('[[test]]\n[[test.expect]]\nfrom = 1\nwithin = 2\noption = "top"\nstate = "busy"')
    [e] = suite.cases[0].expects  # type: ignore[attr-defined]
    assert (e.quantifier, e.start, e.stop) == ("eventually", 1.0, 3.0)
    assert e.text == "eventually in 1 s..3 s: option top in state busy active"


def test_suite_defaults_and_setup_merge(tmp_path: Path) -> None:
    file = tmp_path / "s.xabsl-test.toml"
    file.write_text(
        HEAD
        + '[setup]\nball = [1, 2]\ngame_state = "ready"\n'
        + '[[test]]\nname = "a"\nseed = 9\nsetup = { ball = [3, 4] }\n[[test.expect]]\nalways = true\noption = "top"\n'
    )
    [case] = load_suite(file).cases
    assert case.seed == 9 and case.duration == 2.0
    assert dict(case.setup) == {"ball": [3, 4], "game_state": "ready"}
    assert case.id == "fixture::a"


def test_unreadable_inputs_file(tmp_path: Path) -> None:
    (tmp_path / "in.jsonl").write_text('{"t": 0}\nnot json\n')
    file = tmp_path / "s.xabsl-test.toml"
    file.write_text(HEAD + '[[test]]\ninputs_file = "in.jsonl"\n[[test.expect]]\nalways = true\noption = "top"\n')
    with pytest.raises(SpecError, match=r"in.jsonl:2:1: not JSON"):
        load_suite(file)
