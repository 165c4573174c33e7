"""``xabsl attach`` on a team of robot processes, in headless chromium.

The robots are ``examples/attach/team.py`` (each robot its own process and port, publishing
through the host library); the studio is the real ``xabsl attach`` command line. The UI lists
the hosts and who holds their control, forces an option on one robot through the tester, shows a
killed robot's host as gone (its chip, its robot, a mark on the timeline) and as attached again
when the robot comes back; a host added with Connect… joins the session.
"""

from __future__ import annotations

import json
import socket
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.e2e.conftest import CHROMIUM, REPO, WEB_DIST, free_port, screenshot, watched_tab

STUDIO = "window.xabslStudio"
ROBOTS = 3


def free_ports(count: int) -> int:
    """The first of ``count`` consecutive free loopback ports."""
    for _ in range(50):
        base = free_port()
        sockets = []
        try:
            for port in range(base, base + count):
                s = socket.socket()
                sockets.append(s)
                s.bind(("127.0.0.1", port))
            return base
        except OSError:
            continue
        finally:
            for s in sockets:
                s.close()
    raise RuntimeError("no consecutive free ports")


def robot(name: str, port: int) -> subprocess.Popen[bytes]:
    command = [sys.executable, "-m", "xabsl_studio.examples.attach.robot", "--name", name, "--port", str(port)]
    return subprocess.Popen([*command, "--hz", "50"], stdout=subprocess.DEVNULL, cwd=REPO)


def get(url: str) -> Any:
    with urllib.request.urlopen(url, timeout=10) as response:
        body = response.read()
    return [json.loads(x) for x in body.splitlines()] if "/api/log" in url else json.loads(body)


@pytest.fixture(scope="module")
def team(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, Any]]:
    """Three robot processes (team.py) and ``xabsl attach`` on them; their pids, ports and the studio's URL."""
    if not CHROMIUM.exists() or not (WEB_DIST / "index.html").is_file():
        pytest.fail("chromium and the built UI are needed: `make test` provides both")
    root = tmp_path_factory.mktemp("attach")
    base = free_ports(ROBOTS + 1)  # the last one for Connect…
    team = subprocess.Popen(
        [sys.executable, "-m", "xabsl_studio.examples.attach.team", "--robots", str(ROBOTS), "--port", str(base)],
        stdout=subprocess.PIPE,
        cwd=REPO,
    )
    assert team.stdout is not None
    pids = {}
    for _ in range(ROBOTS):
        name, _, pid, _, port = team.stdout.readline().decode().split()
        pids[name] = (int(pid), int(port))
    port = free_port()
    xabsl = Path(sys.executable).with_name("xabsl")
    command = [str(xabsl), "attach", *(f"127.0.0.1:{base + i}" for i in range(ROBOTS))]
    command += ["--port", str(port), "--web-dist", str(WEB_DIST), "--record-dir", str(root / "recordings")]
    with (root / "attach.log").open("ab") as log:
        studio = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, cwd=REPO)
    url = f"http://127.0.0.1:{port}/"
    extra: list[subprocess.Popen[bytes]] = []
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                status = get(url + "api/status")
                if all(h["connected"] for h in status["attached"]):
                    break
            except OSError:
                pass
            assert studio.poll() is None and time.monotonic() < deadline, (root / "attach.log").read_text()
            time.sleep(0.2)
        yield {"url": url, "robots": pids, "spare": base + ROBOTS, "extra": extra, "log": root / "attach.log"}
    finally:
        studio.terminate()
        studio.wait(timeout=20)
        team.terminate()
        team.wait(timeout=20)
        team.stdout.close()
        for process in extra:
            process.terminate()
            process.wait(timeout=10)


@pytest.fixture
def tab(browser: Any, team: dict[str, Any]) -> Iterator[Any]:
    with watched_tab(browser) as page:
        page.goto(team["url"])
        page.wait_for_function(f"() => {STUDIO} && {STUDIO}.session.buffer.length > 5", timeout=30000)
        yield page


def test_the_team_is_attached_every_tick_arrives_and_forcing_acts_on_the_next(tab: Any, team: dict[str, Any]) -> None:
    url = team["url"]
    # One chip per host, attached, controlled by this studio.
    tab.locator(".attach-host[data-state='attached']").nth(ROBOTS - 1).wait_for(timeout=20000)
    assert tab.locator(".attach-host").count() == ROBOTS
    assert tab.locator(".attach-host .attach-control").first.inner_text() == "control: this studio"
    assert tab.locator("#connect-host").is_visible()
    # Every tick of every host arrives (no gap in any host's seqs).
    first = {h["address"]: h["received"] for h in get(url + "api/status")["attached"]}
    deadline = time.monotonic() + 30
    status = get(url + "api/status")
    while time.monotonic() < deadline and not all(h["received"] > first[h["address"]] + 30 for h in status["attached"]):
        time.sleep(0.2)
        status = get(url + "api/status")
    hosts = status["attached"]
    assert all(h["received"] > first[h["address"]] + 30 for h in hosts), hosts
    assert all(h["missed"] == 0 for h in hosts), team["log"].read_text()[-3000:]
    # Force search_ball on robot2 from the tester.
    tab.locator(".team-strip .chip[data-robot='1']").click()
    tab.keyboard.press("x")
    tab.select_option("#test-target", "option:search_ball")
    tab.click("#test-run")
    tab.locator(".toast.ok", has_text="search_ball runs as the root").wait_for(timeout=10000)
    at = get(url + "api/status")["seq"]
    tab.wait_for_function(
        "() => document.querySelector('.chip[data-robot=\"1\"]').classList.contains('forced')", timeout=10000
    )
    ticks = [t for t in get(url + "api/log?t0=0") if t["seq"] >= at]
    robot2 = [t["robots"][1] for t in ticks]
    assert robot2 and all(r["path"][0]["option"] == "search_ball" for r in robot2), robot2[:3]
    assert all("forced" not in t["robots"][0] for t in ticks)
    screenshot(tab, "attach")
    tab.click("#test-release")
    tab.wait_for_function(f"() => {STUDIO}.session.robotInView() && {STUDIO}.session.robotInView().forced === null")


def test_a_killed_robot_is_marked_gone_and_reattaches_when_it_comes_back(tab: Any, team: dict[str, Any]) -> None:
    import os
    import signal

    pid, port = team["robots"]["robot3"]
    address = f"127.0.0.1:{port}"
    os.kill(pid, signal.SIGKILL)
    chip = tab.locator(f".attach-host[data-address='{address}']")
    tab.wait_for_function(
        f"() => document.querySelector(\".attach-host[data-address='{address}']\").dataset.state === 'gone'",
        timeout=20000,
    )
    assert "gone" in chip.get_attribute("class")
    tab.locator(".team-strip .chip[data-robot='2'][data-gone='true']").wait_for(timeout=10000)
    marks = "() => JSON.parse(document.querySelector('.timeline-panel canvas').dataset.marks || '[]')"
    tab.wait_for_function(f"() => ({marks})().some(m => m.reason === 'host_gone')", timeout=10000)
    team["extra"].append(robot("robot3", port))
    tab.wait_for_function(
        f"() => document.querySelector(\".attach-host[data-address='{address}']\").dataset.state === 'attached'",
        timeout=30000,
    )
    tab.wait_for_function(f"() => ({marks})().some(m => m.reason === 'host_back')", timeout=10000)
    assert tab.locator(".team-strip .chip[data-robot='2'][data-gone='true']").count() == 0
    screenshot(tab, "attach-reattached")


def test_connect_attaches_another_robot_from_the_dialog(tab: Any, team: dict[str, Any]) -> None:
    port = team["spare"]
    team["extra"].append(robot("robot4", port))
    time.sleep(1.0)
    tab.click("#connect-host")
    tab.fill("#connect-address", "not an address")
    tab.click("#connect-go")
    assert "HOST:PORT" in tab.locator(".connect-problem").inner_text()
    tab.fill("#connect-address", f"127.0.0.1:{port}")
    tab.click("#connect-go")
    tab.locator(".toast.ok", has_text="Attached").wait_for(timeout=15000)
    tab.locator(f".attach-host[data-address='127.0.0.1:{port}'][data-state='attached']").wait_for(timeout=15000)
    tab.wait_for_function(f"() => {STUDIO}.session.robots.some(r => r.name === 'robot4')", timeout=15000)
