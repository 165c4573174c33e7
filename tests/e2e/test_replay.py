"""The studio on a recording (``xabsl serve --replay``) in Chromium: the whole match in the
timeline, seeking by the timeline, "why" at a past tick with the operand values."""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.e2e.conftest import REPO, StudioServer, screenshot, serving, studio_tab
from xabsl_studio.engine.record import Recording

STUDIO = "window.xabslStudio"


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("replay-e2e") / "match.mcap"
    command = [
        sys.executable,
        "-m",
        "xabsl_studio.engine.cli",
        "run",
        "examples/soccer",
        "--duration",
        "20",
        "--players",
        "2",
    ]
    env = dict(os.environ, PYTHONPATH=str(REPO))
    subprocess.run([*command, "--record", str(path)], cwd=REPO, env=env, check=True, capture_output=True)
    return path


@pytest.fixture(scope="module")
def replay_server(recording: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[StudioServer]:
    with serving(recording, tmp_path_factory.mktemp("replay-log"), replay=True) as server:
        yield server


@pytest.fixture
def tab(browser: Any, replay_server: StudioServer) -> Iterator[Any]:
    with studio_tab(browser, replay_server, live=False) as page:
        yield page


def loaded(tab: Any, ticks: int) -> None:
    """Wait until the page holds every tick of the recording."""
    try:
        tab.wait_for_function(f"() => {STUDIO}.session.buffer.length === {ticks}", timeout=30000)
    except Exception:
        state = tab.evaluate(f"() => [{STUDIO}.session.buffer.length, JSON.stringify({STUDIO}.session.replay)]")
        raise AssertionError(f"the page holds {state[0]} of {ticks} ticks (replay: {state[1]})") from None


def test_the_timeline_covers_the_recording_and_seeks(tab: Any, recording: Path) -> None:
    with Recording(recording) as file:
        ticks = len(file)
        t_last = file.tick(ticks - 1).t
    # Every tick of the recording is loaded, far more than a live page's 60 s window.
    loaded(tab, ticks)
    assert tab.evaluate(f"{STUDIO}.session.buffer.newest.t") == t_last
    canvas = tab.locator(".timeline-canvas")
    box = canvas.bounding_box()
    assert box is not None
    tab.mouse.click(box["x"] + 150 + (box["width"] - 156) * 0.9, box["y"] + 30)
    tab.wait_for_function(f"() => {STUDIO}.session.cursor !== null")
    late = tab.evaluate(f"{STUDIO}.session.view.seq")
    assert late > ticks * 0.8
    canvas.focus()
    tab.keyboard.press("Home")
    tab.wait_for_function(f"() => {STUDIO}.session.view.seq === 0")
    # Dragging to the right end shows the recording's last tick (not "live": that is the
    # server's playback position, where End and L go back to).
    tab.mouse.click(box["x"] + box["width"] - 7, box["y"] + 30)
    tab.wait_for_function(f"() => {STUDIO}.session.view.seq >= {ticks - 3}")
    tab.keyboard.press("End")
    tab.wait_for_function(f"() => {STUDIO}.session.cursor === null && {STUDIO}.session.view.seq === 0")


def test_why_at_a_past_tick_shows_operand_values(tab: Any, recording: Path) -> None:
    with Recording(recording) as file:
        ticks = len(file)
        option = next(
            o["id"] for o in file.programs[("behavior", 0)].description["options"] if o["name"] == "approach_ball"
        )
        view = next(
            v
            for v in file.ticks(200, ticks)
            if any(n[0] == 0 and n[2] == option and n[7] >= 0 for n in v.agents["blue2"].path)
        )
        distance = view.agents["blue2"].inputs["ball.distance"]
    loaded(tab, ticks)
    tab.evaluate(f"() => {{ {STUDIO}.session.selectRobot(1); {STUDIO}.session.setCursor({view.t}); }}")
    tab.wait_for_function(f"() => {STUDIO}.session.view.seq === {view.seq}")
    tab.keyboard.press("o")
    tab.evaluate(f"() => {STUDIO}.session.openOptionById({option})")
    try:
        tab.wait_for_function(
            "() => document.querySelector('.option-title').textContent === 'approach_ball'"
            " && document.querySelector('.why').textContent.includes('Values recorded at')"
            " && document.querySelector('.why .comparisons li code') !== null",
            timeout=30000,
        )
    except Exception:
        # What the page showed instead: the option, the robot and the why pane's text.
        shown = tab.evaluate(
            f"() => [document.querySelector('.option-title').textContent, {STUDIO}.session.openOption,"
            f" {STUDIO}.session.selectedRobot, {STUDIO}.session.view.seq, document.querySelector('.why').textContent]"
        )
        raise AssertionError(f"the why pane of approach_ball at seq {view.seq} shows {shown}") from None
    comparison = tab.locator(".why .comparisons li code").first.inner_text()
    assert comparison.startswith("ball.distance (") and comparison.endswith(") < 900"), comparison
    shown = float(comparison.split("(")[1].split(")")[0])
    assert abs(shown - distance) < 0.01
    screenshot(tab, "replay-why")


def test_a_replay_does_not_contradict_itself(tab: Any, recording: Path) -> None:
    """The top bar said "0 : 0 · initial · 0.000 s · live · paused" while t = 14 s was shown, and
    the why said "No transition of this option in the buffered history" beside the info's
    "last transition ready → set" (issue 23)."""
    with Recording(recording) as file:
        ticks = len(file)
        seq = int(ticks * 0.7)
        view = file.tick(seq)
    loaded(tab, ticks)
    tab.evaluate(f"() => {STUDIO}.session.selectRobot(0)")
    tab.evaluate(
        f"""() => {{
        const s = {STUDIO}.session;
        s.setCursor(s.buffer.bySeq({seq}).x);
        s.openOptionById(s.indexOf(s.selectedRobot).optionByName.get("play_soccer").id);
    }}"""
    )
    tab.keyboard.press("o")
    tab.wait_for_selector(".option-panel svg g[id^='state_']", timeout=20000)
    tab.wait_for_function(f"() => {STUDIO}.session.view.seq === {seq}")
    clock = tab.locator(".clock").inner_text()
    assert f"{view.t / 1000:.3f} s" in clock, clock  # the tick in view, not the server's position
    assert str(view.status["game_state"]) in clock, (clock, view.status)
    assert "live" not in tab.locator(".link-text").inner_text()
    tab.wait_for_selector(".why .muted:has-text('Values recorded at')", timeout=20000)
    info = tab.locator(".option-info").inner_text()
    why = tab.locator(".why").inner_text()
    assert "last transition" in info  # init → ready → set → playing happened before 14 s
    assert "No transition of this option" not in why, (info, why)
    assert "Last transition:" in why, why
