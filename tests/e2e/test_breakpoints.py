"""Breakpoints and the recorded "why" in headless chromium (issue 13, deliverables 1 and 2).

Each kind of breakpoint is set (from the UI where the UI offers it: the state's context menu,
the condition field), the match is reset and resumed, and it must stop at the tick the
breakpoint names: checked against the server's ring buffer (``/api/log``) at the hit's seq and
the tick before. The soccer match is deterministic after a reset: the game is in init for 1 s,
ready for 5 s, set for 2 s, then playing.
"""

from __future__ import annotations

import json
import os
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.e2e.conftest import StudioServer, screenshot

STUDIO = "window.xabslStudio"


@pytest.fixture(scope="module", autouse=True)
def state_dir(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """Breakpoints of this module's server go to a private state folder (set before it starts)."""
    folder = tmp_path_factory.mktemp("state")
    previous = os.environ.get("XABSL_STATE_DIR")
    os.environ["XABSL_STATE_DIR"] = str(folder)
    yield folder
    if previous is None:
        os.environ.pop("XABSL_STATE_DIR", None)
    else:
        os.environ["XABSL_STATE_DIR"] = previous


def get(studio: StudioServer, path: str) -> Any:
    with urllib.request.urlopen(studio.url + path, timeout=20) as response:
        return response.read()


def ticks(studio: StudioServer, t0: int, t1: int) -> dict[int, dict[str, Any]]:
    lines = get(studio, f"api/log?t0={t0}&t1={t1}").decode().splitlines()
    return {tick["seq"]: tick for tick in map(json.loads, lines)}


def node(tick: dict[str, Any], robot: int, option: str) -> dict[str, Any] | None:
    return next((n for n in tick["robots"][robot]["path"] if n.get("option") == option), None)


def clear(studio: StudioServer) -> None:
    for b in studio.command("list_breakpoints")["result"]["breakpoints"]:
        studio.command("remove_breakpoint", program=b["program"], breakpoint=b["breakpoint"])


def restart_paused(studio: StudioServer) -> None:
    studio.command("pause")
    clear(studio)
    assert studio.command("reset")["ok"]


def run_until_hit(studio: StudioServer, page: Any, hits_before: int) -> dict[str, Any]:
    """Resume at 4x and wait for the hit; the status (paused, seq and t of the hit tick)."""
    studio.command("speed", speed=4)
    studio.command("resume")
    page.wait_for_function(
        f"() => Number(document.querySelector('.timeline-canvas').dataset.hits || 0) > {hits_before}", timeout=40000
    )
    status = json.loads(get(studio, "api/status"))
    assert status["paused"] is True, "a hit pauses the match"
    studio.command("speed", speed=1)
    return status


def hits_shown(page: Any) -> int:
    return int(page.evaluate("() => Number(document.querySelector('.timeline-canvas').dataset.hits || 0)"))


def open_option(page: Any, name: str) -> None:
    page.evaluate(
        f"""() => {{
        const s = {STUDIO}.session;
        const index = s.indexOf(s.selectedRobot);
        s.openOptionById(index.optionByName.get({json.dumps(name)}).id);
    }}"""
    )
    page.keyboard.press("o")
    page.wait_for_selector(".option-panel svg g[id^='state_']", timeout=20000)


def hit_robot(page: Any) -> int:
    return int(page.evaluate(f"() => {STUDIO}.session.selectedRobot"))


def test_each_kind_stops_the_match_at_the_right_tick(page: Any, studio: StudioServer) -> None:
    page.evaluate(f"() => {STUDIO}.session.selectRobot(0)")
    open_option(page, "play_soccer")

    # enter state, from the state's context menu in the option view
    restart_paused(studio)
    before = hits_shown(page)
    page.click(".option-panel svg g#state_1", button="right")  # state 1 of play_soccer: ready
    page.click(".context-menu button:has-text('Break on enter ready')")
    page.wait_for_selector(".breakpoint-list li code:has-text('enter play_soccer.ready')")
    status = run_until_hit(studio, page, before)
    seq, t, robot = status["seq"], status["t"], hit_robot(page)
    log = ticks(studio, t - 500, t)
    assert node(log[seq], robot, "play_soccer")["state"] == "ready"  # type: ignore[index]
    assert node(log[seq - 1], robot, "play_soccer")["state"] == "init"  # type: ignore[index]
    assert 900 <= t <= 1200, t
    screenshot(page, "breakpoint-hit")

    # leave state, enter option, leave option, decision leaf: over the protocol
    cases = [
        (
            {"kind": "leave_state", "option": "play_soccer", "state": "ready"},
            lambda now, prev, r: (
                node(prev, r, "play_soccer")["state"] == "ready"  # type: ignore[index]
                and node(now, r, "play_soccer")["state"] == "set"
            ),  # type: ignore[index]
        ),
        (
            {"kind": "enter_option", "option": "game_playing"},
            lambda now, prev, r: node(now, r, "game_playing") is not None and node(prev, r, "game_playing") is None,
        ),
        (
            {"kind": "leave_option", "option": "game_ready"},
            lambda now, prev, r: node(prev, r, "game_ready") is not None and node(now, r, "game_ready") is None,
        ),
        (
            {"kind": "leaf", "option": "play_soccer", "state": "init", "leaf": 1},  # init: `game.state == ready`
            lambda now, prev, r: (
                node(now, r, "play_soccer")["state"] == "ready"  # type: ignore[index]
                and node(prev, r, "play_soccer")["state"] == "init"
            ),  # type: ignore[index]
        ),
    ]
    for args, right_tick in cases:
        restart_paused(studio)
        before = hits_shown(page)
        assert studio.command("set_breakpoint", **args)["ok"], args
        status = run_until_hit(studio, page, before)
        seq, t, robot = status["seq"], status["t"], hit_robot(page)
        log = ticks(studio, t - 500, t)
        assert right_tick(log[seq], log[seq - 1], robot), (args, seq)

    # a condition over symbols, typed in the option view with the compiler's diagnostics
    restart_paused(studio)
    before = hits_shown(page)
    page.select_option("select[aria-label='Breakpoint kind']", "condition")
    field = page.locator("input[aria-label='Breakpoint condition']")
    field.fill("game.state == playing && ball.distanc > 0")
    page.wait_for_selector(".condition-diagnostics .diagnostic:has-text('1:26: no matching symbol')")
    assert "ball.distance" in page.inner_text(".condition-diagnostics")
    field.fill("game.state == playing && ball.distance > 0")
    page.wait_for_function("() => !document.querySelector('.condition-diagnostics').textContent")
    page.click(".breakpoint-form button:has-text('Add')")
    page.wait_for_selector(".breakpoint-list li code:has-text('when game.state == playing')")
    status = run_until_hit(studio, page, before)
    seq, t, robot = status["seq"], status["t"], hit_robot(page)
    log = ticks(studio, t - 500, t)
    playing = 3  # the element index of game.state.playing
    assert log[seq]["robots"][robot]["inputs"]["game.state"] == playing
    assert log[seq - 1]["robots"][robot]["inputs"]["game.state"] != playing
    assert 7900 <= t <= 8200, t

    # disabling one keeps it listed and stops it from hitting
    page.click(".breakpoint-list li input[type=checkbox]")
    listed = studio.command("list_breakpoints")["result"]["breakpoints"]
    assert [b["enabled"] for b in listed] == [False]
    clear(studio)
    studio.command("resume")


def test_why_at_a_past_tick_shows_operand_values(page: Any, studio: StudioServer) -> None:
    studio.command("resume")
    page.wait_for_function(f"() => {STUDIO}.session.buffer.newest.t > 10000", timeout=40000)
    page.evaluate(f"() => {STUDIO}.session.selectRobot(0)")
    open_option(page, "play_soccer")
    # back to t = 3 s (the game was in ready then): the why uses that tick's recorded values
    page.evaluate(f"() => {STUDIO}.session.setCursor({STUDIO}.session.buffer.newest.t - 4000)")
    page.wait_for_selector(".why .muted:has-text('Values recorded at')", timeout=20000)
    text = page.inner_text(".why")
    assert "game.state (" in text, text  # `game.state (playing) == playing`
    assert page.locator(".why .why-tree .tree-leaf.taken").count() == 1
    assert "Last transition:" in text
    page.keyboard.press("End")
    screenshot(page, "why-recorded")
    time.sleep(0.2)


def test_new_option_dialog_creates_the_file_and_the_include(page: Any, studio: StudioServer) -> None:
    page.keyboard.press("e")
    page.click("button:has-text('New option…')")
    dialog = page.locator("dialog.new-option")
    dialog.wait_for(state="visible")
    page.fill("input[aria-label='Option name']", "2bad")
    page.wait_for_selector(".new-option-problems li:has-text('name: starts with a letter')")
    assert dialog.locator("button:has-text('Create')").is_disabled()
    page.fill("input[aria-label='Option name']", "turn_to_goal")
    page.fill("input[aria-label='Option doc']", "Turns on the spot until the goal is ahead.")
    dialog.locator("button:has-text('+ parameter')").click()
    page.fill("input[aria-label='Parameter name']", "tolerance")
    page.fill("input[aria-label='Range from']", "30")
    page.fill("input[aria-label='Range to']", "5")
    page.wait_for_selector(".new-option-problems li:has-text('the range 30..5 is empty')")
    page.fill("input[aria-label='Range from']", "0")
    page.fill("input[aria-label='Range to']", "45")
    page.fill("input[aria-label='Unit']", "deg")
    assert page.input_value("select[aria-label='Agents file']") == "behavior/agents.xabsl"
    # the diff of the agents file is shown before anything is written
    added = dialog.locator(".new-option-diff .diff-add")
    assert added.count() == 1 and 'include "options/turn_to_goal.xabsl";' in added.inner_text()
    assert 'float @tolerance [0..45] "deg";' in dialog.locator(".new-option-source").inner_text()
    before = get(studio, "api/files/behavior/agents.xabsl")
    assert b"turn_to_goal" not in before
    dialog.locator("button:has-text('Create')").click()
    dialog.wait_for(state="hidden")
    agents = json.loads(get(studio, "api/files/behavior/agents.xabsl"))["text"]
    assert agents.count('include "options/turn_to_goal.xabsl";') == 1
    created = json.loads(get(studio, "api/files/behavior/options/turn_to_goal.xabsl"))["text"]
    assert created.startswith("/** Turns on the spot until the goal is ahead. */\noption turn_to_goal {")
    page.wait_for_function("() => document.querySelector('.cm-content').textContent.includes('option turn_to_goal')")
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        program = json.loads(get(studio, "api/status"))["programs"]["behavior"]
        if "turn_to_goal.xabsl" in " ".join(program["files"]):
            break
        time.sleep(0.3)
    assert program["ok"] is True and any(f.endswith("turn_to_goal.xabsl") for f in program["files"])
    screenshot(page, "new-option")
