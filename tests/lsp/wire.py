"""JSON-RPC over a websocket (the studio's ``/lsp``, ``xabsl lsp --ws``), keeping every message it received.

The confinement and abuse tests look for leaks in *everything* the server sent: answers,
errors and notifications alike, so :class:`WsRpc` keeps the raw text of each frame.
:class:`ServerLog` collects the log records of the language server's process (the studio runs
it in-process) to assert that none carries a traceback.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from websockets.sync.client import ClientConnection


class WsRpc:
    """A JSON-RPC client on one websocket connection: requests, notifications, every frame kept."""

    def __init__(self, ws: ClientConnection) -> None:
        self.ws = ws
        self.next = 0
        self.frames: list[str] = []
        self.pending: list[dict[str, Any]] = []

    def receive(self, timeout: float = 20) -> dict[str, Any]:
        text = self.ws.recv(timeout=timeout)
        assert isinstance(text, str), "the language server sends text frames"
        self.frames.append(text)
        message: dict[str, Any] = json.loads(text)
        return message

    def call(self, method: str, params: Any, timeout: float = 20) -> dict[str, Any]:
        """The whole answer to a request (``result`` or ``error``); notifications meanwhile are kept."""
        self.next += 1
        ident = self.next
        self.ws.send(json.dumps({"jsonrpc": "2.0", "id": ident, "method": method, "params": params}))
        return self.answer(ident, timeout)

    def answer(self, ident: Any, timeout: float = 20) -> dict[str, Any]:
        """The answer with id ``ident`` (received already, or the next one)."""
        for i, message in enumerate(self.pending):
            if message.get("id") == ident and "method" not in message:
                return self.pending.pop(i)
        deadline = time.monotonic() + timeout
        while True:
            message = self.receive(timeout=max(0.01, deadline - time.monotonic()))
            if message.get("id") == ident and "method" not in message:
                return message
            self.pending.append(message)

    def request(self, method: str, params: Any, timeout: float = 20) -> Any:
        answer = self.call(method, params, timeout)
        assert "error" not in answer, answer
        return answer.get("result")

    def notify(self, method: str, params: Any) -> None:
        self.ws.send(json.dumps({"jsonrpc": "2.0", "method": method, "params": params}))

    def initialize(self, root_uri: str | None = None, **options: Any) -> dict[str, Any]:
        result = self.request(
            "initialize",
            {"processId": None, "rootUri": root_uri, "capabilities": {}, "initializationOptions": options or None},
        )
        self.notify("initialized", {})
        return dict(result)

    def open(self, uri: str, text: str) -> None:
        document = {"uri": uri, "languageId": "xabsl", "version": 1, "text": text}
        self.notify("textDocument/didOpen", {"textDocument": document})

    def diagnostics(self, uri: str, timeout: float = 20) -> list[dict[str, Any]]:
        """The next diagnostics published for ``uri``."""
        deadline = time.monotonic() + timeout
        while True:
            for i, m in enumerate(self.pending):
                if m.get("method") == "textDocument/publishDiagnostics" and m["params"]["uri"] == uri:
                    del self.pending[i]
                    return list(m["params"]["diagnostics"])
            self.pending.append(self.receive(timeout=max(0.01, deadline - time.monotonic())))

    def settle(self) -> None:
        """Wait until the server has handled everything sent so far (it answers in order)."""
        self.call("xabsl/root", None)

    def text(self) -> str:
        """Everything received, as one string to search for leaks."""
        return "\n".join(self.frames)


class ServerLog(logging.Handler):
    """Every log record of this process (the studio and its language server), formatted with its traceback."""

    def __init__(self) -> None:
        super().__init__(logging.DEBUG)
        self.lines: list[str] = []
        self.setFormatter(logging.Formatter("%(name)s %(levelname)s %(message)s"))

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append(self.format(record))

    def tracebacks(self) -> list[str]:
        return [line for line in self.lines if "Traceback" in line or 'File "' in line]


@contextmanager
def server_log() -> Iterator[ServerLog]:
    """Collect the records of the root logger and pygls' (they propagate to the root)."""
    handler = ServerLog()
    root = logging.getLogger()
    pygls = logging.getLogger("pygls")
    level = pygls.level
    root.addHandler(handler)
    pygls.setLevel(logging.WARNING)
    try:
        yield handler
    finally:
        root.removeHandler(handler)
        pygls.setLevel(level)
