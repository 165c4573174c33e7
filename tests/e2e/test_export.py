"""The Export menus in headless chromium: the option graph and a state machine downloaded as SVG, PNG, PDF.

The files are the browser's downloads, opened by programs that are not ours (``xml.etree``, the
PNG chunk layout, poppler's ``pdftoppm``).
"""

from __future__ import annotations

import shutil
import subprocess
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.cli.test_picture_cli import png_size
from tests.e2e.conftest import REPO, StudioServer, serving, studio_tab

SVG = "{http://www.w3.org/2000/svg}"


@pytest.fixture(scope="module")
def demo(tmp_path_factory: pytest.TempPathFactory) -> Iterator[StudioServer]:
    root = tmp_path_factory.mktemp("export")
    shutil.copytree(REPO / "examples" / "demo", root / "demo")
    with serving(root / "demo", root) as server:
        yield server


@pytest.fixture
def page(browser: Any, demo: StudioServer) -> Iterator[Any]:
    with studio_tab(browser, demo) as tab:
        yield tab


def export(page: Any, panel: str, fmt: str, tmp_path: Path, with_path: bool = True) -> tuple[str, bytes]:
    """Open ``panel``'s Export menu, pick ``fmt``; the download's name and bytes."""
    menu = page.locator(f"{panel} .export-menu")
    menu.locator("summary").click()
    box = menu.get_by_role("checkbox", name="with the active path")
    if box.is_checked() != with_path:
        box.click()
    with page.expect_download() as info:
        menu.get_by_role("menuitem", name=fmt.upper()).click()
    download = info.value
    target = tmp_path / download.suggested_filename
    download.save_as(target)
    return download.suggested_filename, target.read_bytes()


def test_the_option_graph_downloads_in_each_format(page: Any, tmp_path: Path) -> None:
    page.keyboard.press("g")
    page.locator(".graph-panel svg #option_0").wait_for()
    name, data = export(page, ".graph-panel", "svg", tmp_path)
    assert name.endswith("-play-tick.svg"), name
    root = ET.fromstring(data)
    texts = [t.text or "" for t in root.iter(f"{SVG}text")]
    assert any(t.startswith("robot1 at tick ") for t in texts) and any(t.startswith("▸ ") for t in texts), texts
    name, data = export(page, ".graph-panel", "png", tmp_path, with_path=False)
    assert name.endswith("-play.png") and png_size(data)[0] > 100
    name, data = export(page, ".graph-panel", "pdf", tmp_path, with_path=False)
    assert data.startswith(b"%PDF-")
    pdftoppm = shutil.which("pdftoppm")
    assert pdftoppm is not None, "poppler-utils (make test-deps installs it)"
    subprocess.run([pdftoppm, "-png", "-r", "72", str(tmp_path / name), str(tmp_path / "page")], check=True)
    (page_png,) = tmp_path.glob("page*.png")
    assert png_size(page_png.read_bytes())[0] > 50


def test_the_option_view_exports_its_state_machine(page: Any, tmp_path: Path) -> None:
    page.keyboard.press("o")
    page.locator(".option-panel svg [id^='state_']").first.wait_for()
    title = page.locator(".option-panel .option-title").inner_text()
    name, data = export(page, ".option-panel", "svg", tmp_path)
    assert name.startswith(title) and name.endswith("-tick.svg"), (name, title)
    root = ET.fromstring(data)
    assert any((e.get("id") or "").startswith("state_") for e in root.iter())
    assert len([e for e in root.iter() if e.get("fill") == "#ffe08a"]) == 1, "the active state"
