"""A request's answer does not depend on how TCP cut it into segments.

uvicorn's HTTP parser (h11) refuses a request head only while it is incomplete and already over
its buffer limit: the same long request was a 200 when it arrived in one segment and a 400
("Invalid HTTP request received.") when it arrived in two, as on a loaded machine or a real
network. The studio now decides itself (414, 431) below a parser limit set well above its own.
"""

from __future__ import annotations

import socket
import time
from urllib.parse import quote

import pytest

from tests.server.conftest import LiveServer
from xabsl_studio.server.protocol.limits import MAX_HEAD_BYTES, MAX_TARGET_BYTES


def _status(server: LiveServer, request: bytes, cut: int | None) -> int:
    """The status of ``request`` sent whole, or in two segments cut at byte ``cut``."""
    with socket.create_connection(("127.0.0.1", server.port), timeout=30) as connection:
        if cut is None:
            connection.sendall(request)
        else:
            connection.sendall(request[:cut])
            time.sleep(0.2)  # the server reads (and parses) the first part alone
            connection.sendall(request[cut:])
        answer = b""
        while b"\r\n" not in answer:
            chunk = connection.recv(4096)
            if not chunk:
                break
            answer += chunk
    return int(answer.split(b" ", 2)[1])


def _get(target: str, *headers: str) -> bytes:
    lines = [f"GET {target} HTTP/1.1", "Host: 127.0.0.1", *headers, "Connection: close", "", ""]
    return "\r\n".join(lines).encode("latin-1")


@pytest.mark.parametrize("cut", [None, 20_000])
def test_a_long_graph_request_is_answered_alike_in_one_or_two_segments(live_demo: LiveServer, cut: int | None) -> None:
    # the longest `collapse` the route accepts, in 4-byte characters: 48 KB percent-encoded
    collapse = quote("\U0001f600" * 4000)
    assert _status(live_demo, _get(f"/api/graph/demo?collapse={collapse}"), cut) == 200


@pytest.mark.parametrize("cut", [None, 20_000])
def test_a_target_over_the_limit_is_414_however_it_arrives(live_demo: LiveServer, cut: int | None) -> None:
    target = "/api/status?pad=" + "a" * MAX_TARGET_BYTES
    assert _status(live_demo, _get(target), cut) == 414


@pytest.mark.parametrize("cut", [None, 20_000])
def test_headers_over_the_limit_are_431_however_they_arrive(live_demo: LiveServer, cut: int | None) -> None:
    headers = [f"X-Pad-{i}: {'b' * 4000}" for i in range(MAX_HEAD_BYTES // 4000 + 1)]
    assert _status(live_demo, _get("/api/status", *headers), cut) == 431


def test_a_head_just_under_the_limit_is_served(live_demo: LiveServer) -> None:
    headers = [f"X-Pad-{i}: {'c' * 4000}" for i in range(MAX_HEAD_BYTES // 4000 - 2)]
    assert _status(live_demo, _get("/api/status", *headers), 20_000) == 200
