"""How fluid is the studio UI with a team-sized behavior set, beside the soccer example?

Runs the built UI (``web/dist``) in headless Debian chromium against a real studio server and
prints how often the UI drew per second and how long a draw took, with the option graph and the
activation tree visible, for each scenario in the same run:

* ``soccer``: the soccer example as users open it (5 robots a side, its own behaviors);
* ``team``: a naoth-shaped generated set (``tests/navset.py``: 200 options in 15 folders, a
  31-state root) on 5 robots of the bench world: the option graph at its overview, then with
  every folder expanded (200 option nodes, the active path faded in), then the root's state
  machine in the option view;
* ``tree`` (``--scenario tree``): 100 options as a binary tree on 10 robots, the earlier figure.

Run: ``make web && .venv/bin/python benchmarks/ui_fps.py [--seconds 10] [--scenario soccer team]``.
Needs /usr/bin/chromium.
"""

from __future__ import annotations

import argparse
import shutil
import socket
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import uvicorn
from _sets import navset  # benchmarks/ is the script's folder

from xabsl_studio.engine.host import Example
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.api.app import WEB_DIST, create_app
from xabsl_studio.server.api.listen import uvicorn_config
from xabsl_studio.server.api.security import SecurityPolicy
from xabsl_studio.server.session.live import Session

REPO = Path(__file__).resolve().parents[1]
OPTIONS = 100
AGENTS = 10
#: robots of the team scenario
TEAM_ROBOTS = 5
#: the frame rate the studio keeps (issue 31)
GOAL_FPS = 30
SYMBOLS = """namespace symbols("Benchmark symbols") {
  bool input ball.seen;
  float input ball.distance [0..10000] "mm";
  float input ball.angle [-180..180] "deg";
  float input ball.time_since_seen [0..] "ms";
  enum game.state { init, ready, set, playing, finished };
  enum game.state input game.state;
  float internal ticks;
}
"""

BEHAVIORS = """namespace skills("Basic behaviors") {
  behavior stand { }
  behavior walk { float speed "mm/s"; float direction "deg"; }
  behavior turn { float rate "deg/s"; }
}
"""


def option_source(i: int) -> str:
    children = [c for c in (2 * i + 1, 2 * i + 2) if c < OPTIONS]
    # Every state calls a child option (leaves walk), so the activation path is about 8 deep
    # and changes whenever any option on it switches state.
    calls = [f"o{c}(speed = {100 + c});" for c in children] or ["walk(speed = @speed, direction = ball.angle);"]
    switch = 150 + (37 * i) % 500
    states = []
    for k, name in enumerate(("first", "second", "third")):
        nxt = ("second", "third", "first")[k]
        action = calls[k % len(calls)]
        states.append(
            f"  {'initial ' if k == 0 else ''}state {name} {{\n"
            f"    decision {{\n      if (state_time > {switch + 50 * k} && ball.distance >= 0) goto {nxt};\n"
            f"      else stay;\n    }}\n"
            f"    action {{\n      ticks = ticks + 1;\n      {action}\n    }}\n  }}\n"
        )
    return f'/** Generated option {i}. */\noption o{i} {{\n  float @speed "mm/s";\n' + "".join(states) + "}\n"


def write_behavior(folder: Path) -> None:
    (folder / "options").mkdir(parents=True)
    (folder / "symbols.xabsl").write_text(SYMBOLS)
    (folder / "skills.xabsl").write_text(BEHAVIORS)
    includes = ['include "symbols.xabsl";', 'include "skills.xabsl";']
    for i in range(OPTIONS):
        (folder / "options" / f"o{i}.xabsl").write_text(option_source(i))
        includes.append(f'include "options/o{i}.xabsl";')
    (folder / "agents.xabsl").write_text("\n".join(includes) + '\nagent bench("Benchmark", o0);\n')


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def measure(page: Any, seconds: float) -> tuple[float, float, float]:
    """Frames received, UI draws per second and ms per draw, averaged over ``seconds``."""
    samples = []
    end = time.monotonic() + seconds
    studio = "window.xabslStudio"
    while time.monotonic() < end:
        page.wait_for_timeout(1000)
        samples.append(page.evaluate(f"({{...{studio}.stats, fps: {studio}.connection.framesPerSecond}})"))
    n = len(samples)
    return (
        sum(s["fps"] for s in samples) / n,
        sum(s["drawsPerSecond"] for s in samples) / n,
        sum(s["renderMs"] for s in samples) / n,
    )


def report(name: str, figures: tuple[float, float, float]) -> None:
    frames, draws, render = figures
    # the UI draws at most once per frame received: it keeps up when it draws (nearly) all of them
    verdict = "keeps" if draws >= min(frames, GOAL_FPS) - 1 else "BELOW"
    print(
        f"  {name:<44} frames {frames:5.1f}/s  draws {draws:5.1f}/s  {render:6.2f} ms/draw  "
        f"({verdict} {GOAL_FPS} fps; budget 33 ms, {33.3 / max(render, 0.01):.0f}x)"
    )


def serve(example: Example) -> tuple[uvicorn.Server, int]:
    session = Session(example)
    port = free_port()
    app = create_app(session, SecurityPolicy(token=None), WEB_DIST)
    config = uvicorn_config(app, "127.0.0.1", port)
    server = uvicorn.Server(config)
    threading.Thread(target=server.run, daemon=True).start()
    while not server.started:
        time.sleep(0.05)
    return server, port


def open_studio(browser: Any, port: int) -> Any:
    page = browser.new_page(viewport={"width": 1600, "height": 1000})
    page.goto(f"http://127.0.0.1:{port}/")
    page.wait_for_function("() => window.xabslStudio && window.xabslStudio.session.buffer.length > 10")
    page.keyboard.press("g")
    page.keyboard.press("a")
    page.wait_for_function("() => document.querySelectorAll('.graph-panel g.node').length > 0", timeout=60000)
    page.wait_for_timeout(2000)
    return page


def run(scenario: str, root: Path, browser: Any, seconds: float) -> None:
    if scenario == "soccer":
        from xabsl_studio.examples.soccer.studio import example

        server, port = serve(example(REPO / "examples" / "soccer"))
        page = open_studio(browser, port)
        robots = page.evaluate("window.xabslStudio.session.robots.length")
        print(f"soccer example: {robots} robots")
        report("option graph + activation", measure(page, seconds))
    elif scenario == "team":
        folder = root / "team"
        generator = navset()
        generator.write_set(folder)
        server, port = serve(BenchExample(folder, robots=TEAM_ROBOTS))
        page = open_studio(browser, port)
        options = len(generator.option_names())
        print(f"team-sized set: {options} options in {len(generator.FOLDERS)} folders, {TEAM_ROBOTS} robots")
        report("option graph overview (folders) + activation", measure(page, seconds))
        page.click(".graph-panel button:has-text('Expand all')")
        expanded = f"() => document.querySelectorAll('.graph-panel g.node[id^=option_]').length === {options}"
        page.wait_for_function(expanded, timeout=60000)
        report(f"option graph, all {options} options, faded", measure(page, seconds))
        page.keyboard.press("o")
        page.wait_for_function("() => document.querySelectorAll('.option-panel g.node').length > 20", timeout=60000)
        states = page.evaluate("document.querySelectorAll('.option-panel g.node[id^=state_]').length")
        report(f"option view, the root's {states}-state machine", measure(page, seconds))
    else:
        folder = root / "tree"
        write_behavior(folder)
        server, port = serve(BenchExample(folder, robots=AGENTS))
        page = open_studio(browser, port)
        depth = page.evaluate("window.xabslStudio.session.robotInView().path.length")
        print(f"{OPTIONS} options, {AGENTS} agents, activation path of {depth} nodes")
        report("option graph + activation", measure(page, seconds))
    page.close()
    server.should_exit = True


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=10.0, help="measuring time per view")
    parser.add_argument("--scenario", nargs="+", choices=["soccer", "team", "tree"], default=["soccer", "team"])
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright

    root = Path(tempfile.mkdtemp(prefix="xabsl-ui-fps-"))
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(
                executable_path="/usr/bin/chromium",
                args=[
                    "--headless",
                    "--no-sandbox",
                    "--disable-gpu",
                    "--disable-quic",
                    "--no-first-run",
                    "--disable-background-networking",
                    "--disable-component-update",
                    "--disable-sync",
                ],
            )
            for scenario in args.scenario:
                run(scenario, root, browser, args.seconds)
            browser.close()
    finally:
        shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
