"""The language server under abuse: JSON-RPC junk, hostile URIs, big messages, a connection storm.

Every probe talks to a real server: the studio's ``/lsp`` on a uvicorn on 127.0.0.1
(:class:`~tests.server.conftest.LiveServer`) or ``xabsl lsp`` as its own process on stdio. The
rules (docs/security.md, "The language server"):

* every request gets exactly one JSON-RPC answer, an error for junk (``null`` id when the
  request's own is unusable), and nothing else is answered (notifications, answers);
* no log record and no error reply carries a traceback;
* nothing outside the behavior folder comes back, whatever the URI;
* a message over ``MAX_LSP_MESSAGE_BYTES`` closes with 1009, a binary frame with 1003;
* connections over ``MAX_LSP_CLIENTS`` are closed with 1013 and the worker threads stay at
  ``MAX_LSP_WORKERS`` however many connect.

Counts and times are bounded; the junk is drawn from a fixed seed (``XABSL_FUZZ_EXAMPLES``
scales it, as for the other fuzz tests).
"""

from __future__ import annotations

import base64
import contextlib
import json
import os
import random
import shutil
import socket
import struct
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import ClientConnection, connect

from tests.fuzz.probes import fuzz_settings, splice_odd_value
from tests.lsp.client import ROOT
from tests.lsp.test_confinement import SECRETS, make_outside
from tests.lsp.wire import WsRpc, server_log
from tests.server.conftest import LiveServer
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.api.security import SecurityPolicy
from xabsl_studio.server.protocol.limits import MAX_LSP_CLIENTS, MAX_LSP_MESSAGE_BYTES, MAX_LSP_WORKERS
from xabsl_studio.server.session.live import Session

SCALE = max(1, int(os.environ.get("XABSL_FUZZ_EXAMPLES", "1")))
#: junk messages per run (each waits for its answer)
JUNK = 300 * SCALE


@pytest.fixture(scope="module")
def world(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[LiveServer, Path]]:
    base = tmp_path_factory.mktemp("lsp-fuzz")
    demo = base / "demo"
    shutil.copytree(ROOT / "examples" / "demo", demo)
    outside = make_outside(base)
    (demo / "options" / "link.xabsl").symlink_to(outside / "secret.xabsl")
    os.mkfifo(demo / "options" / "fifo.xabsl")
    session = Session(BenchExample(demo), seed=3, speed=5.0)
    with LiveServer(session, SecurityPolicy(token="s3cret")) as server:
        yield server, outside
    session.stop()


def open_lsp(server: LiveServer, **kwargs: Any) -> ClientConnection:
    return connect(f"ws://127.0.0.1:{server.port}/lsp?token=s3cret", open_timeout=10, max_size=None, **kwargs)


def base_messages(uri: str, text: str) -> list[dict[str, Any]]:
    """One well-formed message of every kind the server handles, on the document ``uri``."""
    doc = {"uri": uri}
    at = {"line": 3, "character": 8}
    span = {"start": at, "end": {"line": 3, "character": 12}}
    requests: list[tuple[str, Any]] = [
        ("textDocument/hover", {"textDocument": doc, "position": at}),
        ("textDocument/completion", {"textDocument": doc, "position": at, "context": {"triggerKind": 1}}),
        ("textDocument/definition", {"textDocument": doc, "position": at}),
        ("textDocument/references", {"textDocument": doc, "position": at, "context": {"includeDeclaration": True}}),
        ("textDocument/prepareRename", {"textDocument": doc, "position": at}),
        ("textDocument/rename", {"textDocument": doc, "position": at, "newName": "renamed"}),
        ("textDocument/documentSymbol", {"textDocument": doc}),
        ("textDocument/semanticTokens/full", {"textDocument": doc}),
        ("textDocument/foldingRange", {"textDocument": doc}),
        ("textDocument/codeAction", {"textDocument": doc, "range": span, "context": {"diagnostics": []}}),
        ("completionItem/resolve", {"label": "x", "data": {"uri": uri, "key": ["option", "play"]}}),
        ("workspace/symbol", {"query": "ball"}),
        ("xabsl/root", None),
        ("no/such/method", {}),
    ]
    messages: list[dict[str, Any]] = [
        {"jsonrpc": "2.0", "id": i + 1000, "method": m, "params": p} for i, (m, p) in enumerate(requests)
    ]
    messages += [
        {
            "jsonrpc": "2.0",
            "method": "textDocument/didChange",
            "params": {"textDocument": {"uri": uri, "version": 9}, "contentChanges": [{"range": span, "text": "x"}]},
        },
        {"jsonrpc": "2.0", "method": "textDocument/didSave", "params": {"textDocument": doc}},
        {"jsonrpc": "2.0", "method": "$/cancelRequest", "params": {"id": 5}},
    ]
    del text
    return messages


def expected_id(raw: str) -> tuple[bool, Any]:
    """Whether ``raw`` must be answered, and with which id (None: ``null``)."""
    try:
        data = json.loads(raw)
    except (ValueError, RecursionError):
        return True, None
    if not isinstance(data, dict):
        return True, None
    if "result" in data or "error" in data:
        return False, None  # an answer: never answered
    if "id" not in data:
        return False, None  # a notification
    ident = data["id"]
    valid = isinstance(ident, str) or (isinstance(ident, int) and not isinstance(ident, bool))
    return True, ident if valid else None


def junk(uri: str, text: str, count: int, seed: int) -> list[str]:
    rnd = random.Random(seed)
    bases = base_messages(uri, text)
    out = [
        "",
        "not json",
        "{",
        "[]",
        "[" * 5000 + "]" * 5000,
        "null",
        "42",
        '"x"',
        "{}",
        '{"jsonrpc": "2.0"}',
        '{"jsonrpc": "2.0", "id": 7}',
        '{"jsonrpc": "1.0", "id": 8, "method": "textDocument/hover", "params": {}}',
        '{"jsonrpc": "2.0", "id": [1], "method": "textDocument/hover", "params": {}}',
        '{"jsonrpc": "2.0", "id": 9, "method": 5, "params": {}}',
        '{"jsonrpc": "2.0", "id": 10, "method": "textDocument/didOpen", "params": {}}',
        '{"jsonrpc": "2.0", "id": 11, "method": "textDocument/hover"}',
        '{"jsonrpc": "2.0", "id": 12, "method": "textDocument/hover", "params": null}',
        '{"jsonrpc": "2.0", "id": 13, "method": "textDocument/hover", "params": [1, 2]}',
        '{"jsonrpc": "2.0", "id": true, "method": "xabsl/root"}',
        '{"jsonrpc": "2.0", "id": 14, "result": null}',
        '{"jsonrpc": "2.0", "id": 15, "error": "boom"}',
    ]
    while len(out) < count:
        out.append(splice_odd_value(rnd.choice(bases), rnd))
    return out


def drive_junk(send: Any, receive: Any, messages: list[str]) -> list[str]:
    """Send each message and wait for its answer; the problems found."""
    problems: list[str] = []
    for raw in messages:
        must, ident = expected_id(raw)
        send(raw)
        # the probe after each message tells "no answer" from "a late answer"
        send(json.dumps({"jsonrpc": "2.0", "id": "probe", "method": "xabsl/root", "params": None}))
        answers: list[dict[str, Any]] = []
        while True:
            message = receive()
            if "method" in message:
                continue  # diagnostics, log messages
            if message.get("id") == "probe":
                break
            answers.append(message)
        got = [a.get("id", "no id") for a in answers]
        if must and got != [ident]:
            problems.append(f"{raw[:120]!r}: answered {got}, expected [{ident!r}]")
        if not must and got:
            problems.append(f"{raw[:120]!r}: answered {got}, expected no answer")
        for a in answers:
            if "traceback" in json.dumps(a.get("error", {})).lower():
                problems.append(f"{raw[:120]!r}: the error carries a traceback")
    return problems


def test_every_junk_request_gets_one_answer_on_lsp(world: tuple[LiveServer, Path]) -> None:
    server, _ = world
    demo = Path(server.session.example.root)
    with server_log() as log, open_lsp(server) as ws:
        rpc = WsRpc(ws)
        rpc.initialize()
        uri = rpc.request("xabsl/root", None)["uri"] + "/options/play.xabsl"
        text = (demo / "options" / "play.xabsl").read_text()
        rpc.open(uri, text)
        rpc.diagnostics(uri)
        problems = drive_junk(ws.send, lambda: rpc.receive(timeout=20), junk(uri, text, JUNK, seed=25))
        assert problems == []
        assert rpc.request("textDocument/documentSymbol", {"textDocument": {"uri": uri}})[0]["name"] == "play"
    assert log.tracebacks() == []


def test_every_junk_request_gets_one_answer_on_stdio(tmp_path: Path) -> None:
    demo = tmp_path / "demo"
    shutil.copytree(ROOT / "examples" / "demo", demo)
    errors = tmp_path / "stderr.txt"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    with errors.open("wb") as stderr:
        process = subprocess.Popen(
            [sys.executable, "-m", "lsp"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=stderr, env=env
        )
    assert process.stdin is not None and process.stdout is not None
    stdin, stdout = process.stdin, process.stdout

    def send(raw: str) -> None:
        data = raw.encode("utf-8", "surrogatepass")
        stdin.write(b"Content-Length: %d\r\n\r\n" % len(data) + data)
        stdin.flush()

    def receive() -> dict[str, Any]:
        length = 0
        while line := stdout.readline().strip():
            name, _, value = line.decode().partition(":")
            if name.lower() == "content-length":
                length = int(value)
        message: dict[str, Any] = json.loads(stdout.read(length))
        return message

    try:
        send(
            json.dumps(
                {
                    "jsonrpc": "2.0",
                    "id": 0,
                    "method": "initialize",
                    "params": {"rootUri": demo.as_uri(), "capabilities": {}},
                }
            )
        )
        assert receive()["id"] == 0
        play = demo / "options" / "play.xabsl"
        uri = play.as_uri()
        document = {"uri": uri, "languageId": "xabsl", "version": 1, "text": play.read_text()}
        send(json.dumps({"jsonrpc": "2.0", "method": "textDocument/didOpen", "params": {"textDocument": document}}))
        problems = drive_junk(send, receive, junk(uri, play.read_text(), JUNK // 2, seed=26))
        assert problems == []
        # a message over the limit is read away and refused; the next one is answered
        stdin.write(b"Content-Length: %d\r\n\r\n" % (MAX_LSP_MESSAGE_BYTES + 1))
        chunk = b" " * (1 << 20)
        for _ in range(MAX_LSP_MESSAGE_BYTES // len(chunk)):
            stdin.write(chunk)
        stdin.write(b" ")
        stdin.flush()
        refused = receive()
        while "method" in refused:  # diagnostics of the junk's edits
            refused = receive()
        assert refused["id"] is None and "over" in refused["error"]["message"]
        send(json.dumps({"jsonrpc": "2.0", "id": 99, "method": "xabsl/root", "params": None}))
        assert receive()["id"] == 99
    finally:
        process.kill()
        process.wait()
        stdin.close()
        stdout.close()
    log = errors.read_text(errors="replace")
    assert "Traceback" not in log, log[-3000:]


# -- hostile URIs ------------------------------------------------------------------------------------------

SEGMENTS = ["..", "%2e%2e", "%2E%2E", ".", "%2e", "", "options", "outside", "%2f..%2f", "linked", "link.xabsl"]
NAMES = [
    "secret.xabsl",
    "%73ecret.xabsl",
    "secret%2exabsl",
    "agents.xabsl",
    "plan.xabsl",
    "link.xabsl",
    "fifo.xabsl",
]


@pytest.fixture(scope="module")
def uri_client(world: tuple[LiveServer, Path]) -> Iterator[tuple[WsRpc, str, Path]]:
    server, outside = world
    with open_lsp(server) as ws:
        rpc = WsRpc(ws)
        rpc.initialize()
        yield rpc, rpc.request("xabsl/root", None)["uri"], outside


@given(
    start=st.sampled_from(["root", "outside", "file://", "file:///"]),
    segments=st.lists(st.sampled_from(SEGMENTS), max_size=6),
    name=st.sampled_from(NAMES),
    method=st.sampled_from(["textDocument/hover", "textDocument/documentSymbol", "textDocument/completion"]),
)
@fuzz_settings(120)
def test_no_uri_reaches_outside_the_folder(
    uri_client: tuple[WsRpc, str, Path], start: str, segments: list[str], name: str, method: str
) -> None:
    rpc, root, outside = uri_client
    head = {"root": root, "outside": outside.as_uri(), "file://": "file://", "file:///": "file://"}[start]
    uri = "/".join([head, *segments, name])
    params: dict[str, Any] = {"textDocument": {"uri": uri}}
    if method != "textDocument/documentSymbol":
        params["position"] = {"line": 3, "character": 16}
    started = time.monotonic()
    answer = rpc.call(method, params, timeout=10)
    assert time.monotonic() - started < 10
    assert not [s for s in SECRETS if s in json.dumps(answer)], (uri, answer)
    assert "traceback" not in json.dumps(answer.get("error", {})).lower()


# -- sizes and frames --------------------------------------------------------------------------------------


def test_big_messages_up_to_the_limit_are_served_and_over_it_closed_with_1009(world: tuple[LiveServer, Path]) -> None:
    server, _ = world
    demo = Path(server.session.example.root)
    with open_lsp(server) as ws:
        rpc = WsRpc(ws)
        rpc.initialize()
        uri = rpc.request("xabsl/root", None)["uri"] + "/options/play.xabsl"
        text = (demo / "options" / "play.xabsl").read_text()
        # 9 MiB: over the old bridge's 8 MiB, which dropped it without a close frame
        rpc.open(uri, text + "/* " + "x" * (9 * 1024 * 1024) + " */\n")
        assert [d for d in rpc.diagnostics(uri, timeout=60) if d["severity"] == 1] == []
    # Over the limit: a frame that announces one byte more is refused by its header, with 1009
    # (sent whole, the client would still be sending when the server drops the connection, and
    # the reset could swallow the close frame: a raw client reads it instead).
    assert close_code_for_a_frame_of(server.port, MAX_LSP_MESSAGE_BYTES + 1) == 1009


def close_code_for_a_frame_of(port: int, length: int) -> int:
    """Open ``/lsp`` as RFC 6455 says, send the header of a text frame of ``length`` bytes and a
    little of it, and return the close code the server answers with."""
    with socket.create_connection(("127.0.0.1", port), timeout=30) as sock:
        key = base64.b64encode(os.urandom(16)).decode()
        sock.sendall(
            (
                f"GET /lsp?token=s3cret HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
                f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n"
            ).encode()
        )
        data = b""
        while b"\r\n\r\n" not in data:
            data += sock.recv(4096)
        head, data = data.split(b"\r\n\r\n", 1)
        assert head.startswith(b"HTTP/1.1 101"), head
        mask = os.urandom(4)
        sock.sendall(bytes([0x81, 0x80 | 127]) + struct.pack("!Q", length) + mask + b"x" * 4096)
        while len(data) < 4:
            chunk = sock.recv(4096)
            if not chunk:
                raise AssertionError(f"closed without a close frame (read {data!r})")
            data += chunk
        assert data[0] == 0x88, f"not a close frame: {data[:8]!r}"
        return int(struct.unpack("!H", data[2:4])[0])


def test_a_binary_frame_closes_with_1003(world: tuple[LiveServer, Path]) -> None:
    server, _ = world
    with open_lsp(server) as ws:
        ws.send(b"\x00\x01")
        with pytest.raises(ConnectionClosed) as closed:
            ws.recv(timeout=10)
        assert closed.value.rcvd is not None and closed.value.rcvd.code == 1003


# -- a connection storm ------------------------------------------------------------------------------------


def lsp_threads() -> int:
    return sum(1 for t in threading.enumerate() if t.name.startswith("xabsl-lsp"))


@pytest.fixture
def own_server(tmp_path: Path) -> Iterator[LiveServer]:
    """A studio of its own: no other test's connection takes a place."""
    demo = tmp_path / "demo"
    shutil.copytree(ROOT / "examples" / "demo", demo)
    session = Session(BenchExample(demo), seed=3, speed=5.0)
    with LiveServer(session, SecurityPolicy(token="s3cret")) as server:
        yield server
    session.stop()


def test_a_connection_storm_is_capped_and_threads_stay_bounded(own_server: LiveServer) -> None:
    server = own_server
    demo = Path(server.session.example.root)
    text = (demo / "options" / "play.xabsl").read_text()
    extra = 8
    refused = 0
    with contextlib.ExitStack() as connections:
        for _ in range(MAX_LSP_CLIENTS + extra):
            ws = connections.enter_context(open_lsp(server))
            rpc = WsRpc(ws)
            try:
                rpc.initialize()
                uri = rpc.request("xabsl/root", None)["uri"] + "/options/play.xabsl"
                rpc.open(uri, text)
            except ConnectionClosed as error:
                assert error.rcvd is not None and error.rcvd.code == 1013
                refused += 1
            assert lsp_threads() <= MAX_LSP_WORKERS
        assert refused == extra
        assert lsp_threads() <= MAX_LSP_WORKERS
    # the places are given back: as many connections are served again
    deadline = time.monotonic() + 10
    while server.studio.lsp_connections and time.monotonic() < deadline:
        time.sleep(0.05)
    with contextlib.ExitStack() as connections:
        for _ in range(MAX_LSP_CLIENTS):
            rpc = WsRpc(connections.enter_context(open_lsp(server)))
            rpc.initialize()
            assert rpc.request("xabsl/root", None)["uri"].startswith("file://")
