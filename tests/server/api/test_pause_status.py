"""The session's paused state is the simulation's as soon as pause or resume is answered.

A paused simulation sends no sample, and the mirrored ``paused`` used to follow samples only:
``/api/status`` and the hello of a new client said "running" while the clock stood (issue 13).
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import orjson
import pytest
from fastapi.testclient import TestClient

from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.api.app import create_app
from xabsl_studio.server.session.live import Session


@pytest.fixture
def api(demo_dir: Path) -> Iterator[TestClient]:
    session = Session(BenchExample(demo_dir), seed=3, speed=5.0)
    with TestClient(create_app(session, web_dist=None), base_url="http://127.0.0.1") as client:
        yield client


def test_status_and_hello_say_paused_while_the_clock_stands(api: TestClient) -> None:
    assert api.get("/api/status").json()["paused"] is False, api.get("/api/status").json()
    assert api.post("/api/command", json={"op": "pause"}).json()["result"] == {"paused": True}
    status = api.get("/api/status").json()
    assert status["paused"] is True, status
    time.sleep(0.3)
    assert api.get("/api/status").json()["t"] == status["t"], "the clock moved while paused"
    with api.websocket_connect("ws://127.0.0.1/ws") as ws:
        hello = orjson.loads(ws.receive_text())
        assert hello["type"] == "hello" and hello["session"]["paused"] is True
    assert api.post("/api/command", json={"op": "resume"}).json()["result"] == {"paused": False}
    assert api.get("/api/status").json()["paused"] is False
