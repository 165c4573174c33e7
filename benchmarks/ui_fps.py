"""How fluid is the studio UI with 10 agents and a 100-option behavior?

Generates a behavior of 100 options (a binary tree of options, three states each, switching on
``state_time`` so the activation path changes every few hundred milliseconds), runs it on 10
robots of the demo world in a real studio server, opens the built UI (``web/dist``) in headless
Debian chromium, and prints how often the UI drew per second and how long a draw took, with the
option graph, the activation tree and the timeline visible (the heaviest panels).

Run: ``make web && .venv/bin/python benchmarks/ui_fps.py [--seconds 10]``. Needs /usr/bin/chromium.
"""

from __future__ import annotations

import argparse
import shutil
import socket
import tempfile
import threading
import time
from pathlib import Path

import uvicorn

from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.api.app import WEB_DIST, create_app
from xabsl_studio.server.api.security import SecurityPolicy
from xabsl_studio.server.protocol.limits import MAX_MESSAGE_BYTES
from xabsl_studio.server.session.live import Session

OPTIONS = 100
AGENTS = 10

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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=10.0, help="measuring time")
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright

    root = Path(tempfile.mkdtemp(prefix="xabsl-ui-fps-"))
    try:
        behavior = root / "bench"
        write_behavior(behavior)
        session = Session(BenchExample(behavior, robots=AGENTS))
        port = free_port()
        app = create_app(session, SecurityPolicy(token=None), WEB_DIST)
        config = uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning", ws_max_size=MAX_MESSAGE_BYTES)
        server = uvicorn.Server(config)
        threading.Thread(target=server.run, daemon=True).start()
        while not server.started:
            time.sleep(0.05)
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
            page = browser.new_page(viewport={"width": 1600, "height": 1000})
            page.goto(f"http://127.0.0.1:{port}/")
            page.wait_for_function("() => window.xabslStudio && window.xabslStudio.session.buffer.length > 10")
            page.keyboard.press("g")
            page.keyboard.press("a")
            page.wait_for_timeout(2000)
            depth = page.evaluate("window.xabslStudio.session.robotInView().path.length")
            samples = []
            end = time.monotonic() + args.seconds
            while time.monotonic() < end:
                page.wait_for_timeout(1000)
                studio = "window.xabslStudio"
                samples.append(page.evaluate(f"({{...{studio}.stats, fps: {studio}.connection.framesPerSecond}})"))
            browser.close()
        server.should_exit = True
        draws = sum(s["drawsPerSecond"] for s in samples) / len(samples)
        render = sum(s["renderMs"] for s in samples) / len(samples)
        frames = sum(s["fps"] for s in samples) / len(samples)
        print(f"{OPTIONS} options, {AGENTS} agents, activation path of {depth} nodes")
        print(
            f"frames received: {frames:.1f}/s; UI draws: {draws:.1f}/s; {render:.2f} ms per draw "
            f"(budget at 30 fps: 33 ms, ratio {33.3 / max(render, 0.01):.0f}x)"
        )
    finally:
        shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
