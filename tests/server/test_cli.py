"""``xabsl serve`` as a user starts it: a real subprocess on a free loopback port."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import httpx2 as httpx
import orjson
import pytest

from tests.server.conftest import REPO, free_port
from xabsl_studio.engine.record.folder import cache_folder, default_folder


def test_serve_is_registered() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "serve", "--help"], capture_output=True, text=True
    )
    assert result.returncode == 0 and "--token" in result.stdout and "--speed" in result.stdout


def test_serve_runs_an_example_and_prints_the_url(demo_dir: Path) -> None:
    port = free_port()
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "xabsl_studio.engine.cli",
            "serve",
            str(demo_dir),
            "--port",
            str(port),
            "--token",
            "t0k",
            "--speed",
            "2",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        deadline = time.monotonic() + 30
        while True:
            try:
                status = httpx.get(f"http://127.0.0.1:{port}/api/status", headers={"Authorization": "Bearer t0k"})
                break
            except httpx.TransportError:
                assert process.poll() is None, process.stderr.read() if process.stderr else ""
                assert time.monotonic() < deadline, "the server did not come up"
                time.sleep(0.2)
        assert status.status_code == 200 and status.json()["speed"] == 2.0
        assert httpx.get(f"http://127.0.0.1:{port}/api/status").status_code == 401
        # a Foxglove viewer (the spec client of tests/server/api) on the address the server prints
        viewer = [sys.executable, str(REPO / "tests" / "server" / "api" / "foxglove_client.py")]
        viewer += [f"ws://127.0.0.1:{port}/foxglove?token=t0k", "--subprotocol", "foxglove.websocket.v1"]
        viewer += ["--messages", "2", "--wait", "/xabsl/agents/"]
        watched = subprocess.run(viewer, capture_output=True, text=True, timeout=120)
        assert watched.returncode == 0, watched.stderr[-2000:]
        assert orjson.loads(watched.stdout)["invalid"] == []
    finally:
        process.terminate()
        out, _ = process.communicate(timeout=20)
    assert f"http://localhost:{port}/?token=t0k" in out
    assert f"ws://localhost:{port}/foxglove?token=t0k" in out


def test_serve_refuses_a_bad_example(tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "serve", str(tmp_path / "nope")],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 2 and "no such folder" in result.stderr


def test_each_behavior_set_records_into_and_lists_its_own_cache_folder(
    demo_dir: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """One shared cache folder made Recordings… list every other behavior set's recordings."""
    cache = tmp_path / "cache"
    monkeypatch.setenv("XDG_CACHE_HOME", str(cache))
    shared = cache_folder()
    own = default_folder([demo_dir / "agents.xabsl"])
    assert own.parent == shared and own != default_folder([tmp_path / "other" / "agents.xabsl"])
    (shared / "someone-else").mkdir(parents=True)
    (shared / "stray.mcap").write_bytes(b"from before: the folder every set shared")
    (shared / "someone-else" / "theirs.mcap").write_bytes(b"another behavior set's")
    own.mkdir()
    (own / "earlier.mcap").write_bytes(b"this set's, from an earlier session")
    port = free_port()
    command = [sys.executable, "-m", "xabsl_studio.engine.cli", "serve", str(demo_dir), "--port", str(port)]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 30
        while True:
            try:
                status = httpx.get(f"http://127.0.0.1:{port}/api/status").json()
                if status["recording"] and status["recording"]["file"]:
                    break
            except httpx.TransportError:
                assert process.poll() is None, process.stderr.read() if process.stderr else ""
            assert time.monotonic() < deadline, "the server did not come up and record"
            time.sleep(0.2)
        assert Path(status["recording"]["file"]).parent == own.resolve()
        listed = [r["name"] for r in httpx.get(f"http://127.0.0.1:{port}/api/recordings").json()["recordings"]]
        assert listed == ["earlier.mcap"]
    finally:
        process.terminate()
        process.communicate(timeout=20)
