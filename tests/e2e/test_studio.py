"""The studio used as a person would, in headless chromium against a real ``xabsl serve``.

Watch the match (robots move, the activation path changes, the option graph highlights it),
open an option's state machine, break a file and see the diagnostic while the team keeps playing,
fix it and see the new behavior, force an option with a parameter, scrub the timeline, and
survive a server restart. The tests share one server (module scope) and run in file order; the
restart comes last.
"""

from __future__ import annotations

import re
import time
from typing import Any

from tests.e2e.conftest import StudioServer, screenshot

STUDIO = "window.xabslStudio"


def live_t(page: Any) -> int:
    return int(page.evaluate(f"{STUDIO}.session.live.t"))


def wait_until(page: Any, expression: str, timeout: float = 20000) -> Any:
    return page.wait_for_function(expression, timeout=timeout)


def test_watch_robots_move_and_the_activation_path_changes(page: Any) -> None:
    # The match starts in its initial phase; robots walk once the referee says "ready".
    robots_before = page.evaluate(f"{STUDIO}.session.live.scene.robots")
    shapes: set[str] = set()
    moved = False
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and not (moved and len(shapes) >= 3):
        shapes.update(page.evaluate(f"{STUDIO}.session.live.robots.map(a => a.shape)"))
        moved = page.evaluate(f"{STUDIO}.session.live.scene.robots") != robots_before
        page.wait_for_timeout(250)
    assert moved, "robots did not move"
    assert len(shapes) >= 3, f"activation paths did not change: {shapes}"

    # The team strip names every robot, the option graph highlights the live path.
    assert page.locator(".team-strip .chip").count() == 10
    page.keyboard.press("g")
    wait_until(page, "() => document.querySelectorAll('.graph-panel g.node.active').length >= 3")
    assert page.locator(".graph-panel g.edge.active").count() >= 2
    page.locator(".link-health[data-state='live']").wait_for()

    # Select another robot by clicking it on the field.
    robots = page.evaluate(f"{STUDIO}.session.live.scene.robots")
    box = page.locator(".field-canvas").bounding_box()
    assert box is not None
    target = page.evaluate(
        """([robots, w, h]) => {
            const s = window.xabslStudio.session.scene.field;
            const scale = Math.min(w / (s.length + 2 * s.border), h / (s.width + 2 * s.border)) * 0.98;
            const [x, y] = robots[2];
            return [w / 2 + x * scale, h / 2 - y * scale];
        }""",
        [robots, box["width"], box["height"]],
    )
    page.mouse.click(box["x"] + target[0], box["y"] + target[1])
    wait_until(page, f"() => {STUDIO}.session.selectedRobot === 2")
    # panels redraw on the next animation frame after the session changes
    wait_until(page, "() => document.querySelector(\".chip[data-robot='2']\").classList.contains('selected')")

    page.wait_for_timeout(1500)
    stats = page.evaluate(f"{STUDIO}.stats")
    print(f"UI: {stats['drawsPerSecond']:.1f} draws/s, {stats['renderMs']:.2f} ms per draw (10 agents)")
    screenshot(page, "watch")


def test_click_an_option_and_see_its_state_machine(page: Any) -> None:
    page.keyboard.press("g")
    wait_until(page, "() => document.querySelectorAll('.graph-panel g.node.active').length >= 3")
    # The deepest active option: click it in the graph.
    option_id = page.evaluate(
        f"""() => {{
            const path = {STUDIO}.session.robotInView().path.filter(n => n.kind === 'option');
            return path[path.length - 1].option;
        }}"""
    )
    page.locator(f".graph-panel g#option_{option_id}").click()
    page.locator(".option-panel").wait_for(state="visible")
    wait_until(page, "() => document.querySelectorAll('.option-panel g.node').length >= 1")
    name = page.evaluate(f"{STUDIO}.session.indexOf({STUDIO}.session.selectedRobot).optionById.get({option_id}).name")
    wait_until(page, f"() => document.querySelector('.option-title').innerText === {name!r}")
    # The active state is highlighted (the option may have left the path meanwhile: pick the
    # root option then, which is always active).
    if page.locator(".option-panel g.node.active").count() == 0:
        page.select_option(".option-panel select", "")
    wait_until(page, "() => document.querySelectorAll('.option-panel g.node.active').length === 1")
    wait_until(page, "() => document.querySelector('.why').textContent.includes('Decision of this tick')")
    wait_until(page, "() => document.querySelector('.why').textContent.includes('the decision read in the last tick')")
    screenshot(page, "option")


PUBLISH = "behavior/options/publish_team_data.xabsl"


def replace_editor_text(page: Any, text: str) -> None:
    page.locator(".editor-host .cm-content").click()
    page.keyboard.press("Control+a")
    page.keyboard.insert_text(text)


def test_break_a_file_see_the_diagnostic_fix_it_see_the_new_behavior(page: Any, studio: StudioServer) -> None:
    original = (studio.example / PUBLISH).read_text()
    page.keyboard.press("e")
    page.locator(f".file-tree [data-path='{PUBLISH}']").click()
    wait_until(page, "() => document.querySelector('.editor-host .cm-content').textContent.includes('publish_team')")
    generation = page.evaluate(f"{STUDIO}.session.hello.generation")

    broken = original.replace("strategy.goal_distance = distance(", "strategy.goal_distance = distanse(", 1)
    assert broken != original
    replace_editor_text(page, broken)
    page.locator(".editor-host .cm-lintRange-error").first.wait_for(timeout=15000)
    page.locator(".editor-status.error").wait_for()
    assert "distanse" in page.locator(".editor-status").inner_text()

    # The team keeps playing while the buffer is broken, and also once the broken file is saved.
    t0 = live_t(page)
    page.keyboard.press("Control+s")
    page.locator(".toast.error", has_text="old behavior keeps running").wait_for()
    page.wait_for_timeout(1000)
    assert live_t(page) > t0 + 500
    assert page.evaluate(f"{STUDIO}.session.hello.generation") == generation
    screenshot(page, "editor")

    # Fix it with a new behavior: a constant goal distance, visible in the activation tree.
    fixed = re.sub(r"strategy\.goal_distance = distan[cs]e\([^;]*\);", "strategy.goal_distance = 4242;", broken)
    assert "4242" in fixed
    replace_editor_text(page, fixed)
    page.locator(".editor-status.ok").wait_for(timeout=15000)
    page.keyboard.press("Control+s")
    page.locator(".toast.ok", has_text="hot reloaded").wait_for()
    wait_until(page, f"() => {STUDIO}.session.hello.generation > {generation}")
    page.keyboard.press("a")
    page.locator(".activation-panel .assign", has_text="strategy.goal_distance = 4242").first.wait_for()
    assert (studio.example / PUBLISH).read_text() == fixed


def test_force_an_option_with_a_parameter_and_see_it_at_the_root(page: Any) -> None:
    page.keyboard.press("x")
    page.select_option("#test-target", "option:go_to_position")
    page.fill("#param-x", "1234")
    page.fill("#param-y", "-500")
    page.click("#test-run")
    page.locator(".toast.ok", has_text="go_to_position runs as the root").wait_for()
    page.keyboard.press("a")
    first = page.locator(".activation-panel .option-row").first
    wait_until(
        page,
        "() => { const r = document.querySelector('.activation-panel .option-row'); "
        "return r && r.textContent.includes('go_to_position') && r.textContent.includes('@x=1234'); }",
    )
    assert "go_to_position" in first.inner_text()
    assert page.evaluate(f"{STUDIO}.session.robotInView().forced") is not None
    wait_until(page, "() => document.querySelector('.chip.selected').classList.contains('forced')")
    screenshot(page, "test")
    page.keyboard.press("x")
    page.click("#test-release")
    wait_until(page, f"() => {STUDIO}.session.robotInView() && {STUDIO}.session.robotInView().forced === null")
    page.keyboard.press("a")
    first_row = "document.querySelector('.activation-panel .option-row')"
    wait_until(page, f"() => !{first_row}.textContent.includes('go_to_position')")


CLEAR = "behavior/options/clear_ball.xabsl"


def test_a_conflicting_save_is_shown_never_overwritten_silently(page: Any, studio: StudioServer) -> None:
    original = (studio.example / CLEAR).read_text()
    page.keyboard.press("e")
    page.locator(f".file-tree [data-path='{CLEAR}']").click()
    wait_until(page, "() => document.querySelector('.editor-host .cm-content').textContent.includes('clear_ball')")
    mine = "// my change\n" + original
    replace_editor_text(page, mine)
    # Someone else saves the file meanwhile (another editor on the same folder).
    theirs = "// their change\n" + original
    (studio.example / CLEAR).write_text(theirs)
    page.keyboard.press("Control+s")
    page.locator(".banner", has_text="Conflict").wait_for()
    assert (studio.example / CLEAR).read_text() == theirs
    page.locator(".banner button", has_text="Keep mine").click()
    page.locator(".toast.ok", has_text="Saved behavior/options/clear_ball.xabsl").wait_for()
    assert (studio.example / CLEAR).read_text() == mine
    assert page.locator(".banner").is_hidden()


def test_scrub_the_timeline_and_back_to_live(page: Any) -> None:
    page.wait_for_timeout(1500)
    canvas = page.locator(".timeline-canvas")
    box = canvas.bounding_box()
    assert box is not None
    page.mouse.click(box["x"] + 150 + (box["width"] - 156) * 0.3, box["y"] + 30)
    wait_until(page, f"() => {STUDIO}.session.cursor !== null")
    wait_until(page, "() => document.querySelector('button.live').innerText.trim().endsWith('Back to live')")
    shown = page.evaluate(f"{STUDIO}.session.view.t")
    assert shown < live_t(page) - 300
    page.keyboard.press("a")
    wait_until(page, "() => document.querySelector('.activation-panel .toolbar').innerText.includes('scrubbed')")
    # Arrow keys step through the history; every panel follows.
    canvas.focus()
    page.keyboard.press("ArrowRight")
    wait_until(page, f"() => {STUDIO}.session.view.t > {shown}")
    screenshot(page, "timeline")
    page.keyboard.press("l")
    wait_until(page, f"() => {STUDIO}.session.cursor === null")
    # the button is redrawn on the next animation frame
    wait_until(page, "() => !document.querySelector('button.live').innerText.includes('Back to live')")
    assert "Live" in page.locator("button.live").inner_text()


def test_reconnect_after_a_server_restart(page: Any, studio: StudioServer) -> None:
    seq_before = page.evaluate(f"{STUDIO}.session.live.seq")
    studio.stop()
    page.locator(".link-health[data-state='waiting']").wait_for(timeout=15000)
    assert "offline" in page.locator(".link-health").inner_text()
    studio.start()
    page.locator(".link-health[data-state='live']").wait_for(timeout=30000)
    # A new session: a fresh hello, frames flowing again, panels rebuilt.
    wait_until(page, f"() => {STUDIO}.session.live && {STUDIO}.session.buffer.length > 5", timeout=30000)
    assert page.evaluate(f"{STUDIO}.session.live.seq") != seq_before or live_t(page) > 0
    assert page.locator(".team-strip .chip").count() == 10
    page.keyboard.press("g")
    wait_until(page, "() => document.querySelectorAll('.graph-panel g.node.active').length >= 3")
    # The editor's language server connection comes back too (it closed with the server).
    wait_until(page, f"() => !{STUDIO}.editor.lsp.closed", timeout=30000)
    assert page.evaluate(f"() => {STUDIO}.editor.lsp.ready.then(() => true)")
