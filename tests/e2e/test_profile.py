"""The profiler in headless Chromium: the HTML report offline, and the studio's coverage overlay.

The report must open from disk with no request leaving the file, show its graphs laid out and
switch the activity plot between agents; in the studio, the Coverage tab must count the session
(GET /api/profile), dim never-active options in the option graph and never-entered states and never-taken
transitions in the state-machine view, with counts on hover, and move
the timeline cursor to an oscillation when it is clicked.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.e2e.conftest import screenshot, watched_tab
from tests.profile.conftest import record
from xabsl_studio.engine.cli import main


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("profile-report")
    recording = record(folder / "team.mcap", robots=2)
    out = folder / "report.html"
    assert main(["profile", str(recording), "--html", str(out)]) == 0
    return out


@pytest.fixture
def tab(browser: Any) -> Iterator[Any]:
    with watched_tab(browser) as page:
        yield page


def test_the_report_opens_offline_with_its_graphs_and_plots(tab: Any, report: Path) -> None:
    requests: list[str] = []
    tab.on("request", lambda request: requests.append(request.url))
    tab.goto(report.as_uri())
    assert all(url.startswith("file://") for url in requests), requests
    assert tab.locator("h2").first.inner_text().startswith("Team cycler")
    graph = tab.locator("section[id^=team-] > .graph svg").first
    box = graph.bounding_box()
    assert box is not None and box["width"] > 100 and box["height"] > 30
    # the never-active option is drawn, dashed and grey; the others coloured by share
    assert tab.locator("#option_2 title, g[id^=option_]").count() >= 3
    # one activity plot per agent, the select shows one at a time
    plots = tab.locator(".activity")
    assert plots.count() == 2
    assert plots.nth(0).is_visible() and not plots.nth(1).is_visible()
    tab.select_option("select[data-agents]", "robot2")
    assert plots.nth(1).is_visible() and not plots.nth(0).is_visible()
    assert tab.locator(".activity[data-agent=robot2] rect.bar").count() >= 11  # cycle once, sub ten times
    tab.locator("details summary").first.click()
    assert tab.locator("details[open] .graph svg g.node").count() >= 2
    assert "Oscillations (54)" in tab.locator("#oscillations h2").inner_text()
    screenshot(tab, "profile-report")


def test_studio_coverage_dims_the_graph_and_jumps_to_an_oscillation(page: Any) -> None:
    page.click("[data-tab=graph]")
    page.wait_for_selector(".graph-panel svg g[id^=option_]", timeout=20000)
    page.click("[data-tab=coverage]")
    page.click(".coverage-panel button:has-text('Refresh')")
    page.wait_for_function(
        "() => /options \\d+\\/\\d+/.test(document.querySelector('.coverage-panel .figures').textContent)",
        timeout=20000,
    )
    # pre-game and kick-off: most of the playing options never ran, they are dimmed
    page.wait_for_function("() => document.querySelectorAll('.graph-panel svg .never').length > 3", timeout=10000)
    active = page.locator(".graph-panel svg g[id^=option_]:not(.never)").first
    assert "% of the time" in active.locator("title").first.text_content()
    never = page.locator(".graph-panel svg g.never[id^=option_]").first
    assert "never active" in never.locator("title").first.text_content()
    screenshot(page, "profile-coverage")
    # the state machine of play_soccer: "finished" is never entered before the match ends
    page.evaluate(
        """() => {
            const s = window.xabslStudio.session;
            const o = s.indexOf(s.selectedRobot).optionByName.get("play_soccer");
            s.openOptionById(o.id);
        }"""
    )
    page.click("[data-tab=option]")
    page.wait_for_function(
        "() => document.querySelectorAll('.option-panel svg .never[id^=state_]').length >= 1", timeout=15000
    )
    never_states = page.locator(".option-panel svg .never[id^=state_] > title").all_text_contents()
    assert "finished: never active" in never_states
    assert page.locator(".option-panel svg .never[id^=leaf_]").count() >= 1
    entered = page.locator(".option-panel svg [id^=state_]:not(.never) title").first.text_content()
    assert "% of the time" in entered
    # with a threshold of ten minutes any re-entered state is an oscillation: one soon turns up
    page.fill(".coverage-panel input[type=number]", "600000")
    for _ in range(60):
        page.click(".coverage-panel button:has-text('Refresh')")
        page.wait_for_timeout(1000)
        if page.locator(".coverage-panel li button").count():
            break
    item = page.locator(".coverage-panel li button").first
    assert "away" in item.inner_text()
    item.click()
    cursor = page.evaluate("() => window.xabslStudio.session.cursor")
    assert cursor is not None
    oldest = page.evaluate("() => window.xabslStudio.session.buffer.oldest.t")
    assert cursor >= oldest
