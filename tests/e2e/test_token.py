"""A studio started with ``--token`` in headless chromium: the UI and the documentation still work.

Every route but the UI's files and the API schema needs the token (docs/security.md, "Routes"):
the page reads it from its address and sends it, and the behavior documentation, whose pages link
to each other without it, is opened once with ``/docs?token=`` and then carried by its cookie.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.e2e.conftest import CHROMIUM, REPO, WEB_DIST, free_port, screenshot, watched_tab

TOKEN = "e2e-" + "t" * 26


@pytest.fixture(scope="module")
def guarded(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """``xabsl serve --token`` on a copy of the demo behavior; its address."""
    if not CHROMIUM.exists() or not (WEB_DIST / "index.html").is_file():
        pytest.fail("chromium and the built UI are needed: `make test` provides both")
    root = tmp_path_factory.mktemp("token")
    shutil.copytree(REPO / "examples" / "demo", root / "demo")
    port = free_port()
    xabsl = Path(sys.executable).with_name("xabsl")
    command = [str(xabsl), "serve", str(root / "demo"), "--port", str(port), "--token", TOKEN]
    command += ["--web-dist", str(WEB_DIST), "--record-dir", str(root / "recordings")]
    with (root / "serve.log").open("ab") as log:
        process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, cwd=REPO)
    url = f"http://127.0.0.1:{port}/"
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                urllib.request.urlopen(url, timeout=2).close()
                break
            except OSError:
                assert process.poll() is None and time.monotonic() < deadline, (root / "serve.log").read_text()
                time.sleep(0.2)
        yield url
    finally:
        process.terminate()
        process.wait(timeout=15)


@pytest.fixture
def tab(browser: Any) -> Iterator[Any]:
    with watched_tab(browser) as page:
        yield page


def status_of(url: str) -> int:
    try:
        with urllib.request.urlopen(url, timeout=10) as response:
            return int(response.status)
    except urllib.error.HTTPError as error:
        return error.code


def test_the_ui_loads_and_talks_with_the_token_from_its_address(tab: Any, guarded: str) -> None:
    refused: list[str] = []
    tab.on("response", lambda r: refused.append(f"{r.status} {r.url}") if r.status in (401, 403) else None)
    with tab.expect_response(lambda r: "/api/" in r.url, timeout=20000) as api:
        tab.goto(f"{guarded}?token={TOKEN}")
    assert api.value.status == 200, api.value.url  # a REST call of the page, with the token
    tab.locator(".link-health[data-state='live']").wait_for(timeout=20000)  # the websocket, with the token
    assert not refused, refused
    assert status_of(guarded + "api/status") == 401


def test_the_docs_open_with_the_token_once_and_their_links_work(tab: Any, guarded: str) -> None:
    assert status_of(guarded + "docs/demo/index.html") == 401
    styles: list[int] = []
    tab.on("response", lambda r: styles.append(r.status) if r.url.endswith("style.css") else None)
    tab.goto(f"{guarded}docs?token={TOKEN}")
    tab.wait_for_url("**/docs/demo/index.html", timeout=15000)
    tab.locator('a[href="options/approach_ball.html"]').first.click()
    tab.wait_for_url("**/options/approach_ball.html", timeout=10000)
    assert tab.locator("h1").inner_text() == "option approach_ball"
    assert "token" not in tab.url and styles and set(styles) == {200}
    screenshot(tab, "docs-token")
