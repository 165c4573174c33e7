"""Searching a replay in Chromium: the timeline's query box marks the matches, ◀ / ▶ go to them,
and the option view finds every tick of a state in one click (docs/queries.md)."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.e2e.conftest import REPO, StudioServer, screenshot, serving, studio_tab
from xabsl_studio.engine.query import query_recording
from xabsl_studio.engine.record import Recording

STUDIO = "window.xabslStudio"


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("query-e2e") / "match.mcap"
    command = [sys.executable, "-m", "xabsl_studio.engine.cli", "run", "examples/soccer", "--duration", "20"]
    command += ["--players", "2", "--record", str(path)]
    env = dict(os.environ, PYTHONPATH=str(REPO))
    subprocess.run(command, cwd=REPO, env=env, check=True, capture_output=True)
    return path


@pytest.fixture(scope="module")
def replay_server(recording: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[StudioServer]:
    with serving(recording, tmp_path_factory.mktemp("query-log"), replay=True) as server:
        yield server


@pytest.fixture
def tab(browser: Any, replay_server: StudioServer, recording: Path) -> Iterator[Any]:
    with studio_tab(browser, replay_server, live=False) as page:
        with Recording(recording) as file:
            ticks = len(file)
        page.wait_for_function(f"() => {STUDIO}.session.buffer.length === {ticks}", timeout=30000)
        yield page


def robot_ids(tab: Any) -> dict[str, int]:
    return dict(tab.evaluate(f"() => {STUDIO}.session.robots.map((r) => [r.name, r.id])"))


def test_the_box_marks_every_match_and_goes_to_them(tab: Any, recording: Path) -> None:
    condition = "kick.active || dribble.active"
    expected = query_recording(recording, condition)
    assert len(expected.intervals) >= 2
    ids = robot_ids(tab)
    tab.fill(".query-input", condition)
    tab.press(".query-input", "Enter")
    n = len(expected.intervals)
    tab.wait_for_function(f"() => document.querySelector('.timeline-canvas').dataset.matches === '{n}'")
    # Enter goes to the first match: its robot selected, its first tick in view
    first = expected.intervals[0]
    tab.wait_for_function(f"() => {STUDIO}.session.view.seq === {first.first_seq}")
    assert tab.evaluate(f"{STUDIO}.session.selectedRobot") == ids[first.robot]
    assert tab.locator(".query-status").inner_text().startswith(f"1 of {n}: {first.robot} ")
    second = expected.intervals[1]
    tab.click(".query-next")
    tab.wait_for_function(f"() => {STUDIO}.session.view.seq === {second.first_seq}")
    assert tab.evaluate(f"{STUDIO}.session.selectedRobot") == ids[second.robot]
    tab.click(".query-previous")
    tab.wait_for_function(f"() => {STUDIO}.session.view.seq === {first.first_seq}")
    tab.click(".query-previous")  # from the first, back round to the last
    last = expected.intervals[-1]
    tab.wait_for_function(f"() => {STUDIO}.session.view.seq === {last.first_seq}")
    screenshot(tab, "query-matches")


def test_a_bad_condition_says_where(tab: Any) -> None:
    tab.fill(".query-input", "striker.state == kik")
    tab.press(".query-input", "Enter")
    tab.wait_for_selector(".query-status.error")
    text = tab.locator(".query-status").inner_text()
    assert "1:18: option striker has no state 'kik'" in text, text
    assert tab.evaluate("document.querySelector('.timeline-canvas').dataset.matches") == "0"


def test_every_tick_in_a_state_from_the_option_view(tab: Any, recording: Path) -> None:
    expected = query_recording(recording, "play_soccer.state == ready")
    assert expected.intervals
    tab.keyboard.press("o")  # the option view's tab
    tab.evaluate(
        f"""() => {{
        const s = {STUDIO}.session;
        s.selectRobot(0);
        s.openOptionById(s.indexOf(0).optionByName.get("play_soccer").id);
    }}"""
    )
    tab.wait_for_function("() => document.querySelector('.option-title').textContent === 'play_soccer'")
    tab.wait_for_selector(".option-panel svg g#state_1")
    tab.click(".option-panel svg g#state_1", button="right")  # state 1 of play_soccer: ready
    tab.click(".context-menu button:has-text('Every tick in ready')")
    n = len(expected.intervals)
    tab.wait_for_function(f"() => document.querySelector('.timeline-canvas').dataset.matches === '{n}'")
    assert tab.input_value(".query-input") == "play_soccer.state == ready"
    tab.wait_for_function(f"() => {STUDIO}.session.view.seq === {expected.intervals[0].first_seq}")
