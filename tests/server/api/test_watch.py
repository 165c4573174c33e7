"""Behavior files changed outside the studio (``git checkout``, the user's own editor): picked up.

Within a second of an external change to a file of the include closure the studio reports it
(a ``file`` event ``by: "disk"``), compiles the sets that read it and hot reloads the clean ones
(a ``hello`` with reason ``reload`` whose generation has the file among its changed files, so the
timeline shows its diff, as for a save). A save from the studio itself is not reported back.
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any

import httpx2 as httpx

from tests.server.conftest import LiveServer, WsClient
from xabsl_studio.server.session.files import version_of

OPTION = "options/approach_ball.xabsl"


def external_write(path: Path, text: str) -> None:
    """Write as git does: a new file renamed over the old one."""
    temporary = path.with_name(f".{path.name}.tmp")
    temporary.write_text(text)
    os.replace(temporary, path)


def file_events(client: WsClient, seconds: float) -> list[dict[str, Any]]:
    """Every file event that arrives within ``seconds`` (frames keep coming meanwhile)."""
    events: list[dict[str, Any]] = []
    deadline = time.monotonic() + seconds
    while (left := deadline - time.monotonic()) > 0:
        try:
            message = client.receive(timeout=left)
        except TimeoutError:
            break
        if message["type"] == "event" and message["event"] == "file":
            events.append(message)
    return events


def test_an_external_change_is_compiled_and_hot_reloaded_within_a_second(
    live_demo: LiveServer, client_for: Any, demo_dir: Path
) -> None:
    client = client_for(live_demo)
    client.frame_after()
    path = demo_dir / OPTION
    old = path.read_text()
    new = old.replace("ball.distance", "ball.distance + 1", 1)
    assert new != old
    started = time.monotonic()
    external_write(path, new)
    event = client.until(lambda m: m["type"] == "event" and m["event"] == "file", timeout=5)
    noticed = time.monotonic() - started
    assert event == {
        "type": "event",
        "event": "file",
        "path": OPTION,
        "version": version_of(new.encode()),
        "deleted": False,
        "by": "disk",
    }
    compiled = client.until(lambda m: m["type"] == "event" and m["event"] == "compile", timeout=10)
    assert compiled["ok"] and compiled["program"] == "demo"
    hello = client.wait_hello("reload", timeout=10)
    diff = httpx.get(f"{live_demo.url}/api/generations/{hello['generation']}/diff").json()
    assert [f["path"] for f in diff["files"]] == [OPTION] and "+" in diff["files"][0]["diff"]
    assert noticed < 1.5, f"noticed after {noticed:.2f} s"
    # the studio's own file API now has the new version: a save against it is no conflict
    body = httpx.get(f"{live_demo.url}/api/files/{OPTION}").json()
    assert body["version"] == version_of(new.encode()) and body["text"] == new


def test_a_change_that_does_not_compile_is_reported_and_the_behavior_keeps_running(
    live_demo: LiveServer, client_for: Any, demo_dir: Path
) -> None:
    client = client_for(live_demo)
    client.frame_after()
    path = demo_dir / OPTION
    external_write(path, path.read_text().replace("ball.distance", "ball.distanse", 1))
    client.until(lambda m: m["type"] == "event" and m["event"] == "file" and m["by"] == "disk", timeout=5)
    compiled = client.until(lambda m: m["type"] == "event" and m["event"] == "compile", timeout=10)
    assert not compiled["ok"] and any("distanse" in d["message"] for d in compiled["diagnostics"])
    assert not any(h["reason"] == "reload" for h in client.hellos)
    seq = client.frame_after()["seq"]
    assert client.frame_after(lambda f: f["seq"] > seq + 3)  # still running


def test_a_save_from_the_studio_is_not_reported_back_as_an_external_change(
    live_demo: LiveServer, client_for: Any, demo_dir: Path
) -> None:
    client = client_for(live_demo)
    client.frame_after()
    current = httpx.get(f"{live_demo.url}/api/files/{OPTION}").json()
    text = current["text"].replace("ball.distance", "ball.distance + 2", 1)
    saved = httpx.put(
        f"{live_demo.url}/api/files/{OPTION}", json={"text": text}, headers={"If-Match": f'"{current["version"]}"'}
    )
    assert saved.status_code == 200, saved.text
    events = file_events(client, 2.0)
    assert [e["by"] for e in events] == ["studio"], events


def test_a_touch_without_a_change_and_files_outside_the_closure_are_not_reported(
    live_demo: LiveServer, client_for: Any, demo_dir: Path
) -> None:
    client = client_for(live_demo)
    client.frame_after()
    path = demo_dir / OPTION
    os.utime(path)  # newer mtime, same bytes
    (demo_dir / "notes.xabsl").write_text("/* not included by the agents file */\n")
    assert file_events(client, 1.5) == []
