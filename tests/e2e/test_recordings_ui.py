"""Recordings from inside the studio in Chromium: the live studio's Recordings dialog opens a headless
recording as a replay in a new tab (``/replay/ID/``), and "Run from here" in it opens a live fork
(``/fork/ID/``) whose timeline starts at the fork tick and whose first ticks are the recording's."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.e2e.conftest import REPO, StudioServer, screenshot, serving, studio_tab
from xabsl_studio.engine.cli import main
from xabsl_studio.engine.record import Recording

STUDIO = "window.xabslStudio"
FORK_AT = 700  # into PLAYING (pre-game is about 16 s)


@pytest.fixture(scope="module")
def live_studio(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[StudioServer, Path]]:
    """A live soccer studio whose record folder holds a headless 1 v 1 match of 20 s."""
    root = tmp_path_factory.mktemp("recordings-e2e")
    example = root / "soccer"
    example.mkdir()
    for name in ("behavior", "chase"):
        shutil.copytree(REPO / "examples" / "soccer" / name, example / name)
    (example / "studio.py").write_text(
        '"""The soccer world plug-in."""\n\nfrom xabsl_studio.examples.soccer.studio import example\n'
    )
    recordings = root / "recordings"  # the record folder StudioServer passes to xabsl serve
    recordings.mkdir()
    match = recordings / "match.mcap"
    code = main(
        ["run", str(REPO / "examples" / "soccer"), "--duration", "20", "--players", "1", "--record", str(match)]
    )
    assert code == 0
    with serving(example, root) as server:
        yield server, match


def _new_tab(browser: Any, click: Any) -> Any:
    with browser.expect_page(timeout=60000) as opened:
        click()
    tab = opened.value
    tab.wait_for_load_state()
    return tab


def test_open_a_recording_from_the_studio_and_run_from_here(
    browser: Any, live_studio: tuple[StudioServer, Path]
) -> None:
    server, match = live_studio
    with Recording(match) as recording:
        ticks = len(recording)
        expected = {
            seq: {name: recording.tick(seq).agents[name].option_names() for name in recording.agents}
            for seq in range(FORK_AT - 1, FORK_AT + 20)
        }
    with studio_tab(browser, server) as page:
        page.click("#recordings")
        row = page.locator('dialog.recordings tr[data-name="match.mcap"]')
        row.wait_for(timeout=15000)
        assert "soccer" in row.inner_text() and "0:" in row.inner_text()  # example and length (m:ss)
        screenshot(page, "recordings-dialog")
        replay = _new_tab(browser, lambda: row.locator("button.open-recording").click())
        errors: list[str] = []
        replay.on("pageerror", lambda error: errors.append(str(error)))
        try:
            assert "/replay/" in replay.url
            replay.wait_for_function(f"() => {STUDIO} && {STUDIO}.session.buffer.length === {ticks}", timeout=60000)
            # The live studio is still live beside it.
            assert page.evaluate(f"{STUDIO}.session.replay") is None
            fork_button = replay.locator("#run-from-here-replay")
            fork_button.wait_for(state="visible", timeout=15000)
            t = replay.evaluate(f"{STUDIO}.session.buffer.all.find((tick) => tick.seq === {FORK_AT}).t")
            replay.evaluate(f"{STUDIO}.session.setCursor({t})")
            fork = _new_tab(browser, fork_button.click)
            fork.on("pageerror", lambda error: errors.append(str(error)))
            assert "/fork/" in fork.url
            fork.wait_for_function(
                f"() => {STUDIO} && {STUDIO}.session.buffer.length > 25 && {STUDIO}.session.buffer.oldest",
                timeout=90000,
            )
            fork.evaluate("window.xabslStudio.connection.command('pause', {})")
            first = fork.evaluate(f"{STUDIO}.session.buffer.oldest.seq")
            assert first == FORK_AT - 1  # the fork's timeline starts at the fork tick
            compared = 0
            for seq in range(FORK_AT, FORK_AT + 20):
                names = fork.evaluate(
                    """(seq) => {
                      const s = window.xabslStudio.session;
                      const tick = s.buffer.all.find((t) => t.seq === seq);
                      if (!tick) return null; // a sample dropped under load
                      return tick.robots.map((r) => {
                        const index = s.indexOf(r.id);
                        const options = r.path.filter((n) => n.kind === "option");
                        return options.map((n) => index.optionById.get(n.option).name);
                      });
                    }""",
                    seq,
                )
                if names is None:
                    continue
                robots = fork.evaluate(f"{STUDIO}.session.robots.map((r) => r.name)")
                assert dict(zip(robots, names, strict=True)) == expected[seq], seq
                compared += 1
            assert compared > 12
            screenshot(fork, "run-from-here")
            fork.close()
        finally:
            replay.close()
        assert not errors, errors
