"""Fixtures for the studio's end-to-end tests: a real ``xabsl serve`` and Debian's chromium.

The server runs as a subprocess of the real command line on a free loopback port, serving the
built UI (``web/dist``, made by ``make web``) and a private copy of the soccer behaviors, so the
tests may break and fix files. The browser is Debian's ``/usr/bin/chromium`` driven by Playwright
for Python (never a downloaded browser), headless, with a fresh user-data directory.

Without chromium or a built UI these tests skip with the reason; ``make test`` provides both.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

REPO = Path(__file__).resolve().parents[2]
CHROMIUM = Path("/usr/bin/chromium")
WEB_DIST = REPO / "web" / "dist"
#: Where the tests save their screenshots (git-ignored). The README's pictures in docs/screenshots
#: are copies of two of them, refreshed by hand (`cp build/screenshots/{watch,editor}.png docs/screenshots/`)
#: so that a test run never dirties the work tree.
SCREENSHOTS = REPO / "build" / "screenshots"
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class StudioServer:
    """``xabsl serve`` on a soccer copy, started, stopped and restarted on one port."""

    def __init__(self, example: Path, port: int, log: Path, replay: bool = False, extra: tuple[str, ...] = ()) -> None:
        self.example = example
        #: more arguments of ``xabsl serve`` (``--robots 5``)
        self.extra = extra
        self.port = port
        self.log = log
        #: serve ``example`` as a recording (``xabsl serve --replay FILE``) instead of a folder
        self.replay = replay
        self.process: subprocess.Popen[bytes] | None = None

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}/"

    def start(self) -> None:
        xabsl = Path(sys.executable).with_name("xabsl")
        what = ["--replay", str(self.example)] if self.replay else [str(self.example)]
        command = [str(xabsl), "serve", *what, "--port", str(self.port), "--web-dist", str(WEB_DIST)]
        command += ["--record-dir", str(self.log.parent / "recordings")]  # not into the user's cache
        command += self.extra
        with self.log.open("ab") as log:
            self.process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, cwd=REPO)
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(f"xabsl serve exited: {self.log.read_text(errors='replace')}")
            try:
                with urllib.request.urlopen(self.url + "api/status", timeout=2) as response:
                    if response.status == 200:
                        return
            except OSError:
                time.sleep(0.2)
        raise RuntimeError("xabsl serve did not answer within 60 s")

    def stop(self) -> None:
        if self.process is not None and self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=15)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(timeout=5)
        self.process = None

    def restart(self) -> None:
        self.stop()
        self.start()

    def command(self, op: str, timeout: float = 20, **args: Any) -> Any:
        """``POST /api/command`` with ``{"op": op, **args}``: the reply as JSON (errors are replies too)."""
        body = json.dumps({"op": op, **args}).encode()
        request = urllib.request.Request(
            self.url + "api/command", data=body, headers={"Content-Type": "application/json"}, method="POST"
        )
        with urllib.request.urlopen(request, timeout=timeout) as response:
            return json.loads(response.read())


@contextlib.contextmanager
def serving(example: Path, root: Path, replay: bool = False, extra: tuple[str, ...] = ()) -> Iterator[StudioServer]:
    """``xabsl serve`` on ``example`` (a folder, or a recording with ``replay``) while in the block.

    Fails (never skips) when chromium or the built UI is missing: a missing browser must not look
    like a passing UI.
    """
    if not CHROMIUM.exists():
        pytest.fail("Debian chromium is not installed: `make test` (or `make test-deps`) installs it")
    if not (WEB_DIST / "index.html").is_file():
        pytest.fail("the web UI is not built: `make test` (or `make web`) builds it")
    server = StudioServer(example, free_port(), root / "serve.log", replay=replay, extra=extra)
    server.start()
    try:
        yield server
    finally:
        server.stop()


@pytest.fixture(scope="module")
def studio(tmp_path_factory: pytest.TempPathFactory) -> Iterator[StudioServer]:
    root = tmp_path_factory.mktemp("studio")
    example = root / "soccer"
    example.mkdir()
    for name in ("behavior", "chase"):
        shutil.copytree(REPO / "examples" / "soccer" / name, example / name)
    # The copy says how the studio runs it as any example folder does: a studio.py (here the
    # soccer plug-in's factory, applied to the copy; the world's code comes from the package).
    (example / "studio.py").write_text(
        '"""The soccer world plug-in."""\n\nfrom xabsl_studio.examples.soccer.studio import example\n'
    )
    with serving(example, root) as server:
        yield server


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Any]:
    if not CHROMIUM.exists():
        # fail, never skip: a missing browser must not look like a passing UI
        pytest.fail("Debian chromium is not installed: `make test` (or `make test-deps`) installs it")
    from playwright.sync_api import sync_playwright

    profile = tmp_path_factory.mktemp("chromium-profile")
    os.environ.setdefault("PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD", "1")
    with sync_playwright() as p:
        context = p.chromium.launch_persistent_context(
            str(profile),
            executable_path=str(CHROMIUM),
            headless=True,
            args=CHROMIUM_ARGS,
            viewport={"width": 1600, "height": 1000},
        )
        yield context
        context.close()


@contextlib.contextmanager
def watched_tab(browser: Any) -> Iterator[Any]:
    """A fresh blank tab; closing it fails the test when the page raised an uncaught error meanwhile."""
    tab = browser.new_page()
    errors: list[str] = []
    tab.on("pageerror", lambda error: errors.append(str(error)))
    yield tab
    tab.close()
    assert not errors, f"uncaught errors in the page: {errors}"


@contextlib.contextmanager
def studio_tab(browser: Any, server: StudioServer, live: bool = True) -> Iterator[Any]:
    """A fresh tab on ``server`` (with ``live``: once the first frames have arrived); see ``watched_tab``."""
    with watched_tab(browser) as tab:
        tab.goto(server.url)
        if live:
            tab.wait_for_function(
                "() => window.xabslStudio && window.xabslStudio.session.buffer.length > 5", timeout=30000
            )
        yield tab


@pytest.fixture
def page(browser: Any, studio: StudioServer) -> Iterator[Any]:
    """A fresh tab on the studio, live (the first frames have arrived)."""
    with studio_tab(browser, studio) as tab:
        yield tab


def screenshot(page: Any, name: str) -> None:
    """Save a screenshot of the whole window into build/screenshots/NAME.png."""
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SCREENSHOTS / f"{name}.png"))
