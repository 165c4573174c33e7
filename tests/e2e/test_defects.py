"""Defects a new user met in the studio (issue 13), each reproduced in headless chromium.

Every test here failed before its fix. They share one server (module scope, see conftest.py)
and leave it as they found it: running, at 1x, nothing forced or overridden.
"""

from __future__ import annotations

import json
import re
import time
import urllib.request
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from tests.e2e.conftest import StudioServer, screenshot

STUDIO = "window.xabslStudio"


def wait_until(page: Any, expression: str, timeout: float = 20000) -> Any:
    return page.wait_for_function(expression, timeout=timeout)


def api_status(studio: StudioServer) -> dict[str, Any]:
    with urllib.request.urlopen(studio.url + "api/status", timeout=10) as response:
        status: dict[str, Any] = json.loads(response.read())
    return status


def eventually(check: Callable[[], bool], seconds: float = 10.0) -> bool:
    """Whether ``check()`` becomes true within ``seconds`` (asked every 100 ms)."""
    deadline = time.monotonic() + seconds
    while not check():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.1)
    return True


@pytest.fixture
def running(studio: StudioServer) -> Iterator[None]:
    """Leave the match running at 1x whatever the test did."""
    yield
    studio.command("resume")
    studio.command("speed", speed=1)


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
    assert eventually(lambda: api_status(studio)["speed"] == 20)
    # A tab switch redraws the top bar: it keeps showing the speed chosen (not the hello's).
    page.keyboard.press("x")
    page.keyboard.press("a")
    page.wait_for_timeout(200)
    assert page.eval_on_selector("#speed", "s => s.value") == "20"
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
        page.evaluate(f"{STUDIO}.session.indexOf({STUDIO}.session.selectedRobot).optionByName.get({option!r}).id")
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
    assert page.evaluate(f"{STUDIO}.session.robotInView().forced") is None
    page.fill("#param-rate", "")
    page.click("#test-run")
    wait_until(page, "() => document.querySelector('.tester-panel .param-error').innerText.includes('number')")
    page.wait_for_timeout(300)
    assert page.evaluate(f"{STUDIO}.session.robotInView().forced") is None
    # A good value clears the message and runs.
    page.fill("#param-rate", "20")
    page.click("#test-run")
    page.locator(".toast.ok", has_text="turn runs as the root").wait_for()
    assert page.locator(".tester-panel .param-error:visible").count() == 0
    page.click("#test-release")
    wait_until(page, f"() => {STUDIO}.session.robotInView().forced === null")


def test_an_override_is_released_with_one_click_and_its_row_fits(page: Any) -> None:
    page.keyboard.press("s")
    page.keyboard.press("Escape")
    name = "ball.distance"  # declared 0..11000 mm
    row = page.locator(f".symbol-row[data-kind='input'][data-symbol='{name}']")
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
    # An empty or out-of-range value is said, not sent (an empty field used to override with 0).
    for text, message in (("", "a number is required"), ("-5", "outside the declared range 0..11000")):
        editor.locator("input").fill(text)
        editor.locator("button", has_text="Override").click()
        editor.locator(".param-error", has_text=message).wait_for()
        page.wait_for_timeout(300)
        assert page.locator(f".symbol-row.overridden[data-symbol='{name}']").count() == 0
    editor.locator("input").fill("1234")
    editor.locator("button", has_text="Override").click()
    overridden = page.locator(f".symbol-row.overridden[data-symbol='{name}']")
    overridden.wait_for()
    # One click releases it.
    overridden.locator("button.release").click()
    row_of = f"document.querySelector(\".symbol-row[data-symbol='{name}']\")"
    wait_until(page, f"() => !{row_of}.classList.contains('overridden')")
    assert page.evaluate(f"Object.keys({STUDIO}.session.robotInView().overrides ?? {{}}).length") == 0


# -- layout at common sizes (issue 13, deliverable 5) ------------------------------------------------


@pytest.fixture
def desktop(page: Any) -> Iterator[None]:
    """Restore the 1600x1000 window after a test that resizes it."""
    yield
    page.set_viewport_size({"width": 1600, "height": 1000})


def box_of(page: Any, selector: str) -> dict[str, float]:
    box = page.locator(selector).first.bounding_box()
    assert box is not None, f"{selector} is not shown"
    return dict(box)


def inside(inner: dict[str, float], outer: dict[str, float], slack: float = 1.0) -> bool:
    return (
        inner["x"] >= outer["x"] - slack
        and inner["y"] >= outer["y"] - slack
        and inner["x"] + inner["width"] <= outer["x"] + outer["width"] + slack
        and inner["y"] + inner["height"] <= outer["y"] + outer["height"] + slack
    )


def test_the_option_graph_refits_when_the_window_is_resized(page: Any, desktop: None) -> None:
    page.keyboard.press("g")
    wait_until(page, "() => document.querySelectorAll('.graph-panel g.node').length >= 10")
    # As opened (fitted, or zoomed to a readable size around the active option when the whole
    # graph is too small to read): a resize places it the same way again.
    page.set_viewport_size({"width": 1100, "height": 760})
    page.wait_for_timeout(400)
    view = box_of(page, ".graph-panel .svg-view")
    graph = box_of(page, ".graph-panel .svg-view svg")
    shown = [b for b in (n.bounding_box() for n in page.locator(".graph-panel g.node.active").all()) if b]
    assert inside(graph, view) or any(inside(b, view) for b in shown), f"nothing active in view {view}: {shown}"
    page.set_viewport_size({"width": 1600, "height": 1000})
    page.locator(".graph-panel button", has_text="Fit").click()
    page.wait_for_timeout(200)
    view = box_of(page, ".graph-panel .svg-view")
    graph = box_of(page, ".graph-panel .svg-view svg")
    assert inside(graph, view), (graph, view)
    for width, height in ((1100, 760), (1600, 1000)):
        page.set_viewport_size({"width": width, "height": height})
        page.wait_for_timeout(400)
        view = box_of(page, ".graph-panel .svg-view")
        graph = box_of(page, ".graph-panel .svg-view svg")
        assert inside(graph, view), f"at {width}x{height} the graph {graph} leaves the view {view}"
        fill = max(graph["width"] / view["width"], graph["height"] / view["height"])
        assert fill > 0.85, f"at {width}x{height} the graph fills only {fill:.0%} of the view"


def test_at_1280x720_the_team_strip_shows_every_robot(page: Any, desktop: None) -> None:
    page.set_viewport_size({"width": 1280, "height": 720})
    page.wait_for_timeout(400)
    strip = box_of(page, ".team-strip")
    chips = page.locator(".team-strip .chip")
    assert chips.count() == 10
    previous_bottom = 0.0
    for i in range(10):
        chip = chips.nth(i).bounding_box()
        assert chip is not None and inside(chip, strip), f"robot {i + 1} is cut off: {chip} outside {strip}"
        assert chip["height"] >= 18 and chip["y"] >= previous_bottom - 0.5, f"robot {i + 1} is squeezed: {chip}"
        previous_bottom = chip["y"] + chip["height"]
    screenshot(page, "layout-1280x720")
    field = box_of(page, ".field-canvas")
    assert field["height"] >= 150, f"the field shrank to {field['height']} px"


def test_at_1024x700_no_tab_or_button_is_clipped(page: Any, desktop: None) -> None:
    page.set_viewport_size({"width": 1024, "height": 700})
    page.wait_for_timeout(400)
    window = {"x": 0, "y": 0, "width": 1024, "height": 700}
    screenshot(page, "layout-1024x700")
    for bar in page.locator(".tabbar").all():
        bar_box = bar.bounding_box()
        assert bar_box is not None
        for tab in bar.locator(".tab:visible").all():  # a world shows only the panels it has
            box = tab.bounding_box()
            assert box is not None and inside(box, bar_box) and inside(box, window), f"{tab.inner_text()!r} clipped"
            assert tab.evaluate("t => t.scrollWidth <= t.clientWidth + 1"), f"{tab.inner_text()!r} text cut"
    # (the attach bar's controls are hidden outside `xabsl attach`: what is not shown is not clipped)
    for button in page.locator(".topbar button:visible, .topbar select:visible").all():
        box = button.bounding_box()
        assert box is not None and inside(box, window), f"top bar control {box} is off screen"


def test_activation_tree_lines_are_never_cut(page: Any, desktop: None) -> None:
    page.set_viewport_size({"width": 1280, "height": 720})
    page.keyboard.press("a")
    wait_until(page, "() => document.querySelectorAll('.activation-panel .row').length >= 3")
    page.wait_for_timeout(300)
    cut = page.evaluate(
        """() => {
            const tree = document.querySelector('.activation-panel .tree');
            const right = tree.getBoundingClientRect().right;
            const out = [];
            for (const el of tree.querySelectorAll('.row > *, .assign > *')) {
                const r = el.getBoundingClientRect();
                if (r.width && r.right > right + 1) out.push(el.textContent);
            }
            return out;
        }"""
    )
    assert not cut, f"cut at the right edge: {cut[:5]}"


def boxes_overlap(a: dict[str, float], b: dict[str, float]) -> bool:
    return (
        a["x"] < b["x"] + b["w"] and b["x"] < a["x"] + a["w"] and a["y"] < b["y"] + b["h"] and b["y"] < a["y"] + a["h"]
    )


def test_robot_labels_on_the_field_do_not_overlap(page: Any, studio: StudioServer) -> None:
    # Crowd three robots of the home team on one spot: their labels ("forced", roles) meet.
    agents = page.evaluate(f"{STUDIO}.session.robots.slice(0, 3).map(a => a.id)")
    for agent in agents:
        studio.command("force_option", robot=agent, option="go_to_position", params={"x": -1500, "y": 0, "rot": 0})
    overlaps: list[Any] = []
    closest = float("inf")
    try:
        for _ in range(60):
            boxes, robots = page.evaluate(f"[{STUDIO}.field.labelBoxes, {STUDIO}.session.live.scene.robots]")
            crowd = robots[: len(agents)]
            closest = min(
                [closest]
                + [max(abs(p[0] - q[0]), abs(p[1] - q[1])) for i, p in enumerate(crowd) for q in crowd[i + 1 :]]
            )
            overlaps.extend((a, b) for i, a in enumerate(boxes) for b in boxes[i + 1 :] if boxes_overlap(a, b))
            page.wait_for_timeout(200)
    finally:
        for agent in agents:
            studio.command("release", robot=agent)
    assert closest < 500, f"the robots did not crowd (closest {closest} mm): the test proves nothing"
    assert not overlaps, f"{len(overlaps)} overlapping labels, e.g. {overlaps[0]}"


# -- a readable state-machine view (issue 13, deliverable 4) -------------------------------------------

STATES = [
    "wait_for_ball", "approach_slowly", "approach_fast", "turn_to_goal", "align_left", "align_right",
    "dribble_forward", "prepare_kick", "kick_hard", "recover", "search_left", "search_right",
]  # fmt: skip


def many_states_option() -> str:
    """A 12-state option whose transitions share a long first condition (their old labels were
    all cut to the same prefix); each state moves on after 300 ms, so transitions fire."""
    lines = ["/** Twelve states in a ring, for the option view's legibility. */", "option many_states {"]
    for i, name in enumerate(STATES):
        nxt = STATES[(i + 1) % len(STATES)]
        far = STATES[(i + 5) % len(STATES)]
        lines += [
            f"  {'initial ' if i == 0 else ''}state {name} {{",
            "    decision {",
            "      if (ball.time_since_seen > 99999999 && ball.distance > 10999 && robot.x > 99999)",
            f"        goto {far};",
            f"      else if (state_time > 300 && ball.distance >= 0 && abs(value = ball.angle) <= 180 + {i})",
            f"        goto {nxt};",
            "      else",
            "        stay;",
            "    }",
            "    action {",
            "    }",
            "  }",
        ]
    lines.append("}")
    return "\n".join(lines) + "\n"


def state_name_sizes(page: Any) -> list[float]:
    """The on-screen font size (px) of every state name in the option view."""
    sizes: list[float] = page.evaluate(
        """() => [...document.querySelectorAll('.option-panel g.node[id^="state_"] text')].map(t => {
            const svg = t.ownerSVGElement;
            const scale = svg.getBoundingClientRect().width / svg.width.baseVal.value;
            return parseFloat(getComputedStyle(t).fontSize) * scale;
        })"""
    )
    return sizes


def zoom_of(page: Any) -> float:
    transform = page.evaluate("() => document.querySelector('.option-panel .svg-stage').style.transform")
    return float(transform.split("scale(")[1].rstrip(")"))


def test_a_twelve_state_option_is_legible_at_fit(page: Any, studio: StudioServer) -> None:
    agents_file = studio.example / "behavior" / "agents.xabsl"
    (studio.example / "behavior" / "options" / "many_states.xabsl").write_text(many_states_option())
    original = agents_file.read_text()
    if "many_states" not in original:
        anchor = original.index("include ")
        agents_file.write_text(original[:anchor] + 'include "options/many_states.xabsl";\n' + original[anchor:])
    generation = page.evaluate(f"{STUDIO}.session.hello.generation")
    assert studio.command("reload")["ok"]
    wait_until(page, f"() => {STUDIO}.session.hello.generation > {generation}")
    agent = page.evaluate(f"{STUDIO}.session.selectedRobot")
    studio.command("force_option", robot=agent, option="many_states", params={})
    try:
        open_option_view(page, "many_states")
        wait_until(page, "() => document.querySelectorAll('.option-panel g.node[id^=\"state_\"]').length === 12")
        page.locator(".option-panel button", has_text="Fit").click()
        page.wait_for_timeout(300)
        sizes = state_name_sizes(page)
        assert len(sizes) >= 12 and min(sizes) >= 11, f"state names at Fit: {min(sizes):.1f} px"
        # The active state and the last transition are marked.
        wait_until(page, "() => document.querySelectorAll('.option-panel g.node.active').length === 1")
        wait_until(page, "() => document.querySelectorAll('.option-panel g.edge.fired').length === 1")
        screenshot(page, "option-12-states")
        # At Fit the view follows the active state (the ring moves on every 300 ms); one
        # evaluate, since the active state may move between two.
        for _ in range(3):
            page.wait_for_timeout(700)
            seen = page.evaluate(
                """() => {
                    const view = document.querySelector('.option-panel .svg-view').getBoundingClientRect();
                    const nodes = [...document.querySelectorAll('.option-panel g.node.active')];
                    const stage = document.querySelector('.option-panel .svg-stage').style.transform;
                    const active = nodes.map(n => [n.id, n.getBoundingClientRect().toJSON()]);
                    return {view: view.toJSON(), stage, active};
                }"""
            )
            assert len(seen["active"]) == 1, seen
            box = seen["active"][0][1]
            view = seen["view"]
            assert view["left"] - 2 <= box["left"] and box["right"] <= view["right"] + 2, (
                f"active state out of view: {seen}"
            )
        # ... also at a moment of the history (found in the buffered ticks).
        page.evaluate(f"{STUDIO}.session.setCursor({STUDIO}.session.live.t - 200)")
        wait_until(page, "() => document.querySelectorAll('.option-panel g.edge.fired').length === 1")
        wait_until(page, "() => document.querySelectorAll('.option-panel .transitions li.fired').length === 1")
        page.evaluate(f"{STUDIO}.session.setCursor(null)")
        # Every condition is there in full: on the edge (hover) and in the transition list.
        conditions = page.evaluate(
            """() => [...document.querySelectorAll('.option-panel .transitions li code')].map(c => c.textContent)"""
        )
        assert len(conditions) == 24, conditions
        assert all("…" not in c for c in conditions)
        assert any("abs(value = ball.angle) <= 180 + 11" in c for c in conditions)
        titles = page.evaluate(
            """() => [...document.querySelectorAll('.option-panel g.edge[id^="leaf_"]')].map(e =>
                [...e.querySelectorAll('title, a')]
                    .map(x => x.getAttribute('xlink:title') || x.textContent).join(' '))"""
        )
        assert len(titles) == 24 and all("state_time > 300" in t or "99999999" in t for t in titles), titles
        labels = page.evaluate(
            """() => [...document.querySelectorAll('.option-panel g.edge[id^="leaf_"] text')].map(t => t.textContent)"""
        )
        # A long condition is cut on the edge, so each label leads with its transition's number in
        # decision order (the tooltip and the list carry the whole condition under that number).
        shown = [label for label in labels if label]
        assert len(shown) == 24 and all(re.match(r"^[12]\. \S", label) for label in shown), shown
        assert {label[:2] for label in shown} == {"1.", "2."}
        # The zoom is reset per option: zoom in here, open another option, it is at Fit.
        page.locator(".option-panel button", has_text="Fit").click()
        fit = zoom_of(page)
        page.locator(".option-panel .svg-view").hover()
        page.mouse.wheel(0, -600)
        page.wait_for_timeout(200)
        assert zoom_of(page) != fit
        open_option_view(page, "striker")
        page.wait_for_timeout(500)
        open_option_view(page, "many_states")
        page.wait_for_timeout(500)
        assert zoom_of(page) == fit
    finally:
        studio.command("release", robot=agent)
