"""The behavior documentation in headless chromium: from disk (``file://``) and from the studio's /docs.

The pages must render (the state machine's SVG laid out with its states), the search box must
find an option and take the reader to its page, and the links of the option graph must lead to
option pages: offline, straight from the folder ``xabsl docs`` wrote, and as the studio serves it.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.e2e.conftest import StudioServer, screenshot, watched_tab
from xabsl_studio.engine.cli import main

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def soccer_docs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("soccer-docs")
    assert main(["docs", str(REPO / "examples" / "soccer" / "behavior" / "agents.xabsl"), "-o", str(folder)]) == 0
    return folder


@pytest.fixture
def tab(browser: Any) -> Iterator[Any]:
    with watched_tab(browser) as page:
        yield page


def search_and_open(page: Any, query: str, expected: str) -> None:
    page.fill("#search", query)
    first = page.locator("#search-results a").first
    first.wait_for(timeout=5000)
    assert first.inner_text().endswith(expected)
    page.keyboard.press("Enter")
    page.wait_for_url(f"**/options/{expected}.html", timeout=5000)


def test_index_and_option_page_render_offline_and_search_finds_an_option(tab: Any, soccer_docs: Path) -> None:
    tab.goto((soccer_docs / "index.html").as_uri())
    assert tab.locator("h1").inner_text() == "xabsl-studio example soccer team"
    assert tab.locator("#options + ul li").count() == 31
    search_and_open(tab, "strik", "striker")
    # the state machine: an inline SVG with a laid-out node per state, and the decision trees
    svg = tab.locator(".graph svg")
    box = svg.bounding_box()
    assert box is not None and box["width"] > 200 and box["height"] > 50
    assert tab.locator(".graph svg g.node").count() == 1 + tab.locator("section[id^=state-]").count()
    assert tab.locator("pre.tree").first.inner_text().strip()
    # a transition edge leads to its leaf in the decision tree
    # Graphviz writes xlink:href: ``*|href`` matches it in any namespace
    edge = tab.locator('.graph svg g.edge a[*|href^="#leaf-"]').first
    href = edge.get_attribute("xlink:href")
    edge.locator("text").first.click()
    assert tab.evaluate("location.hash") == href
    assert tab.locator(f"{href}").is_visible()
    screenshot(tab, "docs-option")


def test_option_graph_nodes_lead_to_option_pages(tab: Any, soccer_docs: Path) -> None:
    tab.goto((soccer_docs / "agents" / "soccer.html").as_uri())
    nodes = tab.locator(".graph svg g.node")
    assert nodes.count() > 31  # the options and the basic behaviors they run
    tab.locator('.graph svg g.node a[*|href$="options/role_selection.html"]').click()
    tab.wait_for_url("**/options/role_selection.html", timeout=5000)
    assert tab.locator("h1").inner_text() == "option role_selection"


def test_the_studio_serves_the_running_behaviors_docs(tab: Any, studio: StudioServer) -> None:
    tab.goto(studio.url + "docs")
    links = tab.locator("li a")
    assert links.count() == 2  # soccer runs two behaviors (home first, then the away team): both listed
    links.first.click()
    tab.wait_for_url("**/index.html", timeout=10000)
    assert tab.locator("h1").inner_text()
    search_and_open(tab, "approach_ball", "approach_ball")
    assert tab.locator(".graph svg g.node").count() >= 2
    screenshot(tab, "docs-studio")
