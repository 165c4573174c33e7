"""Websocket abuse (issue 18): junk, wrong shapes, non-finite numbers, oversize, floods, slow readers.

Every abuse runs against a real uvicorn on 127.0.0.1 (:class:`LiveServer`) while a *healthy* client
beside the abusers subscribes at :data:`HEALTHY_RATE` frames/s, asks for ``status`` now and then and
checks each reply. The test asserts that the healthy client keeps its frame rate through the whole
abuse window, that each abuse gets its documented answer (an error reply, or a close with 1003,
1008, 1009 or 1013, or a refused handshake), that the server answers normally afterwards, and that
no log record of uvicorn or ours carries a traceback. Every loop is bounded in count and in time.
"""

from __future__ import annotations

import base64
import contextlib
import dataclasses
import logging
import os
import re
import socket
import struct
import threading
import time
import typing
from collections.abc import Iterator
from typing import Any

import httpx2 as httpx
import orjson
import pytest
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import ClientConnection, connect

from tests.server.conftest import LiveServer, WsClient
from xabsl_studio.server.api.clients import ClientState
from xabsl_studio.server.protocol import commands
from xabsl_studio.server.protocol.limits import MAX_CLIENTS, MAX_MESSAGE_BYTES, MAX_PENDING_CONTROL

#: Frames per second the healthy client asks for.
HEALTHY_RATE = 20.0
#: Share of HEALTHY_RATE the healthy client must get over the abuse window. The server itself
#: schedules every client's frames exactly (``Client.due``); what it cannot control on this loaded
#: 2-core machine (six test runs in parallel, the abusers' own threads in this process) is the
#: scheduler. 0.7 still fails clearly when an abuser blocks the event loop or the simulation for
#: more than a few hundred ms in total, or starves the healthy client's sender.
MIN_SHARE = 0.7
#: The longest gap between two frames of the healthy client (a stall of the loop shows here).
MAX_GAP_S = 2.0

#: Non-finite and out-of-range JSON numbers, as raw text (a JSON encoder would refuse most).
BAD_NUMBERS = ("NaN", "Infinity", "-Infinity", "1e999", "-1e999", "1" + "0" * 400, str(2**64), "-" + str(2**64))

#: Every numeric argument of every command (and of subscribe), with the other arguments it needs.
NUMERIC_ARGS: list[tuple[dict[str, Any], str]] = [
    ({"type": "subscribe"}, "rate"),
    ({"type": "subscribe"}, "robots"),
    ({"type": "command", "op": "status"}, "id"),
    ({"type": "command", "op": "step"}, "ticks"),
    ({"type": "command", "op": "speed"}, "speed"),
    ({"type": "command", "op": "reset"}, "seed"),
    ({"type": "command", "op": "select_agent", "agent": "x"}, "robot"),
    ({"type": "command", "op": "force_option", "option": "x"}, "robot"),
    ({"type": "command", "op": "force_option", "robot": 0}, "option"),
    ({"type": "command", "op": "force_option", "robot": 0, "option": "x"}, "params"),
    ({"type": "command", "op": "force_behavior", "behavior": "kick"}, "robot"),
    ({"type": "command", "op": "force_behavior", "robot": 0}, "behavior"),
    ({"type": "command", "op": "force_behavior", "robot": 0, "behavior": "kick"}, "params"),
    ({"type": "command", "op": "release"}, "robot"),
    ({"type": "command", "op": "seek"}, "seq"),
    ({"type": "command", "op": "fork"}, "seq"),
    ({"type": "command", "op": "override_input", "symbol": "ball.seen", "value": 1}, "robot"),
    ({"type": "command", "op": "override_input", "robot": 0, "value": 1}, "symbol"),
    ({"type": "command", "op": "override_input", "robot": 0, "symbol": "ball.distance"}, "value"),
    ({"type": "command", "op": "release_input"}, "robot"),
    ({"type": "command", "op": "release_input", "robot": 0}, "symbol"),
    ({"type": "command", "op": "reset_agent"}, "robot"),
    ({"type": "command", "op": "explain", "option": "x"}, "robot"),
    ({"type": "command", "op": "explain", "robot": 0}, "option"),
    ({"type": "command", "op": "history"}, "t0"),
    ({"type": "command", "op": "history"}, "t1"),
    ({"type": "command", "op": "history"}, "every"),
    ({"type": "command", "op": "explain", "robot": 0, "option": "x"}, "seq"),
    ({"type": "command", "op": "explain", "robot": 0, "option": "x"}, "why_not"),
    ({"type": "command", "op": "query", "condition": "ball.seen"}, "robot"),
    ({"type": "command", "op": "world_command", "name": "x"}, "args"),
    ({"type": "command", "op": "set_breakpoint", "kind": "leaf", "option": "x"}, "breakpoint"),
    ({"type": "command", "op": "set_breakpoint", "kind": "leaf", "option": "x"}, "leaf"),
    ({"type": "command", "op": "set_breakpoint", "kind": "leaf", "option": "x"}, "robot"),
    ({"type": "command", "op": "remove_breakpoint"}, "breakpoint"),
    ({"type": "command", "op": "enable_breakpoint", "enabled": True}, "breakpoint"),
]

#: Wrong shapes: unknown type/op, wrong argument types, extra and missing arguments.
WRONG_SHAPES: list[dict[str, Any]] = [
    {"type": "teleport"},
    {"type": "command", "op": "fly"},
    {"type": "command"},
    {"op": "status"},
    {"type": None, "op": "status"},
    {"type": "command", "op": ["status"]},
    {"type": "command", "op": "status", "extra": 1},
    {"type": "subscribe", "rate": "30"},
    {"type": "subscribe", "rate": True},
    {"type": "subscribe", "robots": "0"},
    {"type": "subscribe", "robots": [-1]},
    {"type": "subscribe", "robots": [{"a": 1}]},
    {"type": "subscribe", "frames": 1},
    {"type": "resync", "now": True},
    {"type": "command", "op": "step", "ticks": 0},
    {"type": "command", "op": "step", "ticks": 3.5},
    {"type": "command", "op": "step", "ticks": "3"},
    {"type": "command", "op": "speed"},
    {"type": "command", "op": "speed", "speed": "fast"},
    {"type": "command", "op": "speed", "speed": 1000},
    {"type": "command", "op": "reset", "seed": -1},
    {"type": "command", "op": "select_agent"},
    {"type": "command", "op": "select_agent", "robot": 0, "agent": 5},
    {"type": "command", "op": "select_agent", "robot": 99, "agent": "nope"},
    {"type": "command", "op": "force_option", "robot": 0, "option": None},
    {"type": "command", "op": "force_option", "robot": 0, "option": "nope"},
    {"type": "command", "op": "force_option", "robot": 0, "option": 2**31},
    {"type": "command", "op": "force_behavior", "robot": 0, "behavior": "kick", "params": [1]},
    {"type": "command", "op": "force_behavior", "robot": 0, "behavior": "kick", "params": {"x": [1]}},
    {"type": "command", "op": "force_behavior", "robot": 0, "behavior": "kick", "params": {"nope": 1}},
    {"type": "command", "op": "override_input", "robot": 0, "symbol": "ball.seen"},
    {"type": "command", "op": "override_input", "robot": 0, "symbol": "ball.seen", "value": None},
    {"type": "command", "op": "override_input", "robot": 0, "symbol": "ball.seen", "value": {"a": 1}},
    {"type": "command", "op": "override_input", "robot": 0, "symbol": "nope", "value": 1},
    {"type": "command", "op": "override_input", "robot": 0, "symbol": "ball.distance", "value": "far"},
    {"type": "command", "op": "release", "robot": "0"},
    {"type": "command", "op": "release", "robot": False},
    {"type": "command", "op": "explain", "robot": 0},
    {"type": "command", "op": "explain", "robot": 0, "option": "nope"},
    {"type": "command", "op": "history", "t0": -5},
    {"type": "command", "op": "history", "every": 0},
    {"type": "command", "op": "reload", "program": 3},
    {"type": "command", "op": "reload", "program": "nope"},
    {"type": "command", "op": "world_command", "name": "nope"},
    {"type": "command", "op": "world_command", "name": 5},
    {"type": "command", "op": "world_command", "name": "x", "args": [1]},
]

#: Junk text messages (each must get an error reply and leave the connection open).
JUNK_TEXT = [
    "",
    " ",
    "{not json",
    "null",
    "true",
    "17",
    '"status"',
    "[1, 2]",
    "[]",
    "{}",
    '{"type": "command", "op": "status"',
    '{"type": "command", "op": "status"} trailing',
    "\ufeff{}",
    "\x00",
    "\ud7ff\ue000",
    "[" * 65_000,  # as deep as fits in a message (100,000 are oversize: see abuse_oversize)
    "{" * 60_000,
    '{"a":' * 10_000 + "1" + "}" * 10_000,
    "[" * 30_000 + "]" * 30_000,
]


class LogCapture(logging.Handler):
    """Every record of uvicorn's, asyncio's and our loggers, formatted with its traceback."""

    LOGGERS = ("", "uvicorn", "uvicorn.error", "uvicorn.access", "asyncio", "xabsl", "xabsl.server")

    def __init__(self) -> None:
        super().__init__(logging.DEBUG)
        self.lines: list[str] = []
        self.setFormatter(logging.Formatter("%(name)s %(levelname)s %(message)s"))
        self._seen: set[int] = set()

    def emit(self, record: logging.LogRecord) -> None:
        if id(record) in self._seen:  # a record propagates to several of our loggers
            return
        self._seen.add(id(record))
        self.lines.append(self.format(record))

    def problems(self) -> list[str]:
        bad = ("Traceback", "Exception in ASGI application", "RuntimeError", "Task exception was never retrieved")
        return [line for line in self.lines if any(b in line for b in bad)]


@pytest.fixture
def server_log() -> Iterator[LogCapture]:
    handler = LogCapture()
    loggers = [logging.getLogger(name) for name in LogCapture.LOGGERS]
    levels = [logger.level for logger in loggers]
    for logger in loggers:
        logger.addHandler(handler)
        if logger.name in ("xabsl", "xabsl.server"):
            logger.setLevel(logging.DEBUG)
    try:
        yield handler
    finally:
        for logger, level in zip(loggers, levels, strict=True):
            logger.removeHandler(handler)
            logger.setLevel(level)


class Healthy(threading.Thread):
    """A well-behaved client: reads every message, subscribes at HEALTHY_RATE, asks ``status`` every 0.5 s."""

    def __init__(self, server: LiveServer) -> None:
        super().__init__(daemon=True, name="healthy-client")
        self.connection = connect(server.ws_url, max_size=None, open_timeout=10)
        self.client = WsClient(self.connection.__enter__())
        self.stop = threading.Event()
        self.times: list[float] = []
        self.replies_ok = 0
        self.errors: list[str] = []

    def run(self) -> None:
        client = self.client
        try:
            client.send({"type": "subscribe", "rate": HEALTHY_RATE, "id": "sub"})
            asked: dict[int, float] = {}
            ident, next_ask = 0, time.monotonic() + 0.5
            deadline = time.monotonic() + 120  # never outlives a hung test
            while not self.stop.is_set() and time.monotonic() < deadline:
                now = time.monotonic()
                if now >= next_ask:
                    ident += 1
                    asked[ident] = now
                    client.send({"type": "command", "id": ident, "op": "status"})
                    next_ask = now + 0.5
                try:
                    message = client.receive(timeout=0.5)
                except TimeoutError:
                    continue
                if message["type"] == "frame":
                    self.times.append(time.monotonic())
                elif message["type"] == "reply" and isinstance(message["id"], int):
                    if not message["ok"] or "ticks" not in orjson.dumps(message["result"]).decode():
                        self.errors.append(f"bad status reply {message}")
                    elif asked.pop(message["id"], None) is None:
                        self.errors.append(f"a reply to no request {message['id']}")
                    else:
                        self.replies_ok += 1
            late = [i for i, t in asked.items() if time.monotonic() - t > 5.0]
            if late:
                self.errors.append(f"status requests never answered: {late}")
        except Exception as error:  # reported by the test
            self.errors.append(f"healthy client failed: {error!r}")

    def rate(self, t0: float, t1: float) -> tuple[float, float]:
        """Frames/s between t0 and t1, and the longest gap between frames in it."""
        inside = [t for t in self.times if t0 <= t <= t1]
        gaps = [b - a for a, b in zip([t0, *inside], [*inside, t1], strict=True)]
        return len(inside) / (t1 - t0), max(gaps)


def _connect(server: LiveServer, **kwargs: Any) -> ClientConnection:
    return connect(server.ws_url, max_size=None, open_timeout=10, close_timeout=2, **kwargs)


def _close_code(ws: ClientConnection, timeout: float = 10.0) -> int | None:
    """Read (and drop) messages until the server closes; the close code it sent."""
    deadline = time.monotonic() + timeout
    try:
        while time.monotonic() < deadline:
            ws.recv(timeout=max(0.01, deadline - time.monotonic()))
    except ConnectionClosed as closed:
        return closed.rcvd.code if closed.rcvd is not None else None
    raise AssertionError("the server did not close the connection")


def _replies(ws: ClientConnection, count: int, timeout: float = 10.0) -> list[dict[str, Any]]:
    """The next ``count`` replies (frames and hellos in between are dropped)."""
    replies: list[dict[str, Any]] = []
    deadline = time.monotonic() + timeout
    while len(replies) < count:
        message = orjson.loads(ws.recv(timeout=max(0.01, deadline - time.monotonic())))
        if message["type"] == "reply":
            replies.append(message)
    return replies


def _is_json(text: str) -> bool:
    try:
        orjson.loads(text)
    except orjson.JSONDecodeError:
        return False
    return True


def _masked_text(payload: bytes) -> bytes:
    """A client's text frame (masked, as RFC 6455 requires of clients)."""
    mask = os.urandom(4)
    size = len(payload)
    head = bytes([0x81]) + (
        bytes([0x80 | size])
        if size < 126
        else bytes([0x80 | 126]) + struct.pack("!H", size)
        if size < 1 << 16
        else bytes([0x80 | 127]) + struct.pack("!Q", size)
    )
    return head + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(payload))


def _raw_close_code(raw: socket.socket, timeout: float = 10.0) -> int | None:
    """Read a raw connection until the server's close frame; its code (None: the stream ended first)."""
    data = bytearray()
    at = 0
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        while at + 2 <= len(data):  # whole server frames (not masked) read so far
            opcode, size, start = data[at] & 0x0F, data[at + 1] & 0x7F, at + 2
            if size == 126:
                size, start = (
                    (struct.unpack("!H", data[start : start + 2])[0], start + 2)
                    if len(data) >= start + 2
                    else (-1, start)
                )
            elif size == 127:
                size, start = (
                    (struct.unpack("!Q", data[start : start + 8])[0], start + 8)
                    if len(data) >= start + 8
                    else (-1, start)
                )
            if size < 0 or start + size > len(data):
                break
            if opcode == 0x8:
                return int(struct.unpack("!H", data[start : start + 2])[0]) if size >= 2 else None
            at = start + size
        raw.settimeout(max(0.01, deadline - time.monotonic()))
        try:
            chunk = raw.recv(1 << 16)
        except OSError:
            return None
        if not chunk:
            return None
        data += chunk
    raise AssertionError("no close frame in time")


def _raw_websocket(server: LiveServer) -> socket.socket:
    """A websocket on a raw socket with tiny buffers, after the handshake: it reads nothing unless told.

    A websocket library would read (and buffer) every message in a thread of its own.
    """
    raw = _raw_socket(server)
    raw.settimeout(10)
    key = base64.b64encode(os.urandom(16)).decode()
    raw.sendall(
        f"GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\nUpgrade: websocket\r\n"
        f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n".encode()
    )
    response = b""
    while b"\r\n\r\n" not in response and len(response) < 4096:
        response += raw.recv(1)
    assert response.startswith(b"HTTP/1.1 101"), response
    return raw


def _raw_socket(server: LiveServer, rcvbuf: int = 4096) -> socket.socket:
    raw = socket.socket()
    raw.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
    raw.connect(("127.0.0.1", server.port))
    return raw


# -- the abuses --------------------------------------------------------------------------------------


def abuse_junk_and_wrong_shapes(server: LiveServer, seen: dict[str, int]) -> None:
    """Junk text and wrong shapes: one error reply each, and the connection stays open."""
    with _connect(server) as ws:
        ws.send(orjson.dumps({"type": "subscribe", "rate": 1}).decode())
        for text in JUNK_TEXT:
            ws.send(text)
            (reply,) = _replies(ws, 1)
            assert reply["ok"] is False and reply["error"], (text[:40], reply)
            seen["junk"] = seen.get("junk", 0) + 1
        for i, shape in enumerate(WRONG_SHAPES):
            ws.send(orjson.dumps({**shape, "id": f"w{i}"}).decode())
            (reply,) = _replies(ws, 1)
            assert reply["ok"] is False and reply["error"], (shape, reply)
            assert reply["id"] == f"w{i}", (shape, reply)
            assert "internal error" not in reply["error"], (shape, reply)
            seen["wrong shape"] = seen.get("wrong shape", 0) + 1
        ws.send(orjson.dumps({"type": "command", "id": "ok", "op": "status"}).decode())
        assert _replies(ws, 1)[0]["ok"] is True
    # Invalid UTF-8 in a text frame: the websocket layer refuses it (1007), the server stays up.
    with _connect(server) as ws:
        with ws.send_context():  # bypasses the client's own UTF-8 encoding
            ws.protocol.send_text(b"\xff\xfe{}")
        code = _close_code(ws)
        assert code == 1007, code
        seen["close 1007 (bad UTF-8)"] = seen.get("close 1007 (bad UTF-8)", 0) + 1
    with _connect(server) as ws:
        ws.send(b"\x00\x01binary")
        assert _close_code(ws) == 1003
        seen["close 1003 (binary)"] = 1


def abuse_non_finite_numbers(server: LiveServer, seen: dict[str, int]) -> None:
    """Each non-finite or out-of-range number in each numeric argument: an error reply (not internal)."""
    with _connect(server) as ws:
        ws.send(orjson.dumps({"type": "subscribe", "rate": 1}).decode())
        for base, name in NUMERIC_ARGS:
            for number in BAD_NUMBERS:
                if name in ("value", "params") and number.lstrip("-") == str(2**64):
                    continue  # a decimal value may be 2**64 (a finite double)
                if name == "robots":
                    value = f"[{number}]"
                elif name in ("params", "args"):
                    value = f'{{"p": {number}}}'
                else:
                    value = number
                ident = "n" if name == "id" else f'"{name}-{number[:6]}"'
                head = orjson.dumps(base).decode()[:-1]
                text = f'{head}, "{name}": {value}' + ("" if name == "id" else f', "id": {ident}') + "}"
                ws.send(text)
                (reply,) = _replies(ws, 1)
                assert reply["ok"] is False, (text, reply)
                assert "internal error" not in reply["error"], (text, reply)
                if name != "id" and _is_json(text):  # NaN is no JSON: then no id can be read
                    assert reply["id"] == orjson.loads(ident), (text, reply)
                seen["non-finite"] = seen.get("non-finite", 0) + 1
        ws.send(orjson.dumps({"type": "command", "id": "ok", "op": "status"}).decode())
        assert _replies(ws, 1)[0]["ok"] is True


def abuse_oversize(server: LiveServer, seen: dict[str, int]) -> None:
    """Over 64 KiB: close 1009; exactly at the limit: an answer."""
    with _connect(server) as ws:
        padding = MAX_MESSAGE_BYTES - len('{"type":"command","op":"status","id":""}')
        ws.send('{"type":"command","op":"status","id":"' + "x" * padding + '"}')
        assert _replies(ws, 1)[0]["ok"] is True
    for size in (MAX_MESSAGE_BYTES + 1, 100_000, 4 * MAX_MESSAGE_BYTES, 1 << 20):
        with _connect(server) as ws:
            ws.send("[" * size)
            assert _close_code(ws) == 1009
            seen["close 1009 (oversize)"] = seen.get("close 1009 (oversize)", 0) + 1
    # 2 bytes per character: over the limit in bytes, under it in characters.
    with _connect(server) as ws:
        ws.send('"' + "é" * (MAX_MESSAGE_BYTES // 2 + 10) + '"')
        assert _close_code(ws) == 1009
        seen["close 1009 (oversize)"] += 1


def abuse_command_flood(server: LiveServer, seen: dict[str, int]) -> None:
    """Thousands of commands, replies never read: closed with 1008, its queue never over the limit."""
    hub = server.studio.hub
    # A raw socket: a websocket library would read (and buffer) the replies in its own thread.
    before = set(hub.clients)
    raw = _raw_websocket(server)
    try:
        # The id comes back in each reply: 256 of them are more than the socket buffers hold.
        frame = _masked_text(orjson.dumps({"type": "command", "id": "x" * 30_000, "op": "fly"}))
        deadline = time.monotonic() + 10
        while not set(hub.clients) - before and time.monotonic() < deadline:  # accepted, not yet listed
            time.sleep(0.01)
        (flooder,) = [c for key, c in hub.clients.items() if key not in before]
        sent, longest = 0, 0
        while sent < 5000 and time.monotonic() < deadline and flooder.state is ClientState.LIVE:
            try:
                raw.sendall(frame)
            except OSError:  # the server closed (and reset) the connection
                break
            sent += 1
            if sent % 50 == 0:
                longest = max(longest, max(hub.stats()["pending_control"].values(), default=0))
        assert longest <= MAX_PENDING_CONTROL, longest
        code = _raw_close_code(raw)
        assert code == 1008, f"closed with {code} after {sent} commands (queue at most {longest})"
        deadline = time.monotonic() + 5
        while flooder.id in hub.clients and time.monotonic() < deadline:
            time.sleep(0.02)
        assert flooder.id not in hub.clients, "the flooder still holds a place after its close"
        seen["close 1008 (command flood)"] = sent
    finally:
        raw.close()


def abuse_subscribe_flood(server: LiveServer, seen: dict[str, int]) -> None:
    """Thousands of subscribes (read): the connection lives and still streams."""
    with _connect(server) as ws:
        for i in range(3000):
            ws.send(orjson.dumps({"type": "subscribe", "rate": 1 + i % 60, "robots": [i % 2]}).decode())
        ws.send(orjson.dumps({"type": "subscribe", "rate": 10, "id": "last"}).decode())
        replies = _replies(ws, 1, timeout=15)
        assert replies[0] == {"type": "reply", "id": "last", "ok": True} or replies[0]["ok"] is True
        seen["subscribes"] = 3001


def abuse_connect_disconnect(server: LiveServer, seen: dict[str, int]) -> None:
    """A few hundred connections opened and closed at once (some before reading the hello)."""
    for i in range(300):
        with _connect(server) as ws:
            if i % 3 == 0:
                ws.recv(timeout=10)
        seen["connect/disconnect"] = seen.get("connect/disconnect", 0) + 1


def abuse_too_many_clients(server: LiveServer, seen: dict[str, int]) -> None:
    """MAX_CLIENTS at once: the next one is closed with 1013; a place frees when one leaves."""
    hub = server.studio.hub
    opened: list[ClientConnection] = []
    deadline = time.monotonic() + 10
    while len(hub.clients) > 1 and time.monotonic() < deadline:  # the earlier abusers leave
        time.sleep(0.05)
    assert len(hub.clients) == 1, "only the healthy client is left"
    with contextlib.ExitStack() as stack:
        for _ in range(MAX_CLIENTS - 1):
            ws = stack.enter_context(_connect(server))
            ws.send(orjson.dumps({"type": "subscribe", "rate": 1}).decode())
            opened.append(ws)
        deadline = time.monotonic() + 10
        while len(hub.clients) < MAX_CLIENTS and time.monotonic() < deadline:  # accepted, not yet listed
            time.sleep(0.01)
        assert len(hub.clients) == MAX_CLIENTS
        for _ in range(5):
            with _connect(server) as extra:
                assert _close_code(extra) == 1013
                seen["close 1013 (too many)"] = seen.get("close 1013 (too many)", 0) + 1
    deadline = time.monotonic() + 10
    while len(hub.clients) >= MAX_CLIENTS and time.monotonic() < deadline:
        time.sleep(0.05)
    with _connect(server) as ws:
        assert orjson.loads(ws.recv(timeout=10))["type"] == "hello"


def abuse_slow_reader(server: LiveServer, seen: dict[str, int]) -> None:
    """A client that never reads at 60 frames/s: frames skipped, its queue and the server's memory bounded."""
    hub = server.studio.hub
    before = set(hub.clients)
    stuck = _raw_websocket(server)
    with contextlib.closing(stuck):
        stuck.sendall(_masked_text(orjson.dumps({"type": "subscribe", "rate": 60})))
        for _ in range(30):  # replies it never reads
            stuck.sendall(_masked_text(orjson.dumps({"type": "command", "id": 1, "op": "status"})))
        deadline = time.monotonic() + 5
        while not set(hub.clients) - before and time.monotonic() < deadline:
            time.sleep(0.01)
        time.sleep(0.5)
        mine = [c for key, c in hub.clients.items() if key not in before]
        assert len(mine) == 1
        client = mine[0]
        seq0, sent0, bytes0 = server.session.ring.latest.seq, client.frames_sent, client.bytes_sent
        time.sleep(3.0)
        ticks = server.session.ring.latest.seq - seq0
        status = httpx.get(server.url + "/api/status", timeout=10).json()
        pending = status["clients"]["pending_control"][client.id]
        assert pending <= 30, pending
        assert client.frames_sent - sent0 < 0.5 * ticks, "frames are not being skipped"
        assert client.bytes_sent - bytes0 < 4 << 20, "bytes keep being queued for a client that does not read"
        seen["slow reader frames sent / ticks"] = client.frames_sent - sent0
        seen["slow reader ticks"] = ticks


def abuse_wrong_origin(server: LiveServer, seen: dict[str, int]) -> None:
    """A foreign, a null, a wrong-scheme and a wrong-port Origin: handshake refused with 403."""
    port = server.port
    for origin in ("http://evil.example", "null", f"https://127.0.0.1:{port}", f"http://127.0.0.1:{port + 1}"):
        with pytest.raises(InvalidStatus) as refused:
            _connect(server, origin=origin)  # type: ignore[arg-type]
        assert refused.value.response.status_code == 403, origin
        seen["403 (origin)"] = seen.get("403 (origin)", 0) + 1


ABUSES = [
    abuse_junk_and_wrong_shapes,
    abuse_non_finite_numbers,
    abuse_oversize,
    abuse_command_flood,
    abuse_subscribe_flood,
    abuse_connect_disconnect,
    abuse_too_many_clients,
    abuse_slow_reader,
    abuse_wrong_origin,
]


def test_every_numeric_argument_is_abused() -> None:
    """NUMERIC_ARGS names every argument of every op that takes a number (a new command joins it)."""
    covered = {(base.get("op", base["type"]), name) for base, name in NUMERIC_ARGS}
    numeric = re.compile(r"\b(int|float|Ref|RobotId|Ms|BreakpointId|CommandValue|dict)\b")
    for union in typing.get_args(commands.Command)[0].__args__:
        op = typing.get_args(typing.get_type_hints(union)["op"])[0]
        for field in dataclasses.fields(union):
            if field.name not in ("type", "op", "id") and numeric.search(str(field.type)):
                assert (op, field.name) in covered, (op, field.name)
    assert ("subscribe", "rate") in covered and ("status", "id") in covered


def test_abuse_leaves_a_healthy_client_its_frame_rate(live_demo: LiveServer, server_log: LogCapture) -> None:
    server = live_demo
    healthy = Healthy(server)
    healthy.start()
    seen: dict[str, int] = {}
    try:
        deadline = time.monotonic() + 10
        while len(healthy.times) < 5 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert len(healthy.times) >= 5, ("the healthy client gets no frames", healthy.errors)
        t0 = time.monotonic()
        durations: dict[str, float] = {}
        for abuse in ABUSES:
            started = time.monotonic()
            abuse(server, seen)
            durations[abuse.__name__] = round(time.monotonic() - started, 1)
            assert healthy.is_alive(), healthy.errors
        t1 = time.monotonic()
    finally:
        healthy.stop.set()
        healthy.join(timeout=10)
        healthy.connection.__exit__(None, None, None)
    rate, gap = healthy.rate(t0, t1)
    print(f"abuse window {t1 - t0:.1f} s {durations}")
    print(
        f"healthy client: {rate:.1f} frames/s of {HEALTHY_RATE}, longest gap {gap:.2f} s, {healthy.replies_ok} replies"
    )
    print(f"seen: {seen}")
    assert not healthy.errors, healthy.errors
    assert rate >= MIN_SHARE * HEALTHY_RATE, f"the healthy client got {rate:.1f} frames/s"
    assert gap <= MAX_GAP_S, f"the healthy client waited {gap:.2f} s for a frame"
    assert healthy.replies_ok >= (t1 - t0) / 0.5 * 0.7, healthy.replies_ok

    # After the abuse: REST and new clients are served normally, every abuser is gone.
    status = httpx.get(server.url + "/api/status", timeout=10)
    assert status.status_code == 200
    deadline = time.monotonic() + 10
    while len(server.studio.hub.clients) > 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert len(server.studio.hub.clients) == 0, server.studio.hub.stats()
    with _connect(server) as ws:
        fresh = WsClient(ws)
        fresh.until(lambda m: m["type"] == "hello")
        fresh.frame_after()
        assert fresh.command("status")["ok"] is True
    assert not server_log.problems(), server_log.problems()[:5]
