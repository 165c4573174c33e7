"""The behavioral diff: its statistics, and two soccer recordings with a known edit.

The edit: a copy of the example team whose role selection never picks the goalie (player 1 is
a field player like the others). Played on the same seed as the original, its goalie options
never run: they must come first, 0 % against the original's share, and significant.
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import orjson
import pytest

from xabsl_studio.engine.cli import main
from xabsl_studio.engine.host import BehaviorLoop
from xabsl_studio.engine.profile import ProfileError, profile
from xabsl_studio.engine.profile.against import compare_reports, pair_teams
from xabsl_studio.engine.profile.stats import change_key, difference_interval, rate_test, sort_by_change, wilson
from xabsl_studio.engine.record import Recorder, Recording
from xabsl_studio.examples.soccer.run import DEFAULT_AWAY, DEFAULT_HOME, build_world, load_team

TICKS = 2000  # 16 s before kick-off, then about 34 s of play at 40 Hz
GOALIE_OPTIONS = {"goalie", "goalie_position", "goalie_clear"}


def test_wilson_and_newcombe_match_the_published_values() -> None:
    low, high = wilson(0, 10)
    assert (round(low, 4), round(high, 4)) == (0.0, 0.2775)  # Newcombe 1998, table I
    # Newcombe 1998 (Stat. Med. 17:873), example (a): 56/70 - 48/80, method 10
    low, high = difference_interval(56, 70, 48, 80)
    assert (round(low, 4), round(high, 4)) == (0.0524, 0.3339)
    assert difference_interval(0, 0, 0, 0) == (-1.0, 1.0)


def test_rates() -> None:
    assert not rate_test(10, 60_000, 10, 60_000)
    assert rate_test(30, 60_000, 5, 60_000)
    assert not rate_test(0, 60_000, 0, 60_000)


def test_the_order_puts_one_sided_rows_first_then_the_largest_change() -> None:
    rows = [("a", False, 0.3), ("b", True, 0.01), ("c", False, -0.5), ("d", True, -0.2), ("e", False, 0.3)]
    ordered = sort_by_change(rows, lambda r: r[1], lambda r: r[2], lambda r: r[0])
    assert [r[0] for r in ordered] == ["d", "b", "c", "a", "e"]
    assert change_key(True, 0.0, "x") < change_key(False, 1.0, "a")


def _record(path: Path, home_folder: Path, seed: int = 3) -> Path:
    home, away = load_team(home_folder), load_team(DEFAULT_AWAY)
    world = build_world(seed, home, away, players=5)
    loop = BehaviorLoop(world)
    recorder = Recorder(
        path, world, {"behavior": home, "chase": away}, example="soccer", behavior_hz=40, physics_hz=120
    )
    for _ in range(TICKS):
        now = loop.now_ms
        loop.tick()
        recorder.tick(now)
    recorder.close()
    return path


@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """(the edited team's recording, the original's), same seed."""
    folder = tmp_path_factory.mktemp("versions")
    edited = folder / "no_goalie"
    shutil.copytree(DEFAULT_HOME, edited)
    roles = edited / "options" / "role_selection.xabsl"
    text = roles.read_text()
    assert text.count("if (robot.number == 1)") == 1
    roles.write_text(text.replace("if (robot.number == 1)", "if (robot.number == 0)"))  # numbers start at 1
    return _record(folder / "edited.mcap", edited), _record(folder / "original.mcap", DEFAULT_HOME)


@pytest.fixture(scope="module")
def reports(recordings: tuple[Path, Path]) -> tuple[dict[str, Any], dict[str, Any]]:
    with Recording(recordings[0]) as a, Recording(recordings[1]) as b:
        return profile(a), profile(b)


def test_the_goalie_that_never_plays_comes_first(reports: tuple[dict[str, Any], dict[str, Any]]) -> None:
    a, b = reports
    document = compare_reports(a, b)
    assert [(c["a"]["team"], c["b"]["team"]) for c in document["comparisons"]] == [
        ("behavior", "behavior"),
        ("chase", "chase"),
    ]
    rows = document["comparisons"][0]["options"]
    original = b["teams"]["behavior"]["options"]
    first = rows[0]
    assert first["option"] == "goalie" and first["only_in"] == "b"
    assert first["a"]["share"] == 0.0 and first["a"]["activations"] == 0
    # the original's goalie: one robot of five for the time of play
    assert first["b"]["share"] == original["goalie"]["share"] > 0.1
    assert first["change"]["share"] == -first["b"]["share"]
    assert first["change"]["significant"] and first["change"]["share_ci95"][1] < 0
    # every option only one side ran comes before every option both ran
    one_sided = [r["only_in"] is not None for r in rows]
    assert one_sided == sorted(one_sided, reverse=True)
    assert {r["option"] for r in rows if r["only_in"] == "b"} >= GOALIE_OPTIONS
    # then by the size of the change
    changes = [abs(r["change"]["share"]) for r in rows if r["only_in"] is None]
    assert changes == sorted(changes, reverse=True)
    # the role selection's goalie state: 0 % of the option's time against its share in the original
    roles = next(r for r in rows if r["option"] == "role_selection")
    goalie_state = next(s for s in roles["states"] if s["state"] == "goalie")
    role_states = original["role_selection"]["states"]
    assert goalie_state["only_in"] == "b" and goalie_state["a"]["share"] == 0.0
    assert goalie_state["b"]["share"] == round(
        role_states["goalie"]["active_ms"] / original["role_selection"]["active_ms"], 6
    )
    # the transition into it was taken by the original only
    into = [t for t in roles["transitions"] if t["to"] == "goalie"]
    assert into and all(t["only_in"] == "b" and t["a"]["count"] == 0 for t in into)


def test_the_same_recording_has_no_significant_change(reports: tuple[dict[str, Any], dict[str, Any]]) -> None:
    document = compare_reports(reports[1], reports[1])
    for comparison in document["comparisons"]:
        for row in comparison["options"]:
            assert row["only_in"] is None and row["change"]["share"] == 0.0 and not row["change"]["significant"]


def test_two_sides_of_one_match(reports: tuple[dict[str, Any], dict[str, Any]]) -> None:
    document = compare_reports(reports[1], reports[1], "behavior", "chase")
    (comparison,) = document["comparisons"]
    assert (comparison["a"]["team"], comparison["b"]["team"]) == ("behavior", "chase")
    names = {r["option"] for r in comparison["options"] if r["only_in"] == "b"}
    assert names == set(reports[1]["teams"]["chase"]["options"]) - set(reports[1]["teams"]["behavior"]["options"])
    with pytest.raises(ProfileError, match="--against-team: no team 'nobody'"):
        pair_teams(reports[0], reports[1], "behavior", "nobody")


def test_command_line(recordings: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    edited, original = (str(p) for p in recordings)
    page = tmp_path / "diff.html"
    assert main(["profile", edited, "--against", original, "--json", "--html", str(page)]) == 0
    document = orjson.loads(capsys.readouterr().out)
    assert document["format"] == "xabsl-profile-diff/1"
    assert document["comparisons"][0]["options"][0]["option"] == "goalie"
    html = page.read_text()
    assert html.index("goalie (only B)") < html.index("role_selection") and "<script" not in html
    assert main(["profile", edited, "--against", original]) == 0
    out = capsys.readouterr().out
    table = out[out.index("options: share of robot time") :]
    assert table.index("goalie (only B)") < table.index("role_selection")
    assert main(["profile", edited, "--against", original, "--team", "nobody"]) == 2
    assert "--team: no team 'nobody'" in capsys.readouterr().err
    assert main(["profile", edited, "--team", "behavior"]) == 2
    assert "--team needs --against" in capsys.readouterr().err
    assert main(["profile", edited, "--against", str(tmp_path / "none.mcap")]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["profile", edited, "--against", original, "--window-ms", "0"]) == 2
