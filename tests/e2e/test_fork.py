"""Fork in headless chromium: "Run from here" on the timeline, the fork mark, the original's path beside the fork's,
and where a fork of an edited behavior parts from the original."""

from __future__ import annotations

import json
import urllib.request
from typing import Any

from tests.e2e.conftest import StudioServer, screenshot

STUDIO = "window.xabslStudio"


def test_run_from_here_forks_marks_the_timeline_and_shows_the_original_path(page: Any, studio: StudioServer) -> None:
    # Into the playing phase (from 8.5 s of match time), then look back in time.
    assert studio.command("speed", speed=4)["ok"]
    page.wait_for_function(f"() => {STUDIO}.session.live && {STUDIO}.session.live.t > 15000", timeout=60000)
    assert studio.command("pause")["ok"]
    button = page.locator("#run-from-here")
    assert button.is_disabled(), "live: nothing to fork from"
    canvas = page.locator(".timeline-canvas")
    box = canvas.bounding_box()
    canvas.click(position={"x": box["width"] * 0.85, "y": 30})  # about 12.5 s: playing
    page.wait_for_function(f"() => {STUDIO}.session.cursor !== null")
    cursor = page.evaluate(f"() => {STUDIO}.session.view.t")
    assert button.is_enabled()
    button.click()
    # A fork generation arrives: the badge and the timeline's mark say where it comes from.
    page.wait_for_function(f"() => {STUDIO}.session.hello.reason === 'fork'", timeout=60000)
    fork = page.evaluate(f"() => {STUDIO}.session.hello.fork")
    assert fork["t"] == cursor
    badge = page.locator(".fork-badge")
    badge.wait_for(state="visible")
    assert "fork of t =" in badge.inner_text()
    # The fork is a generation of the history: marked where its ticks start, after the original's.
    page.wait_for_function(
        "() => JSON.parse(document.querySelector('.timeline-canvas').dataset.marks || '[]')"
        ".some((m) => m.reason === 'fork')"
    )
    # It runs on live (the button resumes a paused session); then look at a tick of the fork.
    page.wait_for_function(f"() => {STUDIO}.session.live.t > {fork['t'] + 300}", timeout=60000)
    assert studio.command("pause")["ok"]
    start = page.evaluate(f"() => {STUDIO}.session.buffer.bySeq({fork['start']}).x")
    assert start > cursor  # the original run stays on the timeline before the fork
    page.evaluate(f"() => {STUDIO}.session.setCursor({start + 250})")
    original = page.locator(".fork-original")
    original.wait_for(state="visible")
    page.wait_for_function(
        f"() => document.querySelector('.fork-original').dataset.seq === String({STUDIO}.session.view.seq)",
        timeout=30000,
    )
    assert "play_soccer/playing" in page.locator(".fork-original-path").inner_text()
    # Unchanged behavior: the original's option path is the fork's, node for node.
    own = page.evaluate(
        f"""() => {{
          const s = {STUDIO}.session, index = s.indexOf(s.selectedRobot);
          return s.robotInView().path.map((n) => n.kind === 'option'
            ? `${{index.optionById.get(n.option).name}}/${{index.optionById.get(n.option).states[n.state].name}}`
            : index.behaviorById.get(n.behavior).name).join(' › ');
        }}"""
    )
    assert page.locator(".fork-original-path").inner_text() == own
    screenshot(page, "fork")
    # At 1600 px the toolbar with the fork's badge stays one row above the timeline: it wrapped
    # onto the timeline, and a click meant for the timeline opened Recordings… (issue 23).
    bar = page.locator(".timeline-panel > .toolbar").bounding_box()
    row = page.locator(".timeline-panel > .toolbar #run-from-here").bounding_box()
    box = canvas.bounding_box()
    assert bar is not None and row is not None and box is not None
    assert bar["height"] <= row["height"] + 14, (bar, row)  # one row of buttons
    assert bar["y"] + bar["height"] <= box["y"] + 1, (bar, box)
    for fraction in (0.05, 0.5, 0.95):
        x, y = box["x"] + box["width"] * fraction, box["y"] + 4
        hit = page.evaluate(f"() => document.elementFromPoint({x}, {y}).className")
        assert hit == "timeline-canvas", (fraction, hit)
    assert page.evaluate("() => document.querySelector('dialog.recordings')?.open ?? false") is False


def _api(studio: StudioServer, method: str, path: str, body: Any = None, headers: dict[str, str] | None = None) -> Any:
    data = None if body is None else json.dumps(body).encode()
    request = urllib.request.Request(
        studio.url + path, data=data, headers={"Content-Type": "application/json", **(headers or {})}, method=method
    )
    with urllib.request.urlopen(request, timeout=30) as response:
        return json.loads(response.read())


def test_a_fork_of_an_edited_behavior_shows_where_it_parts_from_the_original(page: Any, studio: StudioServer) -> None:
    """The chasers' edit sends them from `chase` to `search` at once: the fork names the tick and the decision."""
    assert studio.command("resume")["ok"]
    page.wait_for_function(f"() => {STUDIO}.session.live && {STUDIO}.session.live.t > 16000", timeout=60000)
    files = _api(studio, "GET", "api/files")["files"]
    path = next(f["path"] for f in files if f["path"].endswith("chase_ball.xabsl"))
    file = _api(studio, "GET", f"api/files/{path}")
    text = file["text"].replace("      else\n        stay;", "      else\n        goto search;", 1)
    assert text != file["text"]
    _api(studio, "PUT", f"api/files/{path}", {"text": text}, {"If-Match": f'"{file["version"]}"'})
    page.wait_for_function(f"() => {STUDIO}.session.hello.reason === 'reload'", timeout=60000)
    assert studio.command("pause")["ok"]
    canvas = page.locator(".timeline-canvas")
    box = canvas.bounding_box()
    canvas.click(position={"x": box["width"] * 0.8, "y": 30})
    page.wait_for_function(f"() => {STUDIO}.session.cursor !== null")
    page.locator("#run-from-here").click()
    page.wait_for_function(f"() => {STUDIO}.session.hello.reason === 'fork'", timeout=60000)
    head = page.locator(".fork-diverge strong")
    page.wait_for_function(
        "() => (document.querySelector('.fork-diverge strong')?.textContent ?? '').startsWith('The fork parts')",
        timeout=60000,
    )
    assert head.inner_text().startswith("The fork parts from the original: red")
    first = page.locator(".fork-diverge-list li").first
    assert "chase_ball: fork chase → search · original chase stays" in first.inner_text()
    marked = page.evaluate("() => JSON.parse(document.querySelector('.timeline-canvas').dataset.divergence || 'null')")
    assert marked is not None and marked["agent"].startswith("red")
    seq = int(first.get_attribute("data-seq"))
    robot = int(first.get_attribute("data-robot"))
    first.locator("button.fork-diverge-go").first.click()
    # the tick, or the last the client holds before it (frames may skip ticks)
    page.wait_for_function(
        f"() => {STUDIO}.session.view.seq <= {seq} && {STUDIO}.session.view.seq > {seq - 4}"
        f" && {STUDIO}.session.selectedRobot === {robot}"
    )
    assert marked["seq"] == seq
    screenshot(page, "fork-diverge")
