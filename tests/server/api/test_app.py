"""The REST API and the websocket through FastAPI's TestClient (no network), plus the security middleware."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import orjson
import pytest
from fastapi.testclient import TestClient
from starlette.websockets import WebSocketDisconnect

from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.api.app import create_app
from xabsl_studio.server.api.security import SecurityPolicy
from xabsl_studio.server.protocol.limits import MAX_BODY_BYTES
from xabsl_studio.server.session.live import Session

BASE = "http://127.0.0.1"


@pytest.fixture
def api(demo_dir: Path) -> Iterator[TestClient]:
    session = Session(BenchExample(demo_dir), seed=2, speed=4.0)
    with TestClient(create_app(session, web_dist=None), base_url=BASE) as client:
        yield client


def test_status_structure_and_the_no_ui_page(api: TestClient) -> None:
    status = api.get("/api/status").json()
    assert status["example"] == "demo" and status["version"] == 1 and status["programs"]["demo"]["ok"]
    assert status["ring"]["capacity"] == 120 * 40
    structure = api.get("/api/structure").json()
    assert [a["name"] for a in structure["robots"]] == ["robot1", "robot2"]
    assert structure["programs"]["demo"]["options"][0]["states"]
    page = api.get("/")
    assert page.status_code == 200 and "web/dist" in page.text
    schema = api.get("/api/openapi.json").json()
    assert "/api/files/{path}" in schema["paths"] and "/api/graph/{program}/{option}" in schema["paths"]


def test_files_list_read_and_etag(api: TestClient) -> None:
    listed = {f["path"]: f for f in api.get("/api/files").json()["files"]}
    assert set(listed) >= {"agents.xabsl", "symbols.xabsl", "options/play.xabsl"}
    assert listed["options/play.xabsl"]["programs"] == ["demo"]
    response = api.get("/api/files/options/play.xabsl")
    assert response.headers["etag"] == f'"{listed["options/play.xabsl"]["version"]}"'
    assert response.json()["text"].startswith("/** Root option")


@pytest.mark.parametrize(
    ("url", "status"),
    [
        ("/api/files/..%2Fsecret.xabsl", 400),
        ("/api/files/options/..%2F..%2Fetc%2Fpasswd", 400),
        ("/api/files/%2Fetc%2Fpasswd", 400),
        ("/api/files/options%5C..%5Cplay.xabsl", 400),
        ("/api/files/options/play.xabsl%00", 400),
        ("/api/files/%252e%252e/secret.xabsl", (400, 404)),
        ("/api/files/nope.xabsl", 404),
    ],
)
def test_traversal_over_http_is_refused(api: TestClient, url: str, status: int | tuple[int, ...]) -> None:
    response = api.get(url)
    assert response.status_code in (status if isinstance(status, tuple) else (status,)), response.text
    assert "detail" in response.json()


def test_write_conflict_create_rename_delete_over_http(api: TestClient, demo_dir: Path) -> None:
    current = api.get("/api/files/options/search_ball.xabsl").json()
    text = current["text"].replace("rate = 45", "rate = 30")
    ok = api.put("/api/files/options/search_ball.xabsl", json={"text": text}, headers={"If-Match": current["version"]})
    assert ok.status_code == 200 and ok.json()["reloaded"] == ["demo"], ok.text
    conflict = api.put(
        "/api/files/options/search_ball.xabsl", json={"text": "x"}, headers={"If-Match": current["version"]}
    )
    assert conflict.status_code == 409 and conflict.json()["version"] == ok.json()["version"]
    assert api.put("/api/files/options/search_ball.xabsl", json={"text": "x"}).status_code == 428
    assert api.put("/api/files/options/search_ball.xabsl", json={"txt": "x"}).status_code == 422
    assert (
        api.put(
            "/api/files/options/search_ball.xabsl", content=b"{nope", headers={"content-type": "application/json"}
        ).status_code
        == 422
    )

    created = api.post("/api/files/options/extra.xabsl", json={"text": "/** unused */\n"})
    assert created.status_code == 201 and created.json()["ok"] is True
    assert api.post("/api/files/options/extra.xabsl", json={"text": ""}).status_code == 409
    assert api.post("/api/files/options/extra.sh", json={"text": "rm -rf /"}).status_code == 400
    renamed = api.patch("/api/files/options/extra.xabsl", json={"path": "options/extra2.xabsl"})
    assert renamed.status_code == 200 and (demo_dir / "options" / "extra2.xabsl").is_file()
    assert api.delete("/api/files/options/extra2.xabsl").status_code == 200
    assert not (demo_dir / "options" / "extra2.xabsl").exists()
    # Deleting a file the behavior includes: deleted, but the compile fails and the old one keeps running.
    broken = api.delete("/api/files/options/search_ball.xabsl")
    assert broken.status_code == 422 and broken.json()["saved"] is True
    assert any(d["code"] == "missing-include-file" for d in broken.json()["diagnostics"])
    assert api.get("/api/status").json()["programs"]["demo"]["running"] is True


def test_compile_unsaved_text(api: TestClient) -> None:
    text = api.get("/api/files/options/play.xabsl").json()["text"]
    clean = api.post("/api/compile", json={"path": "options/play.xabsl", "text": text}).json()
    assert clean["ok"] is True and clean["programs"] == ["demo"]
    broken = api.post("/api/compile", json={"path": "options/play.xabsl", "text": text.replace("stay;", "sty;", 1)})
    body = broken.json()
    assert broken.status_code == 200 and body["ok"] is False
    error = next(d for d in body["diagnostics"] if d["severity"] == "error")
    assert error["file"] == "options/play.xabsl" and error["span"]["line"] > 1
    assert api.get("/api/files/options/play.xabsl").json()["text"] == text, "compile never saves"
    assert api.post("/api/compile", json={"path": "../x.xabsl", "text": ""}).status_code == 422, "not a file path"


def test_graphs_are_svg_and_cached(api: TestClient) -> None:
    first = api.get("/api/graph/demo")
    assert first.status_code == 200 and first.headers["content-type"].startswith("image/svg+xml")
    assert 'id="option_' in first.text
    again = api.get("/api/graph/demo", headers={"If-None-Match": first.headers["etag"]})
    assert again.status_code == 304
    machine = api.get("/api/graph/demo/play")
    assert 'id="state_0"' in machine.text
    assert api.get("/api/graph/demo/1").status_code == 200
    assert api.get("/api/graph/demo?agent=searcher").status_code == 200
    studio = api.app.state.studio  # type: ignore[attr-defined]
    renders = studio.graphs.renders
    api.get("/api/graph/demo/play")
    assert studio.graphs.renders == renders, "the second request is served from the cache"
    assert api.get("/api/graph/demo/nope").status_code == 404
    assert api.get("/api/graph/nope").status_code == 404
    assert api.get("/api/graph/demo?agent=nobody").status_code == 404


def test_command_endpoint_and_the_activation_log(api: TestClient) -> None:
    assert api.post("/api/command", json={"op": "pause"}).json()["result"] == {"paused": True}
    stepped = api.post("/api/command", json={"op": "step", "ticks": 30}).json()
    assert stepped["ok"] and stepped["result"]["t"] >= 29 * 25
    bad = api.post("/api/command", json={"op": "warp"})
    assert bad.status_code == 400 and "unknown op" in bad.json()["detail"]
    assert api.post("/api/command", json={"op": "release", "robot": 7}).status_code == 409
    assert api.post("/api/command", json={"op": "history"}).status_code == 409, "history needs the websocket"
    log = api.get("/api/log", params={"t0": 100, "t1": 400})
    assert log.headers["content-type"].startswith("application/x-ndjson")
    lines = [orjson.loads(line) for line in log.text.splitlines()]
    assert [line["t"] for line in lines] == list(range(100, 401, 25))
    first = lines[0]["robots"][0]
    assert first["name"] == "robot1" and first["path"][0]["option"] == "play"
    assert "ball.distance" in first["inputs"] and "activity" in first["outputs"]
    empty = api.get("/api/log", params={"t0": 5, "t1": 1})
    assert empty.status_code == 200 and empty.text == "", "an empty interval has no ticks"
    assert api.get("/api/log", params={"t0": "x"}).status_code == 422


def test_websocket_hello_frames_and_errors(api: TestClient) -> None:
    with api.websocket_connect("ws://127.0.0.1/ws") as ws:
        hello = orjson.loads(ws.receive_text())
        assert hello["type"] == "hello" and hello["version"] == 1 and hello["scene"]["kind"] == "bench"
        frame = orjson.loads(ws.receive_text())
        assert frame["type"] == "frame" and frame["full"] is True and len(frame["robots"]) == 2
        ws.send_text("nope")
        while (message := orjson.loads(ws.receive_text()))["type"] != "reply":
            pass
        assert message["ok"] is False and message["id"] is None
        ws.send_text(orjson.dumps({"type": "command", "id": "a", "op": "status"}).decode())
        while (message := orjson.loads(ws.receive_text()))["type"] != "reply":
            pass
        assert message["id"] == "a" and message["result"]["example"] == "demo"
        ws.send_text("x" * (65 * 1024))
        with pytest.raises(WebSocketDisconnect) as closed:
            while True:
                ws.receive_text()
        assert closed.value.code == 1009


def test_security_middleware(demo_dir: Path) -> None:
    session = Session(BenchExample(demo_dir), seed=2)
    policy = SecurityPolicy(token="s3cret", loopback=True, allowed_origins=frozenset({"http://localhost:5173"}))
    with TestClient(create_app(session, policy, web_dist=None), base_url=BASE) as client:
        assert client.get("/api/status").status_code == 401
        auth = {"Authorization": "Bearer s3cret"}
        assert client.get("/api/status", headers=auth).status_code == 200
        assert client.get("/api/status", headers={"X-Xabsl-Token": "s3cret"}).status_code == 200
        assert client.get("/api/status", headers={"Authorization": "Bearer wrong"}).status_code == 401
        assert client.get("/").status_code == 200, "the UI page itself needs no token"
        # DNS rebinding: a foreign Host name on a loopback server.
        assert client.get("/api/status", headers={**auth, "Host": "evil.example"}).status_code == 403
        # Cross-site writes.
        text = {"text": "x"}
        foreign = client.put(
            "/api/files/options/play.xabsl",
            json=text,
            headers={**auth, "Origin": "http://evil.example", "If-Match": "0"},
        )
        assert foreign.status_code == 403
        dev = client.post("/api/command", json={"op": "status"}, headers={**auth, "Origin": "http://localhost:5173"})
        assert dev.status_code == 200
        same = client.post("/api/command", json={"op": "status"}, headers={**auth, "Origin": "http://127.0.0.1"})
        assert same.status_code == 200
        # Body limits, declared and streamed.
        big = b"x" * (MAX_BODY_BYTES + 1)
        assert client.post("/api/compile", content=big, headers=auth).status_code == 413

        def chunks() -> Iterator[bytes]:
            for _ in range(20):
                yield b"y" * (MAX_BODY_BYTES // 10)

        assert client.post("/api/compile", content=chunks(), headers=auth).status_code == 413
        with pytest.raises(WebSocketDisconnect), client.websocket_connect("ws://127.0.0.1/ws") as ws:
            ws.receive_text()
        with client.websocket_connect("ws://127.0.0.1/ws?token=s3cret") as ws:
            assert orjson.loads(ws.receive_text())["type"] == "hello"
        with (
            pytest.raises(WebSocketDisconnect),
            client.websocket_connect("/ws?token=s3cret", headers={"Origin": "http://evil.example"}) as ws,
        ):
            ws.receive_text()


def test_policy_for_hosts() -> None:
    assert SecurityPolicy.for_host("127.0.0.1", None).token is None
    assert SecurityPolicy.for_host("::1", None).loopback
    generated = SecurityPolicy.for_host("0.0.0.0", None)
    assert generated.token and len(generated.token) >= 24 and not generated.loopback
    assert SecurityPolicy.for_host("192.168.1.5", "given-" + "x" * 16).token == "given-" + "x" * 16
    policy = SecurityPolicy(token=None)
    assert policy.origin_ok({"host": "localhost:8000", "origin": "http://localhost:8000"})
    assert not policy.origin_ok({"host": "localhost:8000", "origin": "http://localhost:8001"})
    assert not policy.origin_ok({"host": "localhost:8000", "origin": "null"})
    assert policy.origin_ok({"host": "localhost", "origin": "http://localhost:80"})
    assert policy.host_ok({"host": "[::1]:8000"}) and not policy.host_ok({"host": "127.0.0.1.nip.io:8000"})


@pytest.mark.parametrize(
    "body",
    [
        b'{"op": "override_input", "robot": 0, "symbol": "ball.distance", "value": ' + b"9" * 400 + b"}",
        b'{"op": "override_input", "robot": 0, "symbol": "ball.distance", "value": 1e999}',
        b'{"op": "override_input", "robot": 0, "symbol": "ball.distance", "value": NaN}',
        b'{"op": "override_input", "robot": 0, "symbol": "ball.distance", "value": Infinity}',
        b'{"op": "override_input", "robot": 0, "symbol": "ball.distance", "value": -Infinity}',
        b'{"op": "force_behavior", "robot": 0, "behavior": "walk", "params": {"speed": ' + b"9" * 400 + b"}}",
        b'{"op": "force_behavior", "robot": 0, "behavior": "walk", "params": {"speed": 1e999}}',
        b'{"op": "force_option", "robot": 0, "option": "approach_ball", "params": {"stop_at": NaN}}',
    ],
)
def test_non_finite_and_out_of_range_numbers_over_rest_are_a_clear_400(api: TestClient, body: bytes) -> None:
    """Issue 18 item 3: was ``internal error: OverflowError`` (a 400 saying nothing) or accepted NaN."""
    answer = api.post("/api/command", content=body, headers={"Content-Type": "application/json"})
    assert answer.status_code == 400, answer.text
    reply = answer.json()
    assert reply["type"] == "reply" and reply["ok"] is False
    assert "internal error" not in reply["error"] and reply["detail"] == reply["error"]
    assert "finite" in reply["error"] or "less than or equal" in reply["error"] or "valid number" in reply["error"]
    status = api.get("/api/status").json()
    assert status["simulation"]["running"], "the simulation is unharmed"


def test_rest_and_websocket_commands_answer_the_same_errors(api: TestClient) -> None:
    body = {"op": "force_option", "robot": 0, "option": "approach_ball", "params": {"stop_at": "far"}, "id": 9}
    rest = api.post("/api/command", json=body).json()
    with api.websocket_connect("ws://127.0.0.1/ws") as ws:
        ws.send_text(orjson.dumps({"type": "command", **body}).decode())
        while (message := orjson.loads(ws.receive_text()))["type"] != "reply":
            pass
    assert rest["ok"] is False and message["ok"] is False and message["id"] == rest["id"] == 9
    assert message["error"] == rest["error"]
    unknown = api.post("/api/command", json={"op": "release", "agent": 0}).json()
    assert "agent: unknown argument" in unknown["error"] and "robot: Field required" in unknown["error"]
