"""The Compare view in headless chromium: from a reload mark, and against a folder of the example.

The test edits the role selection of a running soccer studio over the API so that the goalie is
never chosen (a hot reload), opens the reload mark's changes dialog, and from it the structural
view: one changed condition in the common decision of role_selection, drawn in its state
machine. Then the Compare button compares the running behavior with the original kept in a
folder of the example.
"""

from __future__ import annotations

import json
import shutil
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.e2e.conftest import REPO, StudioServer, screenshot, serving, studio_tab

STUDIO = "window.xabslStudio"
ROLES = "behavior/options/role_selection.xabsl"
CONDITION = "if (robot.number == 1)"


@pytest.fixture(scope="module")
def studio(tmp_path_factory: pytest.TempPathFactory) -> Iterator[StudioServer]:
    root = tmp_path_factory.mktemp("compare")
    example = root / "soccer"
    example.mkdir()
    for name in ("behavior", "chase"):
        shutil.copytree(REPO / "examples" / "soccer" / name, example / name)
    shutil.copytree(REPO / "examples" / "soccer" / "behavior", example / "versions" / "original")
    (example / "studio.py").write_text(
        '"""The soccer world plug-in."""\n\nfrom xabsl_studio.examples.soccer.studio import example\n'
    )
    with serving(example, root) as server:
        yield server


def _api(server: StudioServer, method: str, path: str, body: Any = None) -> Any:
    data = json.dumps(body).encode() if body is not None else None
    request = urllib.request.Request(
        server.url + "api/" + path, data=data, headers={"Content-Type": "application/json"}, method=method
    )
    with urllib.request.urlopen(request, timeout=30) as response:
        return json.loads(response.read())


def test_a_reload_mark_opens_the_structural_view(browser: Any, studio: StudioServer) -> None:
    with studio_tab(browser, studio) as page:
        old_gen = page.evaluate(f"{STUDIO}.session.hello.generation")
        current = _api(studio, "GET", f"files/{ROLES}")
        assert current["text"].count(CONDITION) == 1
        text = current["text"].replace(CONDITION, "if (robot.number == 0)")
        _api(studio, "PUT", f"files/{ROLES}", {"text": text, "version": current["version"]})
        page.wait_for_function(f"() => {STUDIO}.session.hello.generation > {old_gen}", timeout=20000)
        new_gen = page.evaluate(f"{STUDIO}.session.hello.generation")
        page.wait_for_timeout(1500)
        page.evaluate(f"{STUDIO}.connection.command('pause', {{}})")
        page.wait_for_function(
            "() => JSON.parse(document.querySelector('.timeline-canvas').dataset.marks || '[]')"
            f".some((m) => m.gen === {new_gen})",
            timeout=20000,
        )
        page.wait_for_timeout(800)
        marks = page.evaluate("JSON.parse(document.querySelector('.timeline-canvas').dataset.marks)")
        mark = next(m for m in marks if m["gen"] == new_gen)
        box = page.locator(".timeline-canvas").bounding_box()
        assert box is not None
        page.mouse.click(box["x"] + mark["px"], box["y"] + 8)
        page.locator(f"dialog.changes[open] section.changed-file[data-path='{ROLES}']").wait_for(timeout=10000)
        page.locator("dialog.changes button.structure").click()

        rows = page.locator("dialog.compare[open] table.compare-changes tbody tr")
        rows.first.wait_for(timeout=20000)
        assert rows.count() == 1
        cells = [rows.nth(0).locator("td").nth(i).inner_text() for i in range(6)]
        assert cells == [
            "~",
            "condition",
            "role_selection/(common)",
            "condition: robot.number == 1 → robot.number == 0",
            "options/role_selection.xabsl:5",
            "options/role_selection.xabsl:5",
        ]
        # the option graph marks role_selection changed; its state machine is drawn, the changed edges marked
        graph = page.locator("dialog.compare .compare-graph svg")
        assert graph.locator("g.node.changed > title").all_text_contents() == ["o:role_selection"]
        machine = page.locator("dialog.compare .compare-machine svg")
        assert machine.locator("g.edge.changed").count() >= 3  # into goalie from each state
        assert page.locator("dialog.compare .compare-machine-title").inner_text() == "option role_selection"
        screenshot(page, "compare-reload")
        page.locator("dialog.compare button", has_text="Close").click()
        # the text diff stayed open beside it
        page.locator("dialog.changes[open] button", has_text="Close").click()

        # The Compare button: the running behavior against the original kept in a folder.
        page.locator("button#compare").click()
        page.locator("dialog.compare[open] input.compare-old").fill("versions/original")
        page.locator("dialog.compare select.compare-program").select_option("behavior")
        page.locator("dialog.compare button.compare-run").click()
        page.wait_for_function(
            "() => document.querySelector('dialog.compare .compare-status').textContent.includes('versions/original')",
            timeout=20000,
        )
        rows = page.locator("dialog.compare[open] table.compare-changes tbody tr")
        assert rows.count() == 1 and rows.nth(0).locator("td").nth(2).inner_text() == "role_selection/(common)"
        assert "1 change" in page.locator("dialog.compare .compare-status").inner_text()
        page.locator("dialog.compare button", has_text="Close").click()
    assert (Path(studio.example) / ROLES).read_text() == text
