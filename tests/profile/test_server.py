"""``GET /api/profile``: the live session's ring buffer profiled in the server process."""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

import orjson
import pytest
from fastapi.testclient import TestClient

from tests.profile.conftest import FILES
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.api.app import create_app
from xabsl_studio.server.session.live import Session


@pytest.fixture
def client(tmp_path: Path) -> Iterator[TestClient]:
    for name, text in FILES.items():
        (tmp_path / name).write_text(text)
    app = create_app(Session(BenchExample(tmp_path / "agents.xabsl"), seed=2, speed=4.0), web_dist=None)
    with TestClient(app, base_url="http://127.0.0.1") as test_client:
        yield test_client


def _wait_ticks(client: TestClient, ticks: int) -> None:
    deadline = time.monotonic() + 30
    while client.app.state.studio.session.ring.latest is None or len(client.app.state.studio.session.ring) < ticks:  # type: ignore[attr-defined]
        assert time.monotonic() < deadline, "the session did not tick"
        time.sleep(0.05)


def test_profile_of_the_ring_matches_the_cycle(client: TestClient) -> None:
    _wait_ticks(client, 130)
    response = client.get("/api/profile")
    assert response.status_code == 200, response.text
    report = orjson.loads(response.content)
    assert report["format"] == "xabsl-profile/1" and set(report["robots"]) == {"robot1", "robot2"}
    ring = client.app.state.studio.session.ring.snapshot()  # type: ignore[attr-defined]
    assert report["ticks"] >= 130 and ring[0].seq <= report["first_seq"] <= ring[0].seq + 2
    for name in ("robot1", "robot2"):
        cycle = report["agents"][name]["options"]["cycle"]
        a, b = cycle["states"]["a"], cycle["states"]["b"]
        # every whole period in the ring: a for 4 ticks, b for 2 (the ends may be cut)
        assert a["longest_ms"] == 100.0 and b["longest_ms"] == 50.0
        assert abs(a["active_ticks"] - 2 * b["active_ticks"]) <= 4
        assert report["agents"][name]["coverage"]["states"]["never"] == ["sub.z"]
    oscillation = next(o for o in report["oscillations"] if o["kind"] == "state" and o["state"] == "a")
    assert oscillation["reentered_seq"] - oscillation["left_seq"] == 2 and oscillation["via"] == ["b"]
    assert oscillation["left_t"] == next(e.t for e in ring if e.seq == oscillation["left_seq"])
    only = orjson.loads(client.get("/api/profile", params={"robot": "robot2", "oscillation_ms": 40}).content)
    assert list(only["agents"]) == ["robot2"] and only["oscillations"] == []


def test_bad_requests(client: TestClient) -> None:
    _wait_ticks(client, 5)
    assert client.get("/api/profile", params={"robot": "nobody"}).status_code == 404
    # the documented range (OpenAPI: exclusiveMinimum 0, maximum one hour) refuses these with 422
    for bad in ("0", "-3", "nan", "inf", "1e999", "x"):
        response = client.get("/api/profile", params={"oscillation_ms": bad})
        assert response.status_code == 422, bad
        assert response.json()["detail"][0]["loc"] == ["query", "oscillation_ms"], response.json()
