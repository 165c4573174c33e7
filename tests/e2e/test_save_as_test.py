"""Save as test in the Test panel: the forced option and its parameters end up in a test file that runs."""

from __future__ import annotations

from typing import Any

from tests.e2e.conftest import StudioServer
from xabsl_studio.engine.testing.runner import run_case
from xabsl_studio.engine.testing.spec import load_suite


def test_save_as_test_writes_a_suite_that_passes(page: Any, studio: StudioServer) -> None:
    page.keyboard.press("x")
    page.select_option("#test-target", "option:go_to_position")
    page.fill("#param-x", "-1500")
    page.fill("#param-y", "700")
    page.click("#test-run")
    page.locator(".toast.ok", has_text="go_to_position runs as the root").wait_for()
    # The tick in view shows the forced root before the draft is taken from it.
    page.wait_for_function(
        "() => { const r = window.xabslStudio.session.robotInView(); return !!r && r.forced !== null; }"
    )
    page.once("dialog", lambda dialog: dialog.accept("walks to the left"))
    page.click("#test-save")
    page.locator(".toast.ok", has_text="Saved tests/walks_to_the_left.xabsl-test.toml").wait_for()
    file = studio.example / "tests" / "walks_to_the_left.xabsl-test.toml"
    [case] = load_suite(file).cases
    assert case.force is not None
    kind, name, params = case.force
    assert (kind, name) == ("option", "go_to_position")
    assert params["x"] == -1500 and params["y"] == 700
    assert {"ball", "robots", "game_state"} <= set(case.setup)
    result = run_case(case)
    assert result.ok, result.report()
