"""Divergence in the studio (Chromium): the Compare view names where two runs part, the timeline marks it.

A replay of the original run, with the original and a run of a known edit (tests/compare/runs.py)
in its library: comparing the two recordings names the first divergence, the tick an independent
scan of both files finds, and the timeline marks that tick.
"""

from __future__ import annotations

import json
import shutil
from collections.abc import Iterator
from typing import Any

import pytest

from tests.compare.runs import Runs, record_runs
from tests.compare.test_diverge import first_difference
from tests.e2e.conftest import StudioServer, screenshot, serving, studio_tab

STUDIO = "window.xabslStudio"


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Runs:
    return record_runs(tmp_path_factory.mktemp("diverge-e2e-runs"))


@pytest.fixture(scope="module")
def replay_server(runs: Runs, tmp_path_factory: pytest.TempPathFactory) -> Iterator[StudioServer]:
    root = tmp_path_factory.mktemp("diverge-e2e")
    library = root / "recordings"  # the server's --record-dir: its library
    library.mkdir()
    for path in (runs.original, runs.edited):
        shutil.copy(path, library / path.name)
    with serving(library / runs.original.name, root, replay=True) as server:
        yield server


@pytest.fixture
def tab(browser: Any, replay_server: StudioServer) -> Iterator[Any]:
    with studio_tab(browser, replay_server, live=False) as page:
        yield page


def test_the_compare_view_names_the_first_divergence_and_the_timeline_marks_it(tab: Any, runs: Runs) -> None:
    expected = first_difference(runs.original, runs.edited, "blue2")
    assert expected is not None
    tab.wait_for_function(f"() => {STUDIO}.session.buffer.length > 1000", timeout=30000)
    tab.locator("button#compare").click()
    dialog = tab.locator("dialog.compare[open]")
    dialog.locator("select.compare-program").select_option("behavior")
    dialog.locator("input.compare-old").fill("recording:original.mcap")
    dialog.locator("input.compare-new").fill("recording:edited.mcap")
    dialog.locator("select.compare-recording").select_option("edited.mcap")
    dialog.locator("select.compare-against").select_option("original.mcap")
    dialog.locator("button.compare-run").click()
    head = dialog.locator(".compare-diverge strong")
    head.wait_for(timeout=60000)
    assert head.inner_text().startswith("First divergence: blue2 at ") and f"(tick {expected})" in head.inner_text()
    first = dialog.locator(".compare-diverge-list li").first.inner_text()
    assert "approach_ball" in first and "edited.mcap far stays" in first and "original.mcap far → near" in first
    screenshot(tab, "compare-diverge")
    dialog.locator("button", has_text="Close").click()
    tab.wait_for_function("() => document.querySelector('.timeline-canvas').dataset.divergence !== undefined")
    mark = json.loads(tab.locator(".timeline-canvas").get_attribute("data-divergence"))
    assert (mark["seq"], mark["agent"]) == (expected, "blue2")
