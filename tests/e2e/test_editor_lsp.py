"""The studio editor speaks to the language server (websocket /lsp): completion and diagnostics."""

from __future__ import annotations

from typing import Any

from tests.e2e.conftest import StudioServer, screenshot

FACE = "behavior/options/face_ball.xabsl"


def wait_until(page: Any, expression: str, timeout: float = 20000) -> Any:
    return page.wait_for_function(expression, timeout=timeout)


def open_file(page: Any, path: str, needle: str) -> None:
    page.keyboard.press("e")
    page.locator(f".file-tree [data-path='{path}']").click()
    wait_until(page, f"() => document.querySelector('.editor-host .cm-content').textContent.includes({needle!r})")


def put_cursor_at_line_end(page: Any, line: int) -> None:
    """Click into the editor and move the cursor to the end of 0-based ``line`` (keys only)."""
    page.locator(".editor-host .cm-content").click()
    page.keyboard.press("Control+Home")
    for _ in range(line):
        page.keyboard.press("ArrowDown")
    page.keyboard.press("End")


def test_editor_completes_states_and_shows_the_servers_diagnostic(page: Any, studio: StudioServer) -> None:
    original = (studio.example / FACE).read_text()
    open_file(page, FACE, "face_ball")

    # completion after 'goto ': the option's states, from the server
    line = next(n for n, text in enumerate(original.split("\n")) if "goto facing;" in text)
    put_cursor_at_line_end(page, line)
    page.keyboard.press("ArrowLeft")  # before the ';'
    for _ in range(len("facing")):
        page.keyboard.press("Backspace")
    page.keyboard.type("t")
    popup = page.locator(".cm-tooltip-autocomplete")
    popup.wait_for(timeout=15000)
    assert "turning" in popup.inner_text()
    page.keyboard.press("Escape")

    # a misspelt state: the server's diagnostic, with its "did you mean" as an action
    page.keyboard.type("urnin")  # 'goto turnin': no such state
    page.locator(".editor-host .cm-lintRange-error").first.wait_for(timeout=15000)
    page.locator(".editor-status.error", has_text="no state 'turnin'").wait_for(timeout=15000)
    page.locator(".editor-host .cm-lintRange-error").first.hover()
    tooltip = page.locator(".cm-tooltip-lint")
    tooltip.wait_for(timeout=10000)
    assert "did you mean 'turning'" in tooltip.inner_text()
    screenshot(page, "editor-lsp")
    tooltip.locator("button", has_text="Change to 'turning'").click()
    page.locator(".editor-status.ok").wait_for(timeout=15000)
    content = page.locator(".editor-host .cm-content").inner_text()
    assert "goto turning;" in content and "goto turnin;" not in content
    assert page.locator(".editor-host .cm-lintRange-error").count() == 0


def test_editor_hover_definition_and_rename_come_from_the_server(page: Any, studio: StudioServer) -> None:
    original = (studio.example / FACE).read_text()
    lines = original.split("\n")
    open_file(page, FACE, "face_ball")

    # hover: the symbol's type, range, unit and doc comment
    box = page.evaluate(
        """(needle) => {
          const content = document.querySelector('.editor-host .cm-content');
          const walker = document.createTreeWalker(content, NodeFilter.SHOW_TEXT);
          for (let node = walker.nextNode(); node; node = walker.nextNode()) {
            // the call 'turn(': a token of its own, or followed by its '(' in the same text
            const text = node.textContent;
            const at = text === needle ? 0 : text.indexOf(needle + "(");
            if (at < 0) continue;
            const range = document.createRange();
            range.setStart(node, at + 1);
            range.setEnd(node, at + 2);
            const r = range.getBoundingClientRect();
            return { x: r.x + r.width / 2, y: r.y + r.height / 2 };
          }
          return null;
        }""",
        "turn",
    )
    assert box is not None
    page.mouse.move(box["x"], box["y"])
    hover = page.locator(".cm-xabsl-hover")
    hover.wait_for(timeout=15000)
    assert "basic behavior" in hover.inner_text() and "rate" in hover.inner_text()

    # rename a state: every occurrence, the buffer stays unsaved and compiles
    put_cursor_at_line_end(page, next(n for n, t in enumerate(lines) if "initial state turning" in t))
    page.keyboard.press("ArrowLeft")
    page.keyboard.press("ArrowLeft")  # inside 'turning'
    page.once("dialog", lambda dialog: dialog.accept("spinning"))
    page.keyboard.press("F2")
    page.locator(".toast.ok", has_text="Renamed in 1 file").wait_for(timeout=15000)
    content = page.locator(".editor-host .cm-content").inner_text()
    assert "initial state spinning" in content and "goto spinning;" in content and "turning" not in content
    page.locator(".editor-status.ok").wait_for(timeout=15000)
    assert (studio.example / FACE).read_text() == original  # not saved

    # go to definition: F12 on a basic behavior call opens its declaration
    put_cursor_at_line_end(page, next(n for n, t in enumerate(lines) if "turn(rate" in t))
    page.keyboard.press("Home")
    page.keyboard.press("ArrowRight")
    page.keyboard.press("F12")
    page.locator(".file-title", has_text="behavior/basic_behaviors.xabsl").wait_for(timeout=15000)
    page.locator(".editor-host .cm-activeLine", has_text="behavior turn").wait_for(timeout=15000)
