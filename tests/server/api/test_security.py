"""Who may talk to the studio: token rules, the Origin scheme and the Host check (issue 18)."""

from __future__ import annotations

import base64
import subprocess
import sys
from pathlib import Path

import orjson
import pytest
from fastapi.testclient import TestClient
from starlette.websockets import WebSocketDisconnect

from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.api.app import create_app
from xabsl_studio.server.api.security import MIN_TOKEN_CHARS, SecurityPolicy, TokenError, new_token
from xabsl_studio.server.session.live import Session

BASE = "http://127.0.0.1"
TOKEN = "k" * MIN_TOKEN_CHARS
SERVE = (sys.executable, "-m", "xabsl_studio.engine.cli", "serve")


def test_a_generated_token_has_at_least_128_bits() -> None:
    token = new_token()
    raw = base64.urlsafe_b64decode(token + "=" * (-len(token) % 4))
    assert len(raw) * 8 >= 128
    assert new_token() != token
    generated = SecurityPolicy.for_host("0.0.0.0", None).token
    assert generated is not None and len(generated) >= MIN_TOKEN_CHARS


@pytest.mark.parametrize("host", ["0.0.0.0", "192.168.1.5", "127.0.0.1", "::1"])
def test_an_empty_token_is_refused_everywhere(host: str) -> None:
    with pytest.raises(TokenError, match="empty"):
        SecurityPolicy.for_host(host, "")
    with pytest.raises(TokenError):
        SecurityPolicy.for_host(host, "   ")


def test_a_short_token_is_refused_off_loopback() -> None:
    with pytest.raises(TokenError, match=f"at least {MIN_TOKEN_CHARS}"):
        SecurityPolicy.for_host("0.0.0.0", "k" * (MIN_TOKEN_CHARS - 1))
    assert SecurityPolicy.for_host("0.0.0.0", TOKEN).token == TOKEN
    # On loopback the Host check already guards; a token there is an extra the user chose.
    assert SecurityPolicy.for_host("127.0.0.1", "t0k").token == "t0k"


@pytest.mark.parametrize("token", ["é" * 30, "a b" * 10, "tab\t" * 8, "x" * 30 + "\n"])
def test_a_token_headers_cannot_carry_is_refused(token: str) -> None:
    with pytest.raises(TokenError, match="printable ASCII"):
        SecurityPolicy.for_host("0.0.0.0", token)


def test_a_policy_cannot_be_made_with_an_empty_token() -> None:
    with pytest.raises(TokenError):
        SecurityPolicy(token="")


def test_an_empty_presented_token_never_passes() -> None:
    policy = SecurityPolicy(token=TOKEN, loopback=False)
    assert not policy.token_ok({"x-xabsl-token": ""}, "")
    assert not policy.token_ok({"authorization": "Bearer "}, "token=")
    assert not policy.token_ok({"x-xabsl-token": TOKEN[:-1]}, "")
    assert not policy.token_ok({"x-xabsl-token": TOKEN + "x"}, "")
    assert policy.token_ok({"x-xabsl-token": TOKEN}, "")
    assert policy.token_ok({}, f"token={TOKEN}")
    assert not policy.token_ok({"x-xabsl-token": "é" * 30}, "token=%ff%fe")


def test_serve_refuses_an_empty_token_at_start(demo_dir: Path) -> None:
    for token in ("", "short"):
        result = subprocess.run(
            [*SERVE, str(demo_dir), "--host", "0.0.0.0", "--port", "0", "--token", token],
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert result.returncode == 2, result.stderr
        assert "token" in result.stderr and "Traceback" not in result.stderr


def test_empty_token_header_gets_nothing_over_http_and_ws(demo_dir: Path) -> None:
    session = Session(BenchExample(demo_dir), seed=2)
    policy = SecurityPolicy.for_host("0.0.0.0", TOKEN)
    with TestClient(create_app(session, policy, web_dist=None), base_url="http://192.168.1.5:8000") as client:
        empty = {"X-Xabsl-Token": ""}
        assert client.get("/api/status", headers=empty).status_code == 401
        assert client.post("/api/command", json={"op": "status"}, headers=empty).status_code == 401
        assert client.get("/api/status?token=", headers={"Authorization": "Bearer "}).status_code == 401
        with pytest.raises(WebSocketDisconnect), client.websocket_connect("/ws?token=", headers=empty) as ws:
            ws.receive_text()
        with client.websocket_connect(f"/ws?token={TOKEN}") as ws:
            assert orjson.loads(ws.receive_text())["type"] == "hello"


def test_origin_scheme_must_match_the_server() -> None:
    policy = SecurityPolicy(token=None)
    host = {"host": "127.0.0.1:8000"}
    assert policy.origin_ok({**host, "origin": "http://127.0.0.1:8000"})
    assert not policy.origin_ok({**host, "origin": "https://127.0.0.1:8000"})
    assert policy.origin_ok({**host, "origin": "https://127.0.0.1:8000"}, scheme="https")
    assert not policy.origin_ok({**host, "origin": "http://127.0.0.1:8000"}, scheme="https")
    assert policy.origin_ok({**host, "origin": "http://127.0.0.1:8000"}, scheme="ws")
    assert not policy.origin_ok({**host, "origin": "https://127.0.0.1:8000"}, scheme="ws")


def test_https_origin_is_refused_by_an_http_server(demo_dir: Path) -> None:
    session = Session(BenchExample(demo_dir), seed=2)
    with TestClient(create_app(session, SecurityPolicy(token=None), web_dist=None), base_url=BASE) as client:
        https = client.post("/api/command", json={"op": "status"}, headers={"Origin": "https://127.0.0.1"})
        assert https.status_code == 403
        same = client.post("/api/command", json={"op": "status"}, headers={"Origin": "http://127.0.0.1"})
        assert same.status_code == 200
        with (
            pytest.raises(WebSocketDisconnect),
            client.websocket_connect("ws://127.0.0.1/ws", headers={"Origin": "https://127.0.0.1"}) as ws,
        ):
            ws.receive_text()


@pytest.mark.parametrize(
    "host",
    [
        "127.0.0.1:evil",
        "127.0.0.1:",
        "localhost:80x",
        "[::1]:evil",
        "[::1]x",
        "127.0.0.1:8000:9000",
        "127.0.0.1 :8000",
        "127.0.0.1.nip.io",
        "evil.example",
        "",
    ],
)
def test_host_check_refuses_junk_ports_and_foreign_names(host: str) -> None:
    assert not SecurityPolicy(token=None).host_ok({"host": host})


@pytest.mark.parametrize("host", ["127.0.0.1", "127.0.0.1:8000", "localhost:8000", "LOCALHOST", "[::1]:8000", "[::1]"])
def test_host_check_accepts_loopback_names(host: str) -> None:
    assert SecurityPolicy(token=None).host_ok({"host": host})
