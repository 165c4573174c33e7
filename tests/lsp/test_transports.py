"""``xabsl lsp``: the subcommand's registration, and the websocket transport of the standalone server."""

from __future__ import annotations

import argparse
import json
import os
import socket
import subprocess
import sys
import time
import tomllib
from collections.abc import Iterator
from pathlib import Path

import pytest
from websockets.exceptions import InvalidStatus
from websockets.sync.client import ClientConnection, connect

from tests.lsp.client import ROOT
from tests.lsp.wire import WsRpc


def test_the_subcommand_is_registered_through_the_entry_point_group() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert project["project"]["entry-points"]["xabsl.commands"]["lsp"] == "xabsl_studio.lsp.cli:register"
    assert any(d.startswith("pygls") for d in project["project"]["dependencies"])
    from xabsl_studio.lsp.cli import register, run

    parser = argparse.ArgumentParser()
    register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["lsp", "--ws", "--port", "9999", "--agents", "a.xabsl"])
    assert args.func is run and args.ws and args.port == 9999 and args.agents == "a.xabsl"


def test_engine_imports_without_pygls() -> None:
    code = (
        "import sys; sys.modules['pygls'] = None; import xabsl_studio.engine.lang, xabsl_studio.engine.cli; print('ok')"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, cwd=ROOT)
    assert out.stdout.strip() == "ok", out.stderr


def test_websocket_transport() -> None:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    process = subprocess.Popen(
        [sys.executable, "-m", "lsp", "--ws", "--port", str(port)],
        env=env,
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + 30
        while True:
            try:
                ws = connect(f"ws://127.0.0.1:{port}", open_timeout=5)
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.2)
        with ws:
            demo = ROOT / "examples" / "demo"
            ws.send(json.dumps({"jsonrpc": "2.0", "id": 1, "method": "initialize", "params": {"capabilities": {}}}))
            answer = json.loads(ws.recv(timeout=20))
            assert answer["id"] == 1 and answer["result"]["capabilities"]["hoverProvider"]
            play = demo / "options" / "play.xabsl"
            document = {"uri": play.resolve().as_uri(), "languageId": "xabsl", "version": 1, "text": play.read_text()}
            ws.send(
                json.dumps({"jsonrpc": "2.0", "method": "textDocument/didOpen", "params": {"textDocument": document}})
            )
            while True:
                message = json.loads(ws.recv(timeout=20))
                if (
                    message.get("method") == "textDocument/publishDiagnostics"
                    and message["params"]["uri"] == document["uri"]
                ):
                    assert [d for d in message["params"]["diagnostics"] if d["severity"] == 1] == []
                    break
    finally:
        process.kill()
        process.wait()


@pytest.fixture
def ws_server() -> Iterator[int]:
    """``xabsl lsp --ws`` as its own process; its port."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = int(s.getsockname()[1])
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    process = subprocess.Popen(
        [sys.executable, "-m", "lsp", "--ws", "--port", str(port), "--allow-origin", "http://localhost:5173"],
        env=env,
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.monotonic() + 30
        while True:
            try:
                with socket.create_connection(("127.0.0.1", port), timeout=1):
                    break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.2)
        yield port
    finally:
        process.kill()
        process.wait()


def open_ws(port: int, **kwargs: object) -> ClientConnection:
    return connect(f"ws://127.0.0.1:{port}", open_timeout=10, max_size=None, **kwargs)  # type: ignore[arg-type]


def test_websocket_refuses_web_pages_of_other_origins(ws_server: int) -> None:
    # any page open in a browser could connect to a loopback port: only the allowed origin may
    with pytest.raises(InvalidStatus):
        open_ws(ws_server, origin="http://evil.example").close()
    with open_ws(ws_server, origin="http://localhost:5173") as ws:
        assert WsRpc(ws).initialize()["capabilities"]["hoverProvider"]


def test_websocket_connections_have_their_own_server(ws_server: int, tmp_path: Path) -> None:
    # pygls' own transport shared one server: answers went to the last client, one's exit ended all
    demo = ROOT / "examples" / "demo"
    secret = tmp_path / "secret.xabsl"
    secret.write_text('namespace secret("x") {\n  float input secret_input;\n}\n')
    with open_ws(ws_server) as first, open_ws(ws_server) as second:
        a, b = WsRpc(first), WsRpc(second)
        a.initialize(demo.as_uri())
        b.initialize(tmp_path.as_uri())
        play = (demo / "options" / "play.xabsl").as_uri()
        outline = a.request("textDocument/documentSymbol", {"textDocument": {"uri": play}})
        assert [s["name"] for s in outline] == ["play"]
        # each connection's roots are its own workspace's
        refused = a.call("textDocument/documentSymbol", {"textDocument": {"uri": secret.as_uri()}})
        assert "outside the behavior folders" in refused["error"]["message"]
        assert (
            b.request("textDocument/documentSymbol", {"textDocument": {"uri": secret.as_uri()}})[0]["name"] == "secret"
        )
        a.notify("exit", None)
        assert b.request("xabsl/root", None)["uri"] == tmp_path.resolve().as_uri()
