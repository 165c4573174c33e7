"""The errands robot in the studio, in headless chromium against a real ``xabsl serve``.

The world announces its panels (Dynamics, Plan, Facts) in its static scene; the plan is visible
with its current operator, the activation plots move, a perturbation button teleports the mug
and the plan panel shows the replan with its reason, and "why" for a fact names its cause. The
tests share one server (module scope) and run in file order.
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from typing import Any

import pytest

from tests.e2e.conftest import REPO, StudioServer, screenshot, serving, studio_tab

STUDIO = "window.xabslStudio"


@pytest.fixture(scope="module")
def errands(tmp_path_factory: pytest.TempPathFactory) -> Iterator[StudioServer]:
    """``xabsl serve`` on a copy of the errands example (its behavior and its studio.py plug-in)."""
    root = tmp_path_factory.mktemp("errands-studio")
    example = root / "errands"
    example.mkdir()
    shutil.copytree(REPO / "examples" / "errands" / "behavior", example / "behavior")
    shutil.copytree(REPO / "examples" / "errands" / "model", example / "model")
    (example / "studio.py").write_text(
        '"""The errands plug-in."""\n\nfrom xabsl_studio.examples.errands.studio import example\n'
    )
    with serving(example, root) as server:
        yield server


@pytest.fixture
def page(browser: Any, errands: StudioServer) -> Iterator[Any]:
    with studio_tab(browser, errands) as tab:
        yield tab


def test_the_plan_is_visible_and_the_activation_plots_move(page: Any) -> None:
    # Only worlds announcing them get these tabs (soccer's e2e tests see none of them).
    for tab in ("dynamics", "plan", "facts"):
        assert page.locator(f".tab[data-tab='{tab}']").is_visible()
    page.keyboard.press("p")
    current = page.locator(".plan-op[data-op='goto a c'][data-state='current']")
    current.wait_for(timeout=20000)
    assert page.locator(".plan-layer").count() == 6
    last = page.locator(".plan-layer[data-layer='6'] .plan-op")
    assert sorted(last.all_inner_texts()) == ["unload book a", "unload mug a"]
    page.locator(".plan-timer", has_text="of 60.0 s timeout").wait_for()
    page.locator(".plan-version[data-version='1']", has_text="start").wait_for()

    page.keyboard.press("d")
    page.locator(".dd-alpha canvas").first.wait_for()
    legend = page.locator(".dd-alpha .u-legend").inner_text()
    assert "roam" in legend and "approach_c" in legend
    page.locator(".dynamics-panel select").first.select_option("approach_c")
    drive = page.locator(".dd-drive-row[data-behavior='approach_c']")
    drive.wait_for()
    first = drive.inner_text()
    page.wait_for_function(
        "(before) => document.querySelector(\".dd-drive-row[data-behavior='approach_c']\").innerText !== before",
        arg=first,
        timeout=10000,
    )
    assert "plan bias" in first and "self-excitation" in first
    # The α of approach_c rises under GOTO(a, c): the plotted data moves.
    page.wait_for_function(
        f"""() => {{
            const b = {STUDIO}.session.scene.dd.behaviors.indexOf('approach_c');
            const ticks = {STUDIO}.session.buffer.all.filter(t => t.scene && t.scene.alpha);
            return ticks.length > 10 && Math.max(...ticks.map(t => t.scene.alpha[b])) > 0.6;
        }}"""
    )
    assert page.locator(".dd-fusion-row[data-actuator='m_l'] .dd-share").count() >= 1
    # Clicking a plot goes to that moment, like the timeline.
    box = page.locator(".dd-alpha .u-over").bounding_box()
    assert box is not None
    page.mouse.click(box["x"] + box["width"] * 0.5, box["y"] + box["height"] * 0.5)
    page.wait_for_function(f"() => {STUDIO}.session.cursor !== null")
    page.keyboard.press("End")
    page.wait_for_function(f"() => {STUDIO}.session.cursor === null")


def test_a_perturbation_button_leads_to_a_replan_the_plan_panel_shows(page: Any, errands: StudioServer) -> None:
    page.keyboard.press("p")
    page.locator(".plan-op[data-state='current']").first.wait_for(timeout=20000)
    teleport = page.locator(".world-command[data-command='teleport']")
    assert teleport.locator("select").nth(0).input_value() == "mug"
    assert teleport.locator("select").nth(1).input_value() == "b"
    teleport.locator("button").click()
    page.locator(".toast", has_text="teleported the mug to b").wait_for(timeout=10000)
    assert errands.command("speed", speed=10)["ok"]
    try:
        replan = page.locator(".plan-version[data-version='2']")
        replan.wait_for(timeout=90000)
        assert "precondition_lost" in replan.inner_text()
        # The new version is in force; the old one shows its failed operator.
        page.locator(".plan-head", has_text="version 2").wait_for()
        page.locator(".plan-intervention", has_text="by hand: teleported the mug to b").wait_for()
        screenshot(page, "errands-plan")
        page.locator(".plan-version[data-version='1'] button.link").first.click()
        failed = page.locator(".plan-op.failed[data-op='load mug c']")
        failed.wait_for()
        assert "precondition_lost" in failed.inner_text()
    finally:
        errands.command("speed", speed=1)


def test_why_for_a_fact_names_its_cause(page: Any) -> None:
    page.keyboard.press("f")
    page.locator(".facts-canvas").wait_for()
    event = page.locator(".fact-event[data-fact='at mug c'][data-phase='cleared']")
    event.first.wait_for(timeout=20000)
    event.first.locator("button").click()
    why = page.locator(".fact-why-text").inner_text()
    assert why.startswith("−at mug c: cleared") and "by rule" in why and "held 12" in why, why
    page.wait_for_function(f"() => {STUDIO}.session.cursor !== null")
    screenshot(page, "errands-facts")
    page.keyboard.press("d")
    page.locator(".dd-alpha canvas").first.wait_for()
    page.keyboard.press("End")
    page.wait_for_timeout(1500)
    screenshot(page, "errands-dynamics")


def test_the_model_editor_shows_the_loaders_error_at_its_line_and_column(page: Any, errands: StudioServer) -> None:
    page.keyboard.press("d")
    page.locator(".model-editor summary").click()
    text = page.locator(".model-text")
    page.wait_for_function("() => document.querySelector('.model-text').value.includes('xabsl-dd-model/1')")
    original = text.input_value()
    text.fill(original.replace('"drive": "1 - 1.2*max(', '"drive": "1 - zork*max(', 1))
    diagnostic = page.locator(".model-diagnostic")
    diagnostic.wait_for(timeout=10000)
    assert "behaviors.roam.drive: unknown name 'zork'" in diagnostic.inner_text()
    assert diagnostic.inner_text().startswith("model/errands_dd.json:")
    diagnostic.locator("button").click()
    selected = page.evaluate(
        "() => { const t = document.querySelector('.model-text');"
        " return t.value.slice(t.selectionStart, t.selectionStart + 4); }"
    )
    assert selected == "zork"
    text.fill(original.replace('"c_oct": 10.0', '"c_oct": 9.5'))
    page.wait_for_function("() => !document.querySelector('.model-diagnostic')")
    page.locator(".model-editor button[data-run='model_save']").click()
    page.locator(".toast", has_text="Model saved and hot-reloaded").wait_for(timeout=10000)
    assert '"c_oct": 9.5' in (errands.example / "model" / "errands_dd.json").read_text()
