"""``xabsl serve`` as a user starts it: a real subprocess on a free loopback port."""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import httpx2 as httpx

from tests.server.conftest import free_port


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
    finally:
        process.terminate()
        out, _ = process.communicate(timeout=20)
    assert f"http://localhost:{port}/?token=t0k" in out


def test_serve_refuses_a_bad_example(tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "serve", str(tmp_path / "nope")],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 2 and "no such folder" in result.stderr
