"""A small Language Server Protocol client: JSON-RPC with Content-Length framing to ``xabsl lsp``.

Tests and benchmarks/lsp_speed.py talk to the server through this, as an editor would: a
separate process, messages over its stdin/stdout, diagnostics arriving as notifications.
"""

from __future__ import annotations

import json
import os
import queue
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]


def uri(path: str | Path) -> str:
    return Path(os.path.realpath(path)).as_uri()


class LspClient:
    """Starts ``python -m lsp`` (the ``xabsl lsp`` command) and speaks to it."""

    def __init__(self, *args: str) -> None:
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        self.process = subprocess.Popen(
            [sys.executable, "-m", "lsp", *args],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            env=env,
            cwd=str(ROOT),
        )
        self.next_id = 0
        self.responses: dict[int, queue.Queue[dict[str, Any]]] = {}
        self.notifications: queue.Queue[dict[str, Any]] = queue.Queue()
        self.diagnostics: dict[str, list[dict[str, Any]]] = {}
        #: the text of every message the server sent (leak checks search it)
        self.received: list[str] = []
        self.lock = threading.Lock()
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        stream = self.process.stdout
        assert stream is not None
        while True:
            headers: dict[str, str] = {}
            while True:
                line = stream.readline()
                if not line:
                    return
                line = line.strip()
                if not line:
                    break
                name, _, value = line.decode().partition(":")
                headers[name.lower()] = value.strip()
            raw = stream.read(int(headers["content-length"]))
            self.received.append(raw.decode("utf-8", "replace"))
            body = json.loads(raw)
            if "id" in body and "method" not in body:
                with self.lock:
                    box = self.responses.setdefault(body["id"], queue.Queue())
                box.put(body)
            elif "id" in body:  # a request from the server (e.g. registerCapability): accept it
                self._send({"jsonrpc": "2.0", "id": body["id"], "result": None})
            else:
                if body.get("method") == "textDocument/publishDiagnostics":
                    self.diagnostics[body["params"]["uri"]] = body["params"]["diagnostics"]
                self.notifications.put(body)

    def _send(self, message: dict[str, Any]) -> None:
        data = json.dumps(message).encode()
        stdin = self.process.stdin
        assert stdin is not None
        stdin.write(b"Content-Length: %d\r\n\r\n" % len(data) + data)
        stdin.flush()

    def call(self, method: str, params: Any, timeout: float = 30) -> dict[str, Any]:
        """The whole answer to a request: its ``result`` or its ``error``."""
        self.next_id += 1
        ident = self.next_id
        with self.lock:
            box = self.responses.setdefault(ident, queue.Queue())
        self._send({"jsonrpc": "2.0", "id": ident, "method": method, "params": params})
        return box.get(timeout=timeout)

    def request(self, method: str, params: Any, timeout: float = 30) -> Any:
        answer = self.call(method, params, timeout)
        if "error" in answer:
            raise RuntimeError(answer["error"])
        return answer.get("result")

    def notify(self, method: str, params: Any) -> None:
        self._send({"jsonrpc": "2.0", "method": method, "params": params})

    def initialize(
        self, root: str | Path, encodings: list[str] | None = None, file_renames: bool = False, **options: Any
    ) -> Any:
        capabilities: dict[str, Any] = {"textDocument": {"rename": {"prepareSupport": True}}}
        if file_renames:
            capabilities["workspace"] = {
                "workspaceEdit": {"documentChanges": True, "resourceOperations": ["create", "rename", "delete"]}
            }
        if encodings:
            capabilities["general"] = {"positionEncodings": encodings}
        result = self.request(
            "initialize",
            {
                "processId": os.getpid(),
                "rootUri": uri(root),
                "capabilities": capabilities,
                "initializationOptions": options or None,
            },
        )
        self.notify("initialized", {})
        return result

    def wait_diagnostics(self, path: str | Path, timeout: float = 20) -> list[dict[str, Any]]:
        """The next diagnostics published for ``path`` (after the ones seen so far)."""
        target = uri(path)
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"no diagnostics for {path}")
            message = self.notifications.get(timeout=left)
            if message.get("method") == "textDocument/publishDiagnostics" and message["params"]["uri"] == target:
                return list(message["params"]["diagnostics"])

    def drain(self) -> None:
        while True:
            try:
                self.notifications.get_nowait()
            except queue.Empty:
                return

    def open(self, path: str | Path, text: str | None = None) -> str:
        text = Path(path).read_text(encoding="utf-8") if text is None else text
        self.notify(
            "textDocument/didOpen",
            {"textDocument": {"uri": uri(path), "languageId": "xabsl", "version": 1, "text": text}},
        )
        return text

    def change(self, path: str | Path, text: str, version: int = 2) -> None:
        self.notify(
            "textDocument/didChange",
            {"textDocument": {"uri": uri(path), "version": version}, "contentChanges": [{"text": text}]},
        )

    def close(self) -> None:
        try:
            self.request("shutdown", None, timeout=10)
            self.notify("exit", None)
            self.process.wait(timeout=10)
        except Exception:
            self.process.kill()
            self.process.wait()
        for stream in (self.process.stdin, self.process.stdout):
            if stream is not None:
                stream.close()


def position(text: str, needle: str, delta: int = 0, nth: int = 0) -> dict[str, int]:
    """The LSP position of the ``nth`` occurrence of ``needle`` in ``text`` (plus ``delta`` chars)."""
    at = -1
    for _ in range(nth + 1):
        at = text.index(needle, at + 1)
    at += delta
    line = text.count("\n", 0, at)
    return {"line": line, "character": at - (text.rfind("\n", 0, at) + 1)}
