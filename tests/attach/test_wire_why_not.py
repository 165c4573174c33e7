"""``explain_recorded`` on the attach wire carries ``why_not`` (a state id or name), and refuses other types."""

from __future__ import annotations

import orjson
import pytest

from xabsl_studio.server.protocol.attach import FrameReader, WireError, decode_from_studio, encode_from_studio
from xabsl_studio.server.protocol.host import ExplainRecorded, WorkerRequest

TICK = [12, 300, 0, 1, 0, "", 0, 0, 0, 0]  # a 10-item tick as the server sends it


def one_message(data: bytes) -> bytes:
    reader = FrameReader(1 << 20)
    (message,) = reader.feed(data)
    return bytes(message)


@pytest.mark.parametrize("why_not", [None, 2, "near"])
def test_why_not_survives_the_wire(why_not: int | str | None) -> None:
    request = WorkerRequest(7, ExplainRecorded(0, "approach_ball", 3, (tuple(TICK),), why_not=why_not), "client-1")
    decoded = decode_from_studio(one_message(encode_from_studio(request)))
    assert isinstance(decoded, WorkerRequest) and isinstance(decoded.body, ExplainRecorded)
    assert decoded.body.why_not == why_not and decoded.body.option == "approach_ball"


@pytest.mark.parametrize("why_not", [True, 1.5, ["near"], {"state": 1}])
def test_a_why_not_of_another_type_is_refused(why_not: object) -> None:
    command = {
        "op": "explain_recorded",
        "robot": 0,
        "option": "o",
        "generation": 1,
        "ticks": [TICK],
        "why_not": why_not,
    }
    message = orjson.dumps({"type": "request", "id": 1, "owner": None, "command": command})
    with pytest.raises(WireError, match="why_not must be a state id, a name or null"):
        decode_from_studio(message)
