"""History across a hot reload in headless chromium: the timeline, the plot and the panels keep it.

The test edits the root option play_soccer so that every state id shifts (its last state, renamed,
moves to the top), saves it in the studio's editor (a hot reload) and checks that the ticks
before the reload stay, read with the ids of their own generation.
"""

from __future__ import annotations

from typing import Any

from tests.e2e.conftest import StudioServer, screenshot

STUDIO = "window.xabslStudio"
PLAY = "behavior/options/play_soccer.xabsl"
FINISHED = """  state finished {
    action {
      game_finished();
    }
  }
"""
HALTED = FINISHED.replace("state finished", "state halted")


def wait_until(page: Any, expression: str, timeout: float = 20000) -> Any:
    return page.wait_for_function(expression, timeout=timeout)


def shown_path(page: Any) -> list[str]:
    """The option rows of the activation panel as ``option/state``."""
    rows = page.locator(".activation-panel .option-row")
    return [
        f"{rows.nth(i).locator('button.link').inner_text()}/{rows.nth(i).locator('span.state').inner_text()}"
        for i in range(rows.count())
    ]


def seek(page: Any, x: int) -> None:
    page.evaluate(f"{STUDIO}.session.setCursor({x})")
    wait_until(page, f"() => {STUDIO}.session.view && {STUDIO}.session.view.x <= {x}")
    page.wait_for_timeout(300)  # the next animation frame draws the panels


def test_the_history_survives_a_hot_reload_and_shows_what_changed(page: Any, studio: StudioServer) -> None:
    original = (studio.example / PLAY).read_text()
    assert original.endswith(FINISHED + "}\n")
    edited = original.replace(FINISHED, "").replace("  initial state init", HALTED + "  initial state init")
    edited = edited.replace("goto finished;", "goto halted;")
    assert edited != original

    # Pin an input to the plot and let the match run for a while.
    page.keyboard.press("s")
    page.keyboard.press("Escape")
    page.locator("button[aria-label='pin ball.distance']").first.click()
    wait_until(page, f"() => {STUDIO}.session.buffer.length > 150", 30000)
    old_gen = page.evaluate(f"{STUDIO}.session.hello.generation")

    # A tick before the reload, and what the activation panel shows for it now.
    tick = page.evaluate(
        f"(() => {{ const all = {STUDIO}.session.buffer.all; const t = all[Math.floor(all.length / 2)];"
        " return { seq: t.seq, x: t.x, t: t.t, gen: t.gen }; })()"
    )
    page.keyboard.press("a")
    seek(page, tick["x"])
    before = shown_path(page)
    assert before and before[0].startswith("play_soccer/"), before
    page.keyboard.press("l")

    # Edit and save the root option in the studio's editor: a hot reload.
    page.keyboard.press("e")
    page.locator(f".file-tree [data-path='{PLAY}']").click()
    wait_until(page, "() => document.querySelector('.editor-host .cm-content').textContent.includes('play_soccer')")
    page.locator(".editor-host .cm-content").click()
    page.keyboard.press("Control+a")
    page.keyboard.insert_text(edited)
    page.keyboard.press("Escape")  # the completion popup would cover the timeline
    page.locator(".editor-status.ok").wait_for(timeout=15000)
    page.keyboard.press("Control+s")
    page.locator(".toast.ok", has_text="hot reloaded").wait_for()
    wait_until(page, f"() => {STUDIO}.session.hello.generation > {old_gen}")
    new_gen = page.evaluate(f"{STUDIO}.session.hello.generation")
    page.wait_for_timeout(1500)
    assert (studio.example / PLAY).read_text() == edited

    # The timeline still holds the ticks before the reload (the tick picked is still there).
    counts = page.evaluate(
        f"(() => {{ const b = {STUDIO}.session.buffer; return {{ old: b.all.filter((t) => t.gen === {old_gen}).length,"
        f" fresh: b.all.filter((t) => t.gen === {new_gen}).length, picked: b.bySeq({tick['seq']}) !== null }}; }})()"
    )
    assert counts["old"] > 100 and counts["fresh"] > 20 and counts["picked"], counts

    # The reload is marked on the timeline's axis; clicking the mark shows the diff. (Paused: the
    # marks stand still on the axis while the test reads where they are and clicks.)
    page.evaluate(f"{STUDIO}.connection.command('pause', {{}})")
    page.wait_for_timeout(500)
    canvas = page.locator(".timeline-canvas")
    wait_until(
        page,
        "() => JSON.parse(document.querySelector('.timeline-canvas').dataset.marks || '[]')"
        f".some((m) => m.gen === {new_gen})",
    )
    marks = page.evaluate("JSON.parse(document.querySelector('.timeline-canvas').dataset.marks)")
    mark = next(m for m in marks if m["gen"] == new_gen)
    assert mark["reason"] == "reload"
    box = canvas.bounding_box()
    assert box is not None
    page.wait_for_timeout(1000)
    page.on("console", lambda m: print("CONSOLE", m.text))
    page.mouse.click(box["x"] + mark["px"], box["y"] + 8)
    section = page.locator(f"dialog.changes[open] section.changed-file[data-path='{PLAY}']")
    section.wait_for(timeout=10000)
    diff = section.locator("pre.diff").inner_text().splitlines()
    assert "+  state halted {" in diff and "-  state finished {" in diff, diff
    assert "-    else if (game.state == finished) goto finished;" in diff
    assert "Hot reload" in page.locator("dialog.changes h2").inner_text()
    screenshot(page, "reload-diff")
    page.locator("dialog.changes button", has_text="Close").click()

    # The plot still has points from before the reload (and after it).
    reload_x = page.evaluate(f"{STUDIO}.session.buffer.all.find((t) => t.gen === {new_gen}).x / 1000")
    points = page.evaluate(f"{STUDIO}.plot.points()")
    assert points["series"], "nothing pinned"
    values = list(zip(points["x"], points["series"][0], strict=True))
    assert sum(1 for x, v in values if x < reload_x and v is not None) > 50
    assert any(x > reload_x and v is not None for x, v in values)

    # Seeking the tick before the reload shows its path as it was, read with the old ids.
    page.keyboard.press("a")
    seek(page, tick["x"])
    assert page.evaluate(f"{STUDIO}.session.shownGeneration.number") == old_gen
    assert shown_path(page) == before
    # (The new description names that tick's state id differently: the old ids were needed.)
    renamed = page.evaluate(
        f"(() => {{ const s = {STUDIO}.session; const node = s.buffer.bySeq({tick['seq']}).robots"
        f".find((r) => r.id === s.selectedRobot).path[0]; const idx = s.indexIn({new_gen}, s.selectedRobot);"
        " return idx.optionById.get(node.option).states[node.state].name; })()"
    )
    assert f"play_soccer/{renamed}" != before[0]
    page.keyboard.press("l")
    wait_until(page, f"() => {STUDIO}.session.cursor === null")
    page.evaluate(f"{STUDIO}.connection.command('resume', {{}})")
    (studio.example / PLAY).write_text(original)
