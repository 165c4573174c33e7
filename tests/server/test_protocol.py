"""Parsing client messages: every bad message is a ProtocolError (an error reply), never a crash."""

from __future__ import annotations

import orjson
import pytest

from server.protocol import CloseCode, Command, Op, ProtocolError, Resync, Subscribe, parse_message, reply


def test_good_messages() -> None:
    assert parse_message('{"type": "resync"}') == Resync()
    assert parse_message('{"type": "subscribe", "rate": 10, "agents": [2, 0]}') == Subscribe(10.0, frozenset({0, 2}))
    assert parse_message('{"type": "subscribe"}') == Subscribe(30.0, None)
    command = parse_message(b'{"type": "command", "id": 4, "op": "force_option", "agent": 1, "option": "x"}')
    assert command == Command(4, Op.FORCE_OPTION, {"agent": 1, "option": "x"})


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{", "bad JSON"),
        ("[]", "JSON object"),
        ('{"type": "dance"}', "unknown message type"),
        ('{"type": "command", "op": "fly"}', "unknown op"),
        ('{"type": "command", "op": "pause", "id": [1]}', "command id"),
        ('{"type": "subscribe", "rate": 0}', "rate"),
        ('{"type": "subscribe", "rate": true}', "rate"),
        ('{"type": "subscribe", "agents": [1, "a"]}', "agents"),
        ('{"type": "subscribe", "agents": 3}', "agents"),
    ],
)
def test_bad_messages(text: str, message: str) -> None:
    with pytest.raises(ProtocolError, match=message):
        parse_message(text)


def test_reply_and_close_codes() -> None:
    assert orjson.loads(reply(3, True, {"a": 1})) == {"type": "reply", "id": 3, "ok": True, "result": {"a": 1}}
    assert orjson.loads(reply(None, False, error="no")) == {"type": "reply", "id": None, "ok": False, "error": "no"}
    assert CloseCode.MESSAGE_TOO_BIG == 1009 and CloseCode.POLICY_VIOLATION == 1008
