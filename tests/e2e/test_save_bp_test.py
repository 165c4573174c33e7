"""Save as test from a breakpoint hit in headless chromium: set a breakpoint, it hits, the hit's
"Save as test" writes a test file that starts from the world at the hit and passes."""

from __future__ import annotations

from typing import Any

from tests.e2e.conftest import StudioServer, screenshot
from tests.e2e.test_breakpoints import (  # noqa: F401 (state_dir: the autouse private state folder)
    STUDIO,
    hits_shown,
    open_option,
    restart_paused,
    run_until_hit,
    state_dir,
)
from xabsl_studio.engine.testing.runner import run_case
from xabsl_studio.engine.testing.spec import load_suite


def test_save_as_test_from_a_hit_writes_a_test_that_passes(page: Any, studio: StudioServer) -> None:
    page.evaluate(f"() => {STUDIO}.session.selectRobot(0)")
    open_option(page, "play_soccer")
    restart_paused(studio)
    before = hits_shown(page)
    page.click(".option-panel svg g#state_1", button="right")  # state 1 of play_soccer: ready
    page.click(".context-menu button:has-text('Break on enter ready')")
    page.wait_for_selector(".breakpoint-list li code:has-text('enter play_soccer.ready')")
    status = run_until_hit(studio, page, before)
    row = page.locator(".breakpoint-hits li", has_text="enter play_soccer.ready on blue1 ")
    row.wait_for()
    screenshot(page, "breakpoint-save-as-test")
    page.once("dialog", lambda dialog: dialog.accept("goes to ready"))
    row.locator("button", has_text="Save as test").click()
    page.locator(".toast.ok", has_text="Saved tests/goes_to_ready.xabsl-test.toml").wait_for()
    file = studio.example / "tests" / "goes_to_ready.xabsl-test.toml"
    text = file.read_text()
    assert text.startswith("# Saved from breakpoint `enter play_soccer.ready`")
    assert f"after tick {status['seq']}" in text
    [case] = load_suite(file).cases
    assert {"ball", "robots", "game_state"} <= set(case.setup)
    assert [(e.option, e.state) for e in case.expects] == [("play_soccer", "ready")]
    result = run_case(case)
    assert result.ok, result.report()
    studio.command("resume")
