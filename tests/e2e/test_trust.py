"""What a new user tripped on in a debugger that must be trusted (issue 23), in headless chromium.

Every test here failed before its fix. They share one server (module scope, see conftest.py).
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from typing import Any

from tests.e2e.conftest import REPO, StudioServer


def wait_until(page: Any, expression: str, timeout: float = 20000) -> Any:
    return page.wait_for_function(expression, timeout=timeout)


def open_file(page: Any, path: str, needle: str) -> None:
    page.keyboard.press("e")
    page.locator(f".file-tree [data-path='{path}']").click()
    wait_until(page, f"() => document.querySelector('.editor-host .cm-content').textContent.includes({needle!r})")


def cli_count(studio: StudioServer, agents: str) -> tuple[int, int]:
    """(errors, warnings) that ``xabsl compile`` prints for ``agents`` (relative to the example)."""
    done = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "compile", agents],
        cwd=studio.example,
        capture_output=True,
        text=True,
        env={"PYTHONPATH": str(REPO), "PATH": "/usr/bin:/bin"},
    )
    summary = done.stdout.strip().splitlines()[-1]
    found = re.search(r"(\d+) errors?, (\d+) warnings?", summary)
    assert found, summary
    return int(found.group(1)), int(found.group(2))


def status_warnings(page: Any) -> int:
    text = str(page.locator(".editor-status").inner_text())
    found = re.search(r"(\d+) warnings?", text)
    return int(found.group(1)) if found else 0


def test_the_editor_counts_the_diagnostics_the_cli_prints(page: Any, studio: StudioServer) -> None:
    """The chase set reads the team's symbol files: their warnings are chase's too (CLI: 16)."""
    errors, warnings = cli_count(studio, "chase/agents.xabsl")
    assert (errors, warnings) == (0, 16)
    open_file(page, "chase/chase_ball.xabsl", "chase_ball")
    wait_until(page, "() => /warning/.test(document.querySelector('.editor-status').innerText)")
    page.wait_for_timeout(1500)  # every file's diagnostics have arrived
    assert status_warnings(page) == warnings
    # the team's own set has none, and its editor says so whatever chase found in shared files
    open_file(page, "behavior/options/face_ball.xabsl", "face_ball")
    page.wait_for_timeout(1500)
    assert cli_count(studio, "behavior/agents.xabsl") == (0, 0)
    assert status_warnings(page) == 0


STUDIO = "window.xabslStudio"


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


def clear_breakpoints(studio: StudioServer) -> None:
    for b in studio.command("list_breakpoints")["result"]["breakpoints"]:
        studio.command("remove_breakpoint", program=b["program"], breakpoint=b["breakpoint"])


def test_the_why_after_a_breakpoint_hit_shows_values(page: Any, studio: StudioServer) -> None:
    """A hit pauses the match: no frame redraws the why, so the answer itself must (it stayed
    on "Asking the server for values…")."""
    page.evaluate(f"() => {STUDIO}.session.selectRobot(0)")
    open_option(page, "play_soccer")
    studio.command("pause")
    clear_breakpoints(studio)
    assert studio.command("reset")["ok"]
    hits = "() => Number(document.querySelector('.timeline-canvas').dataset.hits || 0)"
    before = int(page.evaluate(hits))
    args = {"program": "behavior", "kind": "enter_state", "option": "play_soccer", "state": "ready"}
    assert studio.command("set_breakpoint", **args)["ok"]
    try:
        studio.command("speed", speed=4)
        studio.command("resume")
        wait_until(page, f"() => ({hits})() > {before}", timeout=40000)
        why = page.locator(".why")
        wait_until(page, "() => document.querySelector('.why').innerText.includes('Values')", timeout=10000)
        text = str(why.inner_text())
        assert "Asking the server for values" not in text, text
        assert page.locator(".why .why-tree .tree-leaf.taken").count() == 1
    finally:
        clear_breakpoints(studio)
        studio.command("speed", speed=1)
        studio.command("resume")


def test_the_server_console_stays_quiet_while_the_editor_talks_to_the_language_server(
    page: Any, studio: StudioServer
) -> None:
    """A few keystrokes wrote 112 KB of the language server's debug lines to the console."""
    open_file(page, "behavior/options/face_ball.xabsl", "face_ball")
    before = studio.log.stat().st_size
    page.locator(".editor-host .cm-content").click()
    page.keyboard.press("Control+End")
    for _ in range(3):
        page.keyboard.type("/* x */")
        page.wait_for_timeout(400)
    page.keyboard.press("Control+z")
    page.wait_for_timeout(1000)
    grown = studio.log.read_bytes()[before:].decode(errors="replace")
    assert len(grown) < 500, grown[:2000]
    page.keyboard.press("Control+z")
    page.keyboard.press("Control+z")


def test_the_editor_does_not_stay_scrolled_sideways_after_typing_at_a_line_end(page: Any, studio: StudioServer) -> None:
    """Typing at the end of a line longer than the pane scrolled the view sideways, and moving to a
    short line left it so: every line's start hidden."""
    open_file(page, "behavior/options/face_ball.xabsl", "face_ball")
    scroller = "document.querySelector('.editor-host .cm-scroller')"
    page.locator(".editor-host .cm-content").click()
    page.keyboard.press("Control+Home")
    page.keyboard.press("End")  # line 1, the doc comment: longer than the pane is wide
    page.keyboard.type(" x")
    page.wait_for_timeout(300)
    scrolled = page.evaluate(f"() => [{scroller}.scrollLeft, {scroller}.clientWidth, {scroller}.scrollWidth]")
    assert scrolled[0] > 0, scrolled  # following the cursor past the right edge
    page.keyboard.press("Backspace")
    page.keyboard.press("Backspace")
    page.keyboard.press("ArrowDown")  # `option face_ball {`: short
    page.wait_for_timeout(300)
    assert page.evaluate(f"() => {scroller}.scrollLeft") == 0


def test_a_completion_opened_by_a_digit_closes_when_the_file_is_saved(page: Any, studio: StudioServer) -> None:
    path = "behavior/options/face_ball.xabsl"
    original = (studio.example / path).read_text()
    open_file(page, path, "face_ball")
    line = next(n for n, text in enumerate(original.split("\n")) if "< 10)" in text)
    page.locator(".editor-host .cm-content").click()
    page.keyboard.press("Control+Home")
    for _ in range(line):
        page.keyboard.press("ArrowDown")
    page.keyboard.press("End")
    page.keyboard.press("ArrowLeft")  # after the 10
    try:
        page.keyboard.type("5")  # `< 105`: a number names nothing to complete
        popup = page.locator(".cm-tooltip-autocomplete")
        page.wait_for_timeout(1000)
        assert popup.count() == 0, "typing a digit opened the completion popup"
        page.keyboard.press("Control+Space")  # asked for, it opens
        popup.wait_for(timeout=15000)
        page.keyboard.press("Control+s")
        page.locator(".editor-status", has_text="hot reloaded").wait_for(timeout=15000)
        assert (studio.example / path).read_text() == original.replace("< 10)", "< 105)")
        page.wait_for_timeout(300)
        assert popup.count() == 0, "the completion popup stayed open after the save"
    finally:
        page.keyboard.press("Escape")
        page.keyboard.press("Backspace")
        page.keyboard.press("Control+s")
        page.wait_for_function("() => !document.querySelector('.file-title').textContent.includes('●')", timeout=15000)
    assert (studio.example / path).read_text() == original
