"""Defects a new user met in the studio (issue 13), each reproduced in headless chromium.

Every test here failed before its fix. They share one server (module scope, see conftest.py)
and leave it as they found it: running, at 1x, nothing forced or overridden.
"""

from __future__ import annotations

import json
import urllib.request
from collections.abc import Iterator
from typing import Any

import pytest

from tests.e2e.conftest import StudioServer

STUDIO = "window.xabslStudio"


def wait_until(page: Any, expression: str, timeout: float = 20000) -> Any:
    return page.wait_for_function(expression, timeout=timeout)


def api_status(studio: StudioServer) -> dict[str, Any]:
    with urllib.request.urlopen(studio.url + "api/status", timeout=10) as response:
        status: dict[str, Any] = json.loads(response.read())
    return status


def command(studio: StudioServer, op: str, **args: Any) -> Any:
    body = json.dumps({"op": op, **args}).encode()
    request = urllib.request.Request(
        studio.url + "api/command", data=body, headers={"Content-Type": "application/json"}, method="POST"
    )
    with urllib.request.urlopen(request, timeout=10) as response:
        return json.loads(response.read())


@pytest.fixture
def running(studio: StudioServer) -> Iterator[None]:
    """Leave the match running at 1x whatever the test did."""
    yield
    command(studio, "resume")
    command(studio, "speed", speed=1)


def pause_text(page: Any) -> str:
    return str(page.locator("#pause").inner_text())


def test_pause_survives_tab_switches_resizes_reloads_and_other_tabs(
    page: Any, browser: Any, studio: StudioServer, running: None
) -> None:
    page.keyboard.press("Space")
    wait_until(page, "() => document.querySelector('#pause').innerText.includes('Resume')")
    # The server knows: /api/status says paused (it used to say running while the clock stood).
    assert api_status(studio)["paused"] is True
    t = api_status(studio)["t"]
    for key in ("x", "a", "s", "g", "o"):
        if key == "s":
            page.keyboard.press(key)
            page.keyboard.press("Escape")  # S focuses the symbol search
            continue
        page.keyboard.press(key)
        page.wait_for_timeout(150)
        assert "Resume" in pause_text(page), f"after {key!r} the top bar says {pause_text(page)!r}"
    page.set_viewport_size({"width": 1400, "height": 900})
    page.wait_for_timeout(2600)  # longer than the "no frames" threshold
    assert "Resume" in pause_text(page)
    link = page.locator(".link-health").inner_text()
    assert "no frames" not in link and "paused" in link, link
    assert api_status(studio)["t"] == t, "the clock moved while paused"
    page.set_viewport_size({"width": 1600, "height": 1000})

    # A second tab, and a reload, show the match paused.
    other = browser.new_page()
    try:
        other.goto(studio.url)
        wait_until(other, f"() => {STUDIO} && {STUDIO}.session.hello !== null")
        wait_until(other, "() => document.querySelector('#pause').innerText.includes('Resume')")
        # ... and learn about a resume made elsewhere (here: by the first tab).
        page.keyboard.press("Space")
        wait_until(page, "() => document.querySelector('#pause').innerText.includes('Pause')")
        assert api_status(studio)["paused"] is False
        wait_until(other, "() => document.querySelector('#pause').innerText.includes('Pause')")
        # and about a pause made elsewhere, although no frame says so
        page.keyboard.press("Space")
        wait_until(page, "() => document.querySelector('#pause').innerText.includes('Resume')")
        wait_until(other, "() => document.querySelector('#pause').innerText.includes('Resume')", timeout=8000)
    finally:
        other.close()
    page.reload()
    wait_until(page, f"() => {STUDIO} && {STUDIO}.session.hello !== null")
    wait_until(page, "() => document.querySelector('#pause').innerText.includes('Resume')")
    # One Space resumes (it used to pause again).
    page.keyboard.press("Space")
    wait_until(page, "() => document.querySelector('#pause').innerText.includes('Pause')")
    assert api_status(studio)["paused"] is False


def test_end_in_the_speed_dropdown_goes_live_and_keeps_the_speed(
    page: Any, studio: StudioServer, running: None
) -> None:
    page.wait_for_timeout(1000)
    page.evaluate(f"{STUDIO}.session.setCursor({STUDIO}.session.live.t - 500)")
    wait_until(page, f"() => {STUDIO}.session.cursor !== null")
    page.focus("#speed")
    page.keyboard.press("End")
    wait_until(page, f"() => {STUDIO}.session.cursor === null")
    page.wait_for_timeout(300)
    assert page.eval_on_selector("#speed", "s => s.value") == "1"
    assert api_status(studio)["speed"] == 1


def test_the_speeds_of_the_docs_are_offered_and_the_clock_shows_one_step(
    page: Any, studio: StudioServer, running: None
) -> None:
    values = page.eval_on_selector_all("#speed option", "os => os.map(o => Number(o.value))")
    assert min(values) == 0.1 and max(values) == 20, values
    page.select_option("#speed", "20")
    wait_until(page, "() => true")
    page.wait_for_timeout(300)
    assert api_status(studio)["speed"] == 20
    # Choosing a speed hands the keys back: Space pauses instead of opening the dropdown.
    page.keyboard.press("Space")
    wait_until(page, "() => document.querySelector('#pause').innerText.includes('Resume')")
    page.select_option("#speed", "1")
    # One step (25 ms at 40 Hz) is visible in the clock.
    clock = page.locator(".clock")
    before = clock.inner_text()
    page.keyboard.press(".")
    wait_until(page, f"() => document.querySelector('.clock').innerText !== {before!r}")
    after = clock.inner_text()
    assert " ms" in after or "." in after.split(" · ")[-1], after
    assert api_status(studio)["t"] > 0


def open_option_view(page: Any, option: str) -> int:
    option_id = int(
        page.evaluate(f"{STUDIO}.session.indexOf({STUDIO}.session.selectedAgent).optionByName.get({option!r}).id")
    )
    page.evaluate(f"{STUDIO}.session.openOptionById({option_id})")
    page.keyboard.press("o")
    wait_until(page, f"() => document.querySelector('.option-title').innerText === {option!r}")
    return option_id


def test_e_opens_the_file_of_the_option_shown(page: Any) -> None:
    open_option_view(page, "clear_ball")
    page.locator(".option-panel .svg-view").focus()
    page.keyboard.press("e")
    wait_until(page, "() => document.querySelector('.file-title').innerText.includes('clear_ball.xabsl')")
    assert "No file open" not in page.locator(".file-title").inner_text()
    editor_text = "document.querySelector('.editor-host .cm-content').textContent"
    wait_until(page, f"() => {editor_text}.includes('option clear_ball')")
    # the cursor is on the option's declaration
    line = page.evaluate("() => { const v = document.querySelector('.cm-activeLine'); return v ? v.textContent : ''; }")
    assert "clear_ball" in line, line


def test_escape_in_the_editor_keeps_the_focus_there(page: Any) -> None:
    page.keyboard.press("e")
    page.locator(".file-tree [data-path='behavior/options/clear_ball.xabsl']").click()
    wait_until(page, "() => document.querySelector('.editor-host .cm-content').textContent.includes('clear_ball')")
    content = page.locator(".editor-host .cm-content")
    content.click()
    page.keyboard.press("Control+End")
    page.keyboard.press("Enter")
    page.keyboard.type("ba")
    page.keyboard.press("Control+Space")
    page.locator(".cm-tooltip-autocomplete").wait_for()
    page.keyboard.press("Escape")
    page.locator(".cm-tooltip-autocomplete").wait_for(state="hidden")
    assert page.evaluate("() => !!document.activeElement.closest('.cm-editor')"), "Escape left the editor"
    page.keyboard.press("Escape")
    assert page.evaluate("() => !!document.activeElement.closest('.cm-editor')"), "a second Escape left the editor"
    # The next letters are text, not shortcuts (g = option graph, a = activation).
    page.keyboard.type("ga")
    assert page.locator(".editor-panel").is_visible()
    assert "baga" in content.text_content()
    page.keyboard.press("Control+z")
    page.keyboard.press("Control+z")


def test_a_shared_symbols_file_shows_only_its_own_behavior_sets_warnings(page: Any) -> None:
    page.keyboard.press("e")
    for path in ("behavior/symbols/robot_symbols.xabsl", "behavior/basic_behaviors.xabsl"):
        page.locator(f".file-tree [data-path='{path}']").click()
        wait_until(page, f"() => document.querySelector('.file-title').innerText.startsWith({path!r})")
        content = page.locator(".editor-host .cm-content")
        content.click()
        page.keyboard.press("Control+End")
        page.keyboard.type(" ")  # a change: the linter compiles the buffer
        page.locator(".editor-status.ok").wait_for(timeout=15000)
        page.wait_for_timeout(1500)
        status = page.locator(".editor-status").inner_text()
        assert "warning" not in status, f"{path}: {status}"
        assert page.locator(".editor-host .cm-lintRange-warning").count() == 0
        page.keyboard.press("Backspace")


def test_the_tester_says_what_is_wrong_with_a_parameter(page: Any) -> None:
    page.keyboard.press("x")
    page.select_option("#test-target", "behavior:turn")
    page.fill("#param-rate", "200")
    page.click("#test-run")
    error = page.locator(".tester-panel .param-error")
    error.first.wait_for()
    assert "-57" in error.first.inner_text() and "57" in error.first.inner_text()
    assert page.get_attribute("#param-rate", "aria-invalid") == "true"
    page.wait_for_timeout(500)
    assert page.evaluate(f"{STUDIO}.session.agentInView().forced") is None
    page.fill("#param-rate", "")
    page.click("#test-run")
    wait_until(page, "() => document.querySelector('.tester-panel .param-error').innerText.includes('number')")
    page.wait_for_timeout(300)
    assert page.evaluate(f"{STUDIO}.session.agentInView().forced") is None
    # A good value clears the message and runs.
    page.fill("#param-rate", "20")
    page.click("#test-run")
    page.locator(".toast.ok", has_text="turn runs as the root").wait_for()
    assert page.locator(".tester-panel .param-error:visible").count() == 0
    page.click("#test-release")
    wait_until(page, f"() => {STUDIO}.session.agentInView().forced === null")


def test_an_override_is_released_with_one_click_and_its_row_fits(page: Any) -> None:
    page.keyboard.press("s")
    page.keyboard.press("Escape")
    row = page.locator(".symbol-row[data-kind='input']").first
    name = row.get_attribute("data-symbol")
    row.locator("button", has_text="set…").click()
    editor = row.locator(".override-editor")
    editor.wait_for()
    panel = page.locator(".symbols-panel").bounding_box()
    for label in ("Override", "Release", "Cancel"):
        box = editor.locator("button", has_text=label).bounding_box()
        assert box is not None and panel is not None
        assert box["x"] >= panel["x"] and box["x"] + box["width"] <= panel["x"] + panel["width"] + 0.5, (
            f"{label} is clipped: {box} outside {panel}"
        )
    editor.locator("button", has_text="Override").click()
    overridden = page.locator(f".symbol-row.overridden[data-symbol='{name}']")
    overridden.wait_for()
    # One click releases it.
    overridden.locator("button.release").click()
    row_of = f"document.querySelector(\".symbol-row[data-symbol='{name}']\")"
    wait_until(page, f"() => !{row_of}.classList.contains('overridden')")
    assert page.evaluate(f"Object.keys({STUDIO}.session.agentInView().overrides ?? {{}}).length") == 0
