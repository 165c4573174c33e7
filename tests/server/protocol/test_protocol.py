"""Parsing client messages: every bad message is a ProtocolError (an error reply), never a crash."""

from __future__ import annotations

import orjson
import pytest

from xabsl_studio.server.protocol.commands import (
    ForceOption,
    OverrideInput,
    Pause,
    Resync,
    Step,
    Subscribe,
    parse_command,
    parse_message,
)
from xabsl_studio.server.protocol.limits import CloseCode
from xabsl_studio.server.protocol.replies import Reply, encode
from xabsl_studio.server.protocol.types import ProtocolError


def test_good_messages() -> None:
    assert parse_message('{"type": "resync"}') == Resync(type="resync")
    assert parse_message('{"type": "subscribe", "rate": 10, "robots": [2, 0]}') == Subscribe(
        type="subscribe", rate=10.0, robots=(2, 0)
    )
    assert parse_message('{"type": "subscribe"}') == Subscribe(type="subscribe", rate=30.0, robots=None)
    command = parse_message(
        b'{"type": "command", "id": 4, "op": "force_option", "robot": 1, "option": "x", "params": {"p": 2.5}}'
    )
    assert command == ForceOption(id=4, op="force_option", robot=1, option="x", params={"p": 2.5})
    assert parse_command(b'{"op": "pause"}') == Pause(op="pause")
    # JSON does not tell 2.0 from 2 (nor does JSON Schema's "integer"): an integral number is an integer.
    assert parse_command(b'{"op": "step", "ticks": 2.0}') == Step(op="step", ticks=2)
    assert parse_command(b'{"op": "override_input", "robot": 0, "symbol": 3, "value": 9007199254740993}') == (
        OverrideInput(op="override_input", robot=0, symbol=3, value=9007199254740993)
    )


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{", "bad JSON"),
        ("[]", "JSON object"),
        ('{"type": "dance"}', "unknown message type"),
        ('{"type": "command", "op": "fly"}', "unknown op"),
        ('{"type": "command"}', "op is required"),
        ('{"type": "command", "op": "pause", "id": [1]}', "id: must be"),
        ('{"type": "command", "op": "pause", "agent": 1}', "agent: unknown argument"),
        ('{"type": "command", "op": "step", "ticks": 0}', "ticks"),
        ('{"type": "command", "op": "step", "ticks": 1.5}', "ticks"),
        ('{"type": "command", "op": "step", "ticks": "2"}', "ticks"),
        ('{"type": "command", "op": "step", "ticks": true}', "ticks"),
        ('{"type": "command", "op": "speed", "speed": "2"}', "speed"),
        ('{"type": "command", "op": "release", "robot": true}', "robot"),
        ('{"type": "command", "op": "release", "robot": -1}', "robot"),
        ('{"type": "command", "op": "override_input", "robot": 0, "symbol": "x"}', "value: Field required"),
        ('{"type": "command", "op": "override_input", "robot": 0, "symbol": "x", "value": NaN}', "value"),
        ('{"type": "command", "op": "override_input", "robot": 0, "symbol": "x", "value": 1e999}', "finite"),
        ('{"type": "command", "op": "force_option", "robot": 0, "option": "o", "params": {"p": [1]}}', "params.p"),
        ('{"type": "subscribe", "rate": 0}', "rate"),
        ('{"type": "subscribe", "rate": true}', "rate"),
        ('{"type": "subscribe", "robots": [1, "a"]}', "robots"),
        ('{"type": "subscribe", "robots": 3}', "robots"),
    ],
)
def test_bad_messages(text: str, message: str) -> None:
    with pytest.raises(ProtocolError, match=message):
        parse_message(text)


@pytest.mark.parametrize("number", ["NaN", "Infinity", "-Infinity", "1e999", "9" * 400, "-" + "9" * 30 + "e400"])
def test_non_finite_and_huge_numbers_are_refused_by_both_edges(number: str) -> None:
    """Issue 18 item 3: the REST body and the websocket message follow one rule."""
    body = '{"op": "override_input", "robot": 0, "symbol": "x", "value": ' + number + "}"
    with pytest.raises(ProtocolError, match="value"):
        parse_command(body)
    with pytest.raises(ProtocolError, match="value"):
        parse_message('{"type": "command", ' + body[1:])
    params = '{"op": "force_behavior", "robot": 0, "behavior": "b", "params": {"p": ' + number + "}}"
    with pytest.raises(ProtocolError, match=r"params\.p"):
        parse_command(params)


def test_reply_and_close_codes() -> None:
    assert orjson.loads(encode(Reply(id=3, ok=True, result={"a": 1}))) == {
        "type": "reply",
        "id": 3,
        "ok": True,
        "result": {"a": 1},
        "error": None,
    }
    assert orjson.loads(encode(Reply(id=None, ok=False, error="no")))["error"] == "no"
    assert CloseCode.MESSAGE_TOO_BIG == 1009 and CloseCode.POLICY_VIOLATION == 1008
