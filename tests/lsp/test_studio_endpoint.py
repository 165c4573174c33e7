"""The studio's websocket ``/lsp``: the same language server, behind the same checks as ``/ws``."""

from __future__ import annotations

import json
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from websockets.exceptions import InvalidStatus
from websockets.sync.client import ClientConnection, connect

from tests.lsp.client import ROOT
from tests.server.conftest import LiveServer
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.api.security import SecurityPolicy
from xabsl_studio.server.session.live import Session


@pytest.fixture
def live(tmp_path: Path) -> Iterator[LiveServer]:
    demo = tmp_path / "demo"
    shutil.copytree(ROOT / "examples" / "demo", demo)
    session = Session(BenchExample(demo), seed=3, speed=5.0)
    with LiveServer(session, SecurityPolicy(token="s3cret")) as server:
        yield server
    session.stop()


class Rpc:
    def __init__(self, ws: ClientConnection) -> None:
        self.ws = ws
        self.next = 0
        self.notifications: list[dict[str, Any]] = []

    def request(self, method: str, params: Any) -> Any:
        self.next += 1
        self.ws.send(json.dumps({"jsonrpc": "2.0", "id": self.next, "method": method, "params": params}))
        while True:
            message = json.loads(self.ws.recv(timeout=20))
            if message.get("id") == self.next and "method" not in message:
                assert "error" not in message, message
                return message.get("result")
            self.notifications.append(message)

    def notify(self, method: str, params: Any) -> None:
        self.ws.send(json.dumps({"jsonrpc": "2.0", "method": method, "params": params}))

    def diagnostics(self, uri: str) -> list[dict[str, Any]]:
        while True:
            for i, m in enumerate(self.notifications):
                if m.get("method") == "textDocument/publishDiagnostics" and m["params"]["uri"] == uri:
                    del self.notifications[: i + 1]
                    return list(m["params"]["diagnostics"])
            self.notifications.append(json.loads(self.ws.recv(timeout=20)))


def test_lsp_endpoint_checks_token_and_origin(live: LiveServer) -> None:
    url = f"ws://127.0.0.1:{live.port}/lsp"
    with pytest.raises(InvalidStatus):
        connect(url, open_timeout=10).close()
    with pytest.raises(InvalidStatus):
        connect(url + "?token=s3cret", origin="http://evil.example", open_timeout=10).close()  # type: ignore[arg-type]


def test_lsp_endpoint_serves_the_behavior_folder(live: LiveServer) -> None:
    with connect(f"ws://127.0.0.1:{live.port}/lsp?token=s3cret", open_timeout=10, max_size=None) as ws:
        rpc = Rpc(ws)
        caps = rpc.request("initialize", {"processId": None, "rootUri": None, "capabilities": {}})["capabilities"]
        assert caps["completionProvider"] and caps["renameProvider"]
        rpc.notify("initialized", {})
        root = rpc.request("xabsl/root", None)["uri"]
        assert root == Path(live.session.example.root).resolve().as_uri()
        uri = root + "/options/play.xabsl"
        text = (Path(live.session.example.root) / "options" / "play.xabsl").read_text()
        broken = text.replace("goto chase;", "goto chasee;", 1)
        rpc.notify(
            "textDocument/didOpen",
            {"textDocument": {"uri": uri, "languageId": "xabsl", "version": 1, "text": broken}},
        )
        assert any(d["code"] == "unknown-state" for d in rpc.diagnostics(uri))
        line = broken.split("\n").index(next(ln for ln in broken.split("\n") if "goto chasee" in ln))
        character = broken.split("\n")[line].index("chasee")
        items = rpc.request(
            "textDocument/completion",
            {"textDocument": {"uri": uri}, "position": {"line": line, "character": character}},
        )["items"]
        assert {"wait", "chase", "search"} == {i["label"] for i in items}
        # 'exit' ends this connection, not the studio
        rpc.notify("exit", None)
    assert live.thread.is_alive()


def test_a_file_larger_than_the_command_limit_opens_over_lsp(live: LiveServer) -> None:
    # A whole file travels in one didOpen; /ws's 64 KiB limit must not cut the editor off.
    with connect(f"ws://127.0.0.1:{live.port}/lsp?token=s3cret", open_timeout=10, max_size=None) as ws:
        rpc = Rpc(ws)
        rpc.request("initialize", {"processId": None, "rootUri": None, "capabilities": {}})
        rpc.notify("initialized", {})
        root = rpc.request("xabsl/root", None)["uri"]
        uri = root + "/options/play.xabsl"
        text = (Path(live.session.example.root) / "options" / "play.xabsl").read_text()
        padded = text.replace("goto chase;", "goto chasee;", 1) + "/* " + "x" * 200_000 + " */\n"
        assert len(padded) > 3 * 64 * 1024
        rpc.notify(
            "textDocument/didOpen",
            {"textDocument": {"uri": uri, "languageId": "xabsl", "version": 1, "text": padded}},
        )
        assert any(d["code"] == "unknown-state" for d in rpc.diagnostics(uri))
