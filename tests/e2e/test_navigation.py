"""Navigating a team-sized behavior set in the studio (issue 31), in Debian's chromium.

A generated naoth-shaped set (tests/navset.py: 200 options in 15 folders) runs on 5 robots of the
bench world through the real ``xabsl serve``. The option graph opens as its overview (one node
per folder) that fits the panel with labels of at least 9 CSS px; a click expands a folder and
collapses it again; Find jumps to an option (expanding its folder) and to a state (in the option
view); the selected robot's path stays bright while the rest fades, and that follows the robot.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import Any

import pytest

from tests import navset
from tests.e2e.conftest import StudioServer, screenshot, serving, studio_tab

#: The smallest label of the overview, in CSS px on screen (a 9 px label is still read).
READABLE_PX = 9.0
#: groups of the generated set: its folders and the basic behaviors it calls
GROUPS = len(navset.FOLDERS) + 1

GRAPH = ".graph-panel .svg-view"


@pytest.fixture(scope="module")
def team(tmp_path_factory: pytest.TempPathFactory) -> Iterator[StudioServer]:
    root = tmp_path_factory.mktemp("team")
    navset.write_set(root / "team")
    with serving(root / "team", root, extra=("--robots", "5")) as server:
        yield server


@pytest.fixture
def tab(browser: Any, team: StudioServer) -> Iterator[Any]:
    with studio_tab(browser, team) as page:
        page.keyboard.press("g")
        page.wait_for_function(f"() => document.querySelectorAll('{GRAPH} g.node[id^=group_]').length > 0")
        yield page


def node_ids(tab: Any) -> list[str]:
    return list(tab.evaluate(f"() => [...document.querySelectorAll('{GRAPH} g.node')].map((n) => n.id)"))


def label_px(tab: Any, texts: str = f"{GRAPH} g.node text") -> list[float]:
    """The font size on screen (CSS px) of each of ``texts``: its font size times its scale on screen."""
    return list(
        tab.evaluate(
            """(texts) => [...document.querySelectorAll(texts)].map((t) =>
                parseFloat(t.getAttribute('font-size')) * t.getBoundingClientRect().height / t.getBBox().height)""",
            texts,
        )
    )


def test_overview_fits_the_panel_with_readable_labels(tab: Any) -> None:
    ids = node_ids(tab)
    assert sorted(ids) == sorted(f"group_{n}" for n in range(GROUPS)), ids
    sizes = label_px(tab)
    assert len(sizes) == 2 * GROUPS - 1  # folder name and count; the behaviors' group has one line
    assert min(sizes) >= READABLE_PX, sizes
    # all of it inside the panel at once, on a 1600x1000 window
    outside = tab.evaluate(
        f"""() => {{
            const view = document.querySelector('{GRAPH}').getBoundingClientRect();
            return [...document.querySelectorAll('{GRAPH} g.node')].filter((n) => {{
                const r = n.getBoundingClientRect();
                return r.left < view.left || r.right > view.right || r.top < view.top || r.bottom > view.bottom;
            }}).map((n) => n.id);
        }}"""
    )
    assert outside == []
    assert tab.evaluate("window.innerWidth") == 1600
    screenshot(tab, "team-overview")


def group_of(tab: Any, key: str) -> str:
    """The element id of the collapsed group of folder ``key`` (by its label)."""
    found = tab.evaluate(
        f"""(key) => [...document.querySelectorAll('{GRAPH} g.node[id^=group_]')]
            .find((n) => n.querySelector('text').textContent === key)?.id ?? null""",
        key,
    )
    assert found, key
    return str(found)


def test_a_click_expands_a_folder_and_its_name_collapses_it(tab: Any) -> None:
    kicks = [name for name, folder in navset.option_names().items() if folder == "Options/Kicks"]
    tab.click(f"{GRAPH} #{group_of(tab, 'Kicks')}")
    tab.wait_for_function(f"() => document.querySelectorAll('{GRAPH} g.node[id^=option_]').length > 0")
    shown = {
        tab.evaluate("(id) => document.getElementById(id).querySelector('text').textContent", i)
        for i in node_ids(tab)
        if i.startswith("option_")
    }
    assert shown == set(kicks)
    assert len(node_ids(tab)) == GROUPS - 1 + len(kicks)
    # the folder's frame: a click on its name collapses it again
    tab.click(f"{GRAPH} g.cluster text >> text='Kicks'")
    tab.wait_for_function(f"() => document.querySelectorAll('{GRAPH} g.node[id^=option_]').length === 0")
    assert len(node_ids(tab)) == GROUPS
    # Expand all: every option in its folder's frame; Overview collapses them again
    tab.click(".graph-panel button:has-text('Expand all')")
    tab.wait_for_function(f"() => document.querySelectorAll('{GRAPH} g.node[id^=option_]').length === 200")
    expanded = len(node_ids(tab))
    tab.click(".graph-panel button:has-text('Overview')")
    tab.wait_for_function(f"() => document.querySelectorAll('{GRAPH} g.node').length === {GROUPS}")
    assert expanded > 10 * GROUPS
    # the minimap shows while the picture is larger than the panel (expanded), not at the overview
    assert not tab.is_visible(f"{GRAPH} .minimap")


def listed(tab: Any) -> list[list[str]]:
    """The search results listed: kind, name, and the option of a state."""
    tab.wait_for_selector(".find-results li")
    return list(
        tab.evaluate(
            """() => [...document.querySelectorAll('.find-results li')].map((li) =>
                [...li.children].map((c) => c.textContent).concat(['']).slice(0, 3))"""
        )
    )


def centre_offset(tab: Any, view: str, element: str) -> float:
    """How far (CSS px) element ``element`` is from the middle of ``view``."""
    return float(
        tab.evaluate(
            """([view, element]) => {
                const v = document.querySelector(view).getBoundingClientRect();
                const e = document.querySelector(element).getBoundingClientRect();
                const dx = e.left + e.width / 2 - (v.left + v.width / 2);
                return Math.hypot(dx, e.top + e.height / 2 - (v.top + v.height / 2));
            }""",
            [view, element],
        )
    )


def test_find_jumps_to_an_option_in_a_collapsed_folder(tab: Any) -> None:
    name = next(n for n, folder in navset.option_names().items() if folder == "Options/Tools")
    tab.keyboard.press("/")
    tab.keyboard.type(name)
    assert listed(tab)[0] == ["option", name, ""]
    tab.keyboard.press("Enter")
    tab.wait_for_selector(f"{GRAPH} g.node.found")
    found = tab.evaluate(f"() => document.querySelector('{GRAPH} g.node.found text').textContent")
    assert found == name
    # its folder was expanded for it, and it is in the middle of the panel, at a readable size
    assert group_of_missing(tab, "Tools")
    assert centre_offset(tab, GRAPH, f"{GRAPH} g.node.found") < 5
    assert min(label_px(tab, f"{GRAPH} g.node.found text")) >= READABLE_PX
    screenshot(tab, "team-find-option")


def group_of_missing(tab: Any, key: str) -> bool:
    return bool(
        tab.evaluate(
            f"""(key) => ![...document.querySelectorAll('{GRAPH} g.node[id^=group_]')]
                .some((n) => n.querySelector('text').textContent === key)""",
            key,
        )
    )


def test_find_jumps_to_a_state_of_another_option(tab: Any) -> None:
    tab.keyboard.press("/")
    tab.keyboard.type(navset.FALLEN)
    assert listed(tab)[0] == ["state", navset.FALLEN, f" in {navset.ROOT}"]
    tab.keyboard.press("Enter")
    view = ".option-panel .svg-view"
    tab.wait_for_selector(f"{view} g.node.found")
    assert tab.inner_text(".option-panel .option-title") == navset.ROOT
    label = tab.evaluate(f"() => document.querySelector('{view} g.node.found text').textContent")
    assert label.startswith(navset.FALLEN)
    assert centre_offset(tab, view, f"{view} g.node.found") < 5
    # a machine of 31 states is larger than the view: the minimap shows where this is
    assert tab.is_visible(f"{view} .minimap")
    screenshot(tab, "team-find-state")


def active_and_faded(tab: Any) -> tuple[set[str], set[str]]:
    """Nodes drawn at full strength and nodes faded (computed fill opacity), in the option graph."""
    rows = tab.evaluate(
        f"""() => [...document.querySelectorAll('{GRAPH} g.node')].map((n) => [
            n.id, n.classList.contains('active'), parseFloat(getComputedStyle(n).fillOpacity),
        ])"""
    )
    for node, active, opacity in rows:
        assert (opacity == 1) == active, (node, active, opacity)
    return {n for n, a, _ in rows if a}, {n for n, a, _ in rows if not a}


def test_fading_follows_the_selected_robot(tab: Any, team: StudioServer) -> None:
    # robot 2 falls (by hand): its root option only calls stand
    reply = team.command("override_input", robot=1, symbol="robot.is_fallen", value=True)
    assert reply["ok"], reply
    try:
        soccer, behaviors = group_of(tab, "Soccer"), group_of(tab, "4 basic behaviors")
        tab.keyboard.press("2")
        tab.wait_for_function(
            """([graph, wanted]) => {
                const active = [...document.querySelectorAll(graph + ' g.node.active')].map((n) => n.id).sort();
                return JSON.stringify(active) === JSON.stringify(wanted);
            }""",
            arg=[GRAPH, sorted([soccer, behaviors])],
        )
        assert tab.evaluate(f"() => document.querySelector('{GRAPH}').classList.contains('fade')")
        active, faded = active_and_faded(tab)
        assert active == {soccer, behaviors} and len(faded) == GROUPS - 2
        # robot 1 runs on into other folders: other nodes are bright, Soccer's stays
        tab.keyboard.press("1")
        tab.wait_for_function(
            """([graph, known]) => [...document.querySelectorAll(graph + ' g.node.active')]
                .some((n) => !known.includes(n.id))""",
            arg=[GRAPH, [soccer, behaviors]],
        )
        active, faded = active_and_faded(tab)
        assert soccer in active and active - {soccer, behaviors}
        # Fade off: nothing is faded
        tab.click(".graph-panel .fade-toggle input")
        full = """(g) => [...document.querySelectorAll(g + ' g.node')]
            .every((n) => getComputedStyle(n).fillOpacity === '1')"""
        assert tab.evaluate(full, GRAPH)
    finally:
        team.command("release_input", robot=1, symbol="robot.is_fallen")


def test_big_state_machine_labels_are_short_and_conditions_are_tooltips(tab: Any) -> None:
    tab.keyboard.press("/")
    tab.keyboard.type(navset.ROOT)
    tab.keyboard.press("Shift+Enter")
    view = ".option-panel .svg-view"
    tab.wait_for_selector(f"{view} g.edge[id^=leaf_]")
    rows = tab.evaluate(
        f"""() => [...document.querySelectorAll('{view} g.edge[id^=leaf_]')].map((e) => [
            [...e.querySelectorAll('text')].map((t) => t.textContent).join(' '),
            e.querySelector('a')?.getAttribute('xlink:title') ?? e.querySelector('a')?.getAttribute('title') ?? '',
        ])"""
    )
    assert len(rows) > 60
    numbered = 0
    for label, tooltip in rows:
        assert len(label) <= 20, label
        number = re.match(r"(\d+)\. ", label)
        if number:  # a state with several transitions: numbered in decision order, the same in the tooltip
            numbered += 1
            assert tooltip.startswith(number.group(0)), (label, tooltip)
        assert len(tooltip) >= len(label.removesuffix(" …")), (label, tooltip)
    assert numbered > 60
    assert max(len(t) for _, t in rows) > 80, "the long conditions are in the tooltips"
