"""What a new user tripped on in a debugger that must be trusted (issue 23), in headless chromium.

Every test here failed before its fix. They share one server (module scope, see conftest.py).
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.e2e.conftest import REPO, StudioServer, screenshot, serving, studio_tab


def wait_until(page: Any, expression: str, timeout: float = 20000) -> Any:
    return page.wait_for_function(expression, timeout=timeout)


def open_file(page: Any, path: str, needle: str) -> None:
    page.keyboard.press("e")
    page.locator(f".file-tree [data-path='{path}']").click()
    wait_until(page, f"() => document.querySelector('.editor-host .cm-content').textContent.includes({needle!r})")


def cli_count(folder: Path, agents: str) -> tuple[int, int]:
    """(errors, warnings) that ``xabsl compile`` prints for ``agents`` (relative to ``folder``)."""
    done = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "compile", agents],
        cwd=folder,
        capture_output=True,
        text=True,
        env={"PYTHONPATH": str(REPO), "PATH": "/usr/bin:/bin"},
    )
    summary = done.stdout.strip().splitlines()[-1]
    found = re.search(r"(\d+) errors?, (\d+) warnings?", summary)
    assert found, summary
    return int(found.group(1)), int(found.group(2))


def status_warnings(page: Any) -> int:
    text = str(page.locator(".editor-status").inner_text())
    found = re.search(r"(\d+) warnings?", text)
    return int(found.group(1)) if found else 0


def test_the_editor_counts_the_diagnostics_the_cli_prints(page: Any, studio: StudioServer) -> None:
    """The chase set reads the team's symbol files: their warnings are chase's too (CLI: 16)."""
    errors, warnings = cli_count(studio.example, "chase/agents.xabsl")
    assert (errors, warnings) == (0, 16)
    open_file(page, "chase/chase_ball.xabsl", "chase_ball")
    wait_until(page, "() => /warning/.test(document.querySelector('.editor-status').innerText)")
    page.wait_for_timeout(1500)  # every file's diagnostics have arrived
    assert status_warnings(page) == warnings
    # the team's own set has none, and its editor says so whatever chase found in shared files
    open_file(page, "behavior/options/face_ball.xabsl", "face_ball")
    page.wait_for_timeout(1500)
    assert cli_count(studio.example, "behavior/agents.xabsl") == (0, 0)
    assert status_warnings(page) == 0


TEAM = {
    "skills.xabsl": 'namespace skills("S") {\n  behavior walk {\n    float speed;\n    float turn;\n  }\n}\n',
    "symbols.xabsl": (
        'namespace symbols("Symbols") {\n  float input ball.x;\n  float input ball.y;\n  float input spare;\n'
        "  float output kick_power;\n}\n"
    ),
    "chase.xabsl": (
        "option chase {\n  initial state go {\n    decision {\n      if (ball.x > 100)\n        goto near;\n"
        "      else\n        stay;\n    }\n    action {\n      walk(speed = ball.x);\n    }\n  }\n"
        "  state near {\n    decision {\n      stay;\n    }\n    action {\n      kick_power = 1;\n    }\n  }\n}\n"
    ),
    "play.xabsl": (
        "option play {\n  initial state run {\n    decision {\n      stay;\n    }\n    action {\n      chase();\n"
        "    }\n  }\n  state lost {\n    decision {\n      stay;\n    }\n    action {\n    }\n  }\n}\n"
    ),
    # the team's agents file, which the studio serves, and beside it a test agent for one option
    "team.xabsl": (
        'include "skills.xabsl";\ninclude "symbols.xabsl";\ninclude "chase.xabsl";\ninclude "play.xabsl";\n'
        'agent team("Team", play);\n'
    ),
    "agents.xabsl": (
        'include "skills.xabsl";\ninclude "symbols.xabsl";\ninclude "chase.xabsl";\nagent test("Test", chase);\n'
    ),
}


@pytest.fixture(scope="module")
def team_studio(tmp_path_factory: pytest.TempPathFactory) -> Iterator[StudioServer]:
    root = tmp_path_factory.mktemp("team")
    folder = root / "team"
    folder.mkdir()
    for name, text in TEAM.items():
        (folder / name).write_text(text)
    with serving(folder / "team.xabsl", root) as server:
        yield server


def test_the_studio_counts_what_the_cli_counts_for_the_set_it_serves(browser: Any, team_studio: StudioServer) -> None:
    """The studio said 116 where `xabsl compile` said 137: it counted another agents file's set."""
    folder = team_studio.example.parent
    errors, warnings = cli_count(folder, "team.xabsl")
    assert errors == 0 and warnings >= 4
    with studio_tab(browser, team_studio, live=False) as page:
        page.wait_for_function(f"() => {STUDIO} && {STUDIO}.session.hello", timeout=30000)
        open_file(page, "chase.xabsl", "option chase")
        wait_until(page, "() => /warning/.test(document.querySelector('.editor-status').innerText)")
        page.wait_for_timeout(1500)
        assert status_warnings(page) == warnings, page.locator(".editor-status").inner_text()


STUDIO = "window.xabslStudio"


def open_option(page: Any, name: str) -> None:
    page.evaluate(
        f"""() => {{
        const s = {STUDIO}.session;
        const index = s.indexOf(s.selectedRobot);
        s.openOptionById(index.optionByName.get({json.dumps(name)}).id);
    }}"""
    )
    page.keyboard.press("o")
    page.wait_for_selector(".option-panel svg g[id^='state_']", timeout=20000)


def clear_breakpoints(studio: StudioServer) -> None:
    for b in studio.command("list_breakpoints")["result"]["breakpoints"]:
        studio.command("remove_breakpoint", program=b["program"], breakpoint=b["breakpoint"])


def test_the_why_after_a_breakpoint_hit_shows_values(page: Any, studio: StudioServer) -> None:
    """A hit pauses the match: no frame redraws the why, so the answer itself must (it stayed
    on "Asking the server for values…")."""
    page.evaluate(f"() => {STUDIO}.session.selectRobot(0)")
    open_option(page, "play_soccer")
    studio.command("pause")
    clear_breakpoints(studio)
    assert studio.command("reset")["ok"]
    hits = "() => Number(document.querySelector('.timeline-canvas').dataset.hits || 0)"
    before = int(page.evaluate(hits))
    args = {"program": "behavior", "kind": "enter_state", "option": "play_soccer", "state": "ready"}
    assert studio.command("set_breakpoint", **args)["ok"]
    try:
        studio.command("speed", speed=4)
        studio.command("resume")
        wait_until(page, f"() => ({hits})() > {before}", timeout=40000)
        why = page.locator(".why")
        # The why of the hit's own decision (init → ready) with values: the why of the tick before
        # the hit showed values too, a moment before the hit's frame redrew it.
        answered = (
            "() => { const text = document.querySelector('.why').innerText;"
            " return text.startsWith('Decision of this tick: init → ready') && text.includes('Values'); }"
        )
        wait_until(page, answered, timeout=10000)
        text = str(why.inner_text())
        assert "Asking the server for values" not in text, text
        assert page.locator(".why .why-tree .tree-leaf.taken").count() == 1
    finally:
        clear_breakpoints(studio)
        studio.command("speed", speed=1)
        studio.command("resume")


def test_the_server_console_stays_quiet_while_the_editor_talks_to_the_language_server(
    page: Any, studio: StudioServer
) -> None:
    """A few keystrokes wrote 112 KB of the language server's debug lines to the console."""
    open_file(page, "behavior/options/face_ball.xabsl", "face_ball")
    before = studio.log.stat().st_size
    page.locator(".editor-host .cm-content").click()
    page.keyboard.press("Control+End")
    for _ in range(3):
        page.keyboard.type("/* x */")
        page.wait_for_timeout(400)
    page.keyboard.press("Control+z")
    page.wait_for_timeout(1000)
    grown = studio.log.read_bytes()[before:].decode(errors="replace")
    assert len(grown) < 500, grown[:2000]
    page.keyboard.press("Control+z")
    page.keyboard.press("Control+z")


def test_the_editor_does_not_stay_scrolled_sideways_after_typing_at_a_line_end(page: Any, studio: StudioServer) -> None:
    """Typing at the end of a line longer than the pane scrolled the view sideways, and moving to a
    short line left it so: every line's start hidden."""
    open_file(page, "behavior/options/face_ball.xabsl", "face_ball")
    scroller = "document.querySelector('.editor-host .cm-scroller')"
    page.locator(".editor-host .cm-content").click()
    page.keyboard.press("Control+Home")
    page.keyboard.press("End")  # line 1, the doc comment: longer than the pane is wide
    page.keyboard.type(" x")
    page.wait_for_timeout(300)
    scrolled = page.evaluate(f"() => [{scroller}.scrollLeft, {scroller}.clientWidth, {scroller}.scrollWidth]")
    assert scrolled[0] > 0, scrolled  # following the cursor past the right edge
    page.keyboard.press("Backspace")
    page.keyboard.press("Backspace")
    page.keyboard.press("ArrowDown")  # `option face_ball {`: short
    page.wait_for_timeout(300)
    assert page.evaluate(f"() => {scroller}.scrollLeft") == 0


def test_a_completion_opened_by_a_digit_closes_when_the_file_is_saved(page: Any, studio: StudioServer) -> None:
    path = "behavior/options/face_ball.xabsl"
    original = (studio.example / path).read_text()
    open_file(page, path, "face_ball")
    line = next(n for n, text in enumerate(original.split("\n")) if "< 10)" in text)
    page.locator(".editor-host .cm-content").click()
    page.keyboard.press("Control+Home")
    for _ in range(line):
        page.keyboard.press("ArrowDown")
    page.keyboard.press("End")
    page.keyboard.press("ArrowLeft")  # after the 10
    try:
        page.keyboard.type("5")  # `< 105`: a number names nothing to complete
        popup = page.locator(".cm-tooltip-autocomplete")
        page.wait_for_timeout(1000)
        assert popup.count() == 0, "typing a digit opened the completion popup"
        page.keyboard.press("Control+Space")  # asked for, it opens
        popup.wait_for(timeout=15000)
        page.keyboard.press("Control+s")
        page.locator(".editor-status", has_text="hot reloaded").wait_for(timeout=15000)
        assert (studio.example / path).read_text() == original.replace("< 10)", "< 105)")
        page.wait_for_timeout(300)
        assert popup.count() == 0, "the completion popup stayed open after the save"
    finally:
        page.keyboard.press("Escape")
        page.keyboard.press("Backspace")
        page.keyboard.press("Control+s")
        page.wait_for_function("() => !document.querySelector('.file-title').textContent.includes('●')", timeout=15000)
    assert (studio.example / path).read_text() == original


def cli_no_lint_count(folder: Path, agents: str) -> int:
    done = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "compile", agents, "--no-lint"],
        cwd=folder,
        capture_output=True,
        text=True,
        env={"PYTHONPATH": str(REPO), "PATH": "/usr/bin:/bin"},
    )
    found = re.search(r"(\d+) warnings?", done.stdout.strip().splitlines()[-1])
    assert found, done.stdout
    return int(found.group(1))


def test_lint_warnings_can_be_hidden_per_code_and_stay_hidden_for_the_set(
    browser: Any, team_studio: StudioServer
) -> None:
    folder = team_studio.example.parent
    _, warnings = cli_count(folder, "team.xabsl")
    squiggles = ".editor-host .cm-lintRange-warning"
    with studio_tab(browser, team_studio, live=False) as page:
        page.wait_for_function(f"() => {STUDIO} && {STUDIO}.session.hello", timeout=30000)
        open_file(page, "chase.xabsl", "option chase")
        wait_until(page, f"() => document.querySelector('.editor-status').innerText.includes('{warnings} warnings')")
        page.locator(squiggles).first.wait_for(timeout=15000)  # walk(speed = ...) leaves out turn
        page.click("#lint-filter")
        dialog = page.locator("dialog.lint-filter")
        dialog.wait_for(state="visible")
        missing = dialog.locator("input[data-code='parameter-missing']")
        assert missing.is_checked()
        missing.uncheck()
        wait_until(page, "() => document.querySelector('.editor-status').innerText.includes('(1 hidden)')")
        assert status_warnings(page) == warnings - 1
        wait_until(page, f"() => !document.querySelector({squiggles!r})")
        dialog.locator("button", has_text="Close").click()
    # remembered for this behavior set, in this browser
    with studio_tab(browser, team_studio, live=False) as page:
        page.wait_for_function(f"() => {STUDIO} && {STUDIO}.session.hello", timeout=30000)
        open_file(page, "chase.xabsl", "option chase")
        wait_until(page, "() => document.querySelector('.editor-status').innerText.includes('(1 hidden)')")
        page.wait_for_timeout(1500)  # the language server's squiggles have come, and stay hidden
        assert page.locator(squiggles).count() == 0
        # the twin of --no-lint: what the original compiler prints
        page.click("#lint-filter")
        page.click("#lint-original")
        wait_until(page, f"() => document.querySelector('.editor-status').innerText.includes('({warnings} hidden)')")
        assert status_warnings(page) == cli_no_lint_count(folder, "team.xabsl") == 0
        page.click("#lint-all")
        wait_until(page, "() => !document.querySelector('.editor-status').innerText.includes('hidden')")
        assert status_warnings(page) == warnings
        page.locator("dialog.lint-filter button", has_text="Close").click()


def external_write(path: Path, text: str) -> None:
    """Write as `git checkout` does: a new file renamed over the old one."""
    temporary = path.with_name(f".{path.name}.tmp")
    temporary.write_text(text)
    os.replace(temporary, path)


def editor_text(page: Any) -> str:
    return str(page.evaluate(f"() => {STUDIO}.editor.editorView.state.sliceDoc()"))


def test_a_file_changed_on_disk_reaches_the_running_team_and_the_editor(page: Any, studio: StudioServer) -> None:
    """After `git checkout` of an option file neither the team nor the editor changed, and the
    next save was refused as a conflict."""
    path = "behavior/options/face_ball.xabsl"
    original = (studio.example / path).read_text()
    open_file(page, path, "face_ball")
    generation = page.evaluate(f"() => {STUDIO}.session.hello.generation")
    checked_out = original.replace("< 10)", "< 12)")
    assert checked_out != original
    try:
        external_write(studio.example / path, checked_out)
        # hot reloaded, as a save from the studio is, and the clean buffer shows the new text
        wait_until(page, f"() => {STUDIO}.session.hello.generation > {generation}", timeout=5000)
        wait_until(page, f"() => {STUDIO}.editor.editorView.state.sliceDoc().includes('< 12)')", timeout=5000)
        assert editor_text(page) == checked_out
        assert "●" not in page.locator(".file-title").inner_text()
        new_gen = page.evaluate(f"() => {STUDIO}.session.hello.generation")
        with urllib.request.urlopen(f"{studio.url}api/generations/{new_gen}/diff", timeout=10) as response:
            diff = json.loads(response.read())
        assert [f["path"] for f in diff["files"]] == [path] and "+      if (abs(value = ball.angle) < 12)" in diff[
            "files"
        ][0]["diff"]

        # unsaved edits, then another checkout: the choice, with the diff between the two
        page.locator(".editor-host .cm-content").click()
        page.keyboard.press("Control+End")
        page.keyboard.type("\n/* mine */")
        theirs = checked_out.replace("< 12)", "< 14)")
        external_write(studio.example / path, theirs)
        banner = page.locator(".banner", has_text="changed on disk")
        banner.wait_for(timeout=5000)
        diff_text = banner.locator("pre.diff").inner_text(timeout=5000)
        assert "- /* mine */" in diff_text and "+       if (abs(value = ball.angle) < 14)" in diff_text, diff_text
        assert "/* mine */" in editor_text(page)  # nothing of mine is lost meanwhile
        screenshot(page, "changed-on-disk")
        banner.locator("button", has_text="Take theirs").click()
        wait_until(page, f"() => {STUDIO}.editor.editorView.state.sliceDoc().includes('< 14)')", timeout=5000)
        assert editor_text(page) == theirs and page.locator(".banner").is_hidden()

        # keep mine: my text is saved over theirs (no conflict refusal)
        page.locator(".editor-host .cm-content").click()
        page.keyboard.press("Control+End")
        page.keyboard.type("\n/* mine again */")
        external_write(studio.example / path, original)
        banner.wait_for(timeout=5000)
        banner.locator("button", has_text="Keep mine").click()
        page.locator(".toast.ok", has_text=f"Saved {path}").wait_for(timeout=10000)
        assert (studio.example / path).read_text() == theirs + "\n/* mine again */"
    finally:
        external_write(studio.example / path, original)
    wait_until(page, f"() => {STUDIO}.editor.editorView.state.sliceDoc() === {json.dumps(original)}", timeout=5000)
