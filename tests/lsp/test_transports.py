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

from websockets.sync.client import connect

from tests.lsp.client import ROOT


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
