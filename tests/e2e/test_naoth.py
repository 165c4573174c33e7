"""A NaoTH robot in the studio, in Chromium: its activation tree arrives, and the tester says that
the robot cannot be forced (the buttons are there, disabled, with the reason) instead of hiding it.

The robot is the test robot of tests/naoth/robot.py (NaoTH's debug port, its own process); the
studio is ``xabsl attach naoth://...`` (its own process).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from tests.attach.test_attached import Studio
from tests.e2e.conftest import studio_tab
from tests.naoth.test_attach import BEHAVIOR, Robot

STUDIO = "window.xabslStudio"


@pytest.fixture
def naoth_tab(browser: Any, tmp_path: Path) -> Iterator[Any]:
    robot = Robot(tmp_path)
    studio = Studio(f"naoth://127.0.0.1:{robot.port}", "--behavior", str(BEHAVIOR), "--no-record")
    try:
        with studio_tab(browser, SimpleNamespace(url=f"http://127.0.0.1:{studio.port}/")) as tab:
            yield tab
    finally:
        studio.stop()
        robot.stop()


def test_the_robots_tree_shows_and_forcing_is_shown_unavailable(naoth_tab: Any) -> None:
    tab = naoth_tab
    tab.wait_for_function(
        f"() => {STUDIO}.session.live && {STUDIO}.session.live.robots[0].path.length > 0", timeout=30000
    )
    root = tab.evaluate(f"() => {STUDIO}.session.live.robots[0].path[0]")
    assert root["kind"] == "option"
    tab.keyboard.press("x")
    note = tab.locator(".tester-panel .test-unavailable")
    note.wait_for(timeout=15000)
    assert "A NaoTH robot cannot be forced" in note.inner_text()
    assert tab.locator("#test-run").is_disabled() and tab.locator("#test-release").is_disabled()
