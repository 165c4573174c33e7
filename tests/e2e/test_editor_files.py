"""Files as they are in the studio's editor (issue 11): CR, CRLF and latin-1 files open unmodified
and save byte-exact; Enter inserts the file's own line separator."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.e2e.conftest import StudioServer

CR = "behavior/options/cr_notes.xabsl"
CRLF = "behavior/options/crlf_notes.xabsl"
CR_BYTES = (
    b"/* Notes kept with CR line ends, caf\xe9 in latin-1. */\r"
    b"option cr_notes {\r  initial state s {\r    decision { else stay; }\r    action { }\r  }\r}\r"
)
CRLF_BYTES = b"/* CRLF notes */\r\noption crlf_notes {\r\n  initial state s {\r\n    action { }\r\n  }\r\n}\r\n"


@pytest.fixture(scope="module")
def odd_files(studio: StudioServer) -> Path:
    """Two files not included by any agents file, written before the first page lists the files."""
    (studio.example / CR).write_bytes(CR_BYTES)
    (studio.example / CRLF).write_bytes(CRLF_BYTES)
    return studio.example


def open_file(page: Any, path: str, marker: str) -> None:
    page.keyboard.press("e")
    page.locator(f".file-tree [data-path='{path}']").click()
    page.wait_for_function(
        f"() => document.querySelector('.editor-host .cm-content').textContent.includes('{marker}')",
        timeout=20000,
    )


def dirty(page: Any, path: str) -> bool:
    title = page.locator(".file-title").inner_text()
    marked = page.locator(f".file-tree [data-path='{path}']").get_attribute("class") or ""
    assert title.startswith(path)
    return title.endswith("●") or "dirty" in marked.split()


def test_a_cr_file_opens_unmodified_and_saves_byte_exact(odd_files: Path, page: Any) -> None:
    open_file(page, CR, "cr_notes")
    assert not dirty(page, CR), "opening a CR file must not mark it modified"
    lines = page.locator(".editor-host .cm-line").all_inner_texts()
    assert lines[:2] == ["/* Notes kept with CR line ends, café in latin-1. */", "option cr_notes {"]

    page.locator(".editor-host .cm-content").click()
    page.keyboard.press("Control+End")
    page.keyboard.type("// edited")
    page.keyboard.press("Enter")
    page.keyboard.type("// more")
    assert dirty(page, CR)
    page.keyboard.press("Control+s")
    page.locator(".toast", has_text=f"Saved {CR}").wait_for(timeout=20000)
    assert not dirty(page, CR)
    data = (odd_files / CR).read_bytes()
    assert data.startswith(CR_BYTES + b"// edited\r"), data
    assert data.endswith(b"// more") and b"\n" not in data, "Enter inserted the file's CR, nothing else"
    assert b"caf\xe9" in data, "the latin-1 byte stays latin-1"


def test_a_crlf_file_opens_unmodified_and_an_unchanged_save_writes_the_same_bytes(odd_files: Path, page: Any) -> None:
    open_file(page, CRLF, "crlf_notes")
    assert not dirty(page, CRLF)
    page.locator(".editor-host .cm-content").click()
    page.keyboard.press("Control+s")
    page.locator(".toast", has_text=f"Saved {CRLF}").wait_for(timeout=20000)
    assert (odd_files / CRLF).read_bytes() == CRLF_BYTES
