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
