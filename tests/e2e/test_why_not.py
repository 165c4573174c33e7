""" "Why not" in the option view of a replay (Chromium): pick a state the decision did not go to.

At a recorded tick where blue2's ``approach_ball`` stays ``far`` (the ball 900 mm or more away),
asking "why not near" must show the one route there blocked by ``ball.distance < 900``, false,
with the distance the decision read (the recording's input value).
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.e2e.conftest import REPO, StudioServer, screenshot, serving, studio_tab
from xabsl_studio.engine.record import Recording

STUDIO = "window.xabslStudio"


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("whynot-e2e") / "match.mcap"
    command = [sys.executable, "-m", "xabsl_studio.engine.cli", "run", "examples/soccer", "--duration", "20"]
    env = dict(os.environ, PYTHONPATH=str(REPO))
    subprocess.run(
        [*command, "--players", "2", "--record", str(path)], cwd=REPO, env=env, check=True, capture_output=True
    )
    return path


@pytest.fixture(scope="module")
def replay_server(recording: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[StudioServer]:
    with serving(recording, tmp_path_factory.mktemp("whynot-log"), replay=True) as server:
        yield server


@pytest.fixture
def tab(browser: Any, replay_server: StudioServer) -> Iterator[Any]:
    with studio_tab(browser, replay_server, live=False) as page:
        yield page


def test_why_not_near_names_the_condition_that_blocked_it(tab: Any, recording: Path) -> None:
    with Recording(recording) as file:
        ticks = len(file)
        option = next(o for o in file.programs[("behavior", 0)].description["options"] if o["name"] == "approach_ball")
        far = next(s["id"] for s in option["states"] if s["name"] == "far")
        view = next(
            v
            for v in file.ticks(200, ticks)
            if any(
                n[0] == 0 and n[2] == option["id"] and n[3] == far and n[6] == far and n[7] >= 0
                for n in v.agents["blue2"].path
            )
            and float(v.agents["blue2"].inputs["ball.distance"]) >= 900  # type: ignore[arg-type]
        )
        distance = float(view.agents["blue2"].inputs["ball.distance"])  # type: ignore[arg-type]
    tab.wait_for_function(f"() => {STUDIO}.session.buffer.length === {ticks}", timeout=30000)
    tab.evaluate(f"() => {{ {STUDIO}.session.selectRobot(1); {STUDIO}.session.setCursor({view.t}); }}")
    tab.wait_for_function(f"() => {STUDIO}.session.view.seq === {view.seq}")
    tab.keyboard.press("o")
    tab.evaluate(f"() => {STUDIO}.session.openOptionById({option['id']})")
    picker = tab.locator(".why-not-picker")
    picker.wait_for(timeout=30000)
    # the picker offers the states the decision did not go to: not far, where it stayed
    assert picker.locator("option").all_inner_texts() == ["Why not…", "near"]
    picker.select_option(label="near")
    answer = tab.locator(".why-not-answer")
    try:
        answer.wait_for(timeout=30000)
    except Exception:
        raise AssertionError(f"no why-not answer; the pane shows {tab.locator('.why').inner_text()}") from None
    text = answer.inner_text()
    assert "Why not near:" in text and "1 route leads there" in text, text
    assert "blocked by ball.distance < 900 (false)" in text, text
    blocker = answer.locator(".cond.blocker")
    assert blocker.count() == 1
    comparison = blocker.locator(".comparisons li code").inner_text()
    assert comparison.startswith("ball.distance (") and comparison.endswith(") < 900"), comparison
    assert abs(float(comparison.split("(")[1].split(")")[0]) - distance) < 0.01
    screenshot(tab, "replay-why-not")
