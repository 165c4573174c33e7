"""A team's own behavior in the studio (the bench world), in headless chromium against ``xabsl serve DIR``.

A behavior folder with a mistake opens with the problem banner and the option graph of what
parsed; a click on the error opens it in the editor, fixing it there starts the robots; the agent
picker switches XABSL agents; a hand-set input and an input function's hand-set value drive a
forced option. The tests share one server (module scope) and run in file order.
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from typing import Any

import pytest

from tests.e2e.conftest import REPO, StudioServer, screenshot, serving, studio_tab

STUDIO = "window.xabslStudio"
BROKEN = "options/approach_ball.xabsl"

#: robot 0's activation path as "option:state" and "behavior(params)" texts
PATH = f"""() => {{
  const s = {STUDIO}.session, index = s.indexOf(0), robot = s.live && s.live.robots[0];
  if (!index || !robot) return [];
  return robot.path.map((n) => n.kind === 'option'
    ? `${{index.optionById.get(n.option).name}}:${{index.optionById.get(n.option).states[n.state].name}}`
    : `${{index.behaviorById.get(n.behavior).name}}(${{n.params.join(',')}})`);
}}"""


@pytest.fixture(scope="module")
def own(tmp_path_factory: pytest.TempPathFactory) -> Iterator[StudioServer]:
    """``xabsl serve`` on a behavior folder of our own (a copy of the demo) with a syntax error."""
    root = tmp_path_factory.mktemp("own-behavior")
    folder = root / "team"
    shutil.copytree(REPO / "examples" / "demo", folder)
    file = folder / BROKEN
    file.write_text(file.read_text().replace("goto kicked;", "goto kicked", 1))
    with serving(folder, root) as server:
        yield server


@pytest.fixture
def page(browser: Any, own: StudioServer) -> Iterator[Any]:
    with studio_tab(browser, own) as tab:
        yield tab


def wait_until(page: Any, expression: str, timeout: float = 20000) -> Any:
    return page.wait_for_function(expression, timeout=timeout)


def test_a_behavior_with_a_mistake_opens_with_the_banner_and_the_graph_and_starts_once_fixed(
    page: Any, own: StudioServer
) -> None:
    banner = page.locator(".problems")
    banner.wait_for()
    assert "has 1 error" in banner.inner_text() and "robots stand" in banner.inner_text()
    # the option graph of what parsed, the broken option dashed
    page.keyboard.press("g")
    wait_until(page, "() => document.querySelector('.graph-panel svg #missing_approach_ball')")
    assert page.locator(".graph-panel svg #option_0").count() == 1
    assert page.locator("#robot-picker").inner_text().count("(stands: errors)") == 2
    page.keyboard.press("s")
    page.locator(".symbols-panel [data-symbol='ball.distance']").wait_for()
    screenshot(page, "own-behavior-broken")

    # click the error: the editor opens the file at its line; fix it there and save
    page.locator(".problems .problem-item").first.click()
    wait_until(page, "() => document.querySelector('.editor-host .cm-content')?.textContent.includes('approach_ball')")
    generation = page.evaluate(f"{STUDIO}.session.hello.generation")
    text = (own.example / BROKEN).read_text()
    page.locator(".editor-host .cm-content").click()
    page.keyboard.press("Control+a")
    page.keyboard.insert_text(text.replace("goto kicked\n", "goto kicked;\n", 1))
    page.locator(".editor-status.ok").wait_for(timeout=15000)
    page.keyboard.press("Control+s")
    wait_until(page, f"() => {STUDIO}.session.hello.generation > {generation}")
    wait_until(page, f"() => {STUDIO}.session.robots.every((r) => r.engine)")
    wait_until(page, f"() => ({PATH})().length > 0")
    banner.wait_for(state="hidden")
    assert "goto kicked;" in (own.example / BROKEN).read_text()
    page.evaluate("document.activeElement.blur()")  # letters are the studio's again, not the editor's
    page.keyboard.press("g")
    wait_until(page, "() => document.querySelector('.graph-panel svg #option_2')")
    assert page.locator(".graph-panel svg [id^='missing_']").count() == 0


def test_the_agent_picker_switches_the_robots_agent(page: Any) -> None:
    wait_until(page, f"() => ({PATH})()[0]?.startsWith('play:')")
    assert page.locator("#agent-picker").input_value() == "chaser"
    page.select_option("#agent-picker", "searcher")
    wait_until(page, f"() => ({PATH})()[0]?.startsWith('search_ball:')")
    wait_until(page, "() => document.querySelector('#agent-picker').value === 'searcher'")
    other = page.evaluate(f"() => {STUDIO}.session.live.robots[1].path[0].option")
    page.select_option("#agent-picker", "chaser")
    wait_until(page, f"() => ({PATH})()[0]?.startsWith('play:')")
    assert page.evaluate(f"() => {STUDIO}.session.live.robots[1].path[0].option") == other, "one robot only"


def set_by_hand(page: Any, symbol: str, value: str) -> None:
    row = page.locator(f".symbols-panel [data-symbol='{symbol}']")
    row.get_by_role("button", name=f"set {symbol}").click()
    control = row.locator(".override-editor input, .override-editor select").first
    control.fill(value)
    control.press("Enter")
    page.locator(".toast.ok", has_text=f"{symbol} set on robot1").first.wait_for()


def test_a_hand_set_input_and_an_input_function_value_drive_a_forced_option(page: Any, own: StudioServer) -> None:
    assert own.command("force_option", robot=0, option="approach_ball", params={"stop_at": 100})["ok"]
    wait_until(page, f"() => ({PATH})()[0] === 'approach_ball:go'")
    # the graph shows the forced root, the agent picker says so
    page.keyboard.press("g")
    page.locator(".graph-root", has_text="forced root: approach_ball").wait_for()
    wait_until(page, "() => document.querySelector('#agent-picker').value === 'forced: approach_ball'")
    page.keyboard.press("s")
    clamp = page.locator(".symbols-panel [data-symbol='clamp']")
    clamp.wait_for()
    # walk(speed = clamp(...)): the demo declares clamp(value, lo, hi), so the bench computes it;
    # the row says so, and the call's result is the clamped argument
    clamp.locator(".by-hand", has_text="computed: clamp(value, lo, hi)").wait_for()
    wait_until(
        page,
        "() => { const m = /clamp\\(([\\d.]+), 50, 250\\) = ([\\d.]+)/"
        ".exec(document.querySelector(\"[data-symbol='clamp'] .calls\").textContent);"
        " return m && Math.abs(Number(m[2]) - Math.max(50, Math.min(250, Number(m[1])))) < 0.01; }",
    )
    set_by_hand(page, "clamp", "120")
    wait_until(page, f"() => ({PATH})().some((n) => n.startsWith('walk(120,'))")
    wait_until(
        page, "() => document.querySelector(\".symbols-panel [data-symbol='clamp']\").innerText.includes('by hand')"
    )
    # released, it is computed again
    clamp.get_by_role("button", name="release clamp").click()
    page.locator(".toast.ok", has_text="clamp is computed again").first.wait_for()
    clamp.locator(".by-hand", has_text="computed: clamp(value, lo, hi)").wait_for()
    wait_until(page, f"() => !({PATH})().some((n) => n.startsWith('walk(120,'))")
    set_by_hand(page, "clamp", "120")
    # ball.distance and ball.angle by hand: close and in front, so approach_ball goes to kick
    set_by_hand(page, "ball.angle", "0")
    set_by_hand(page, "ball.distance", "10")
    wait_until(page, f"() => ({PATH})()[0] === 'approach_ball:kick'")
    # the panel redraws on its next frame: wait for it rather than read the DOM at once
    wait_until(
        page,
        "() => document.querySelector(\".symbols-panel [data-symbol='ball.distance']\").innerText.includes('by hand')",
    )
    screenshot(page, "own-behavior-forced")
    # the values stay: a second later they still hold and the robot kicked again (state cycle)
    page.wait_for_timeout(1000)
    value = page.evaluate(
        f"() => {{ const s = {STUDIO}.session;"
        " const id = s.indexOf(0).description.inputs.find((i) => i.name === 'ball.distance').id;"
        " return s.live.robots[0].inputs[id]; }"
    )
    assert value == 10
