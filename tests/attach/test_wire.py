"""What a studio refuses of a host's messages: reads, enums and sources that break docs/attach.md.

A host is a network peer: every field is checked before the session uses it, and a message that
does not fit closes the connection with the reason (``WireError``), never a crash later.
"""

from __future__ import annotations

from typing import Any

import orjson
import pytest

from xabsl_studio.server.protocol.attach import WireError, decode_from_host
from xabsl_studio.server.protocol.host import Sample

GENERATION: dict[str, Any] = {
    "type": "generation",
    "number": 1,
    "reason": "connect",
    "structure": {"programs": {"behavior": {"options": []}}, "robots": [{"name": "r", "program": "behavior"}]},
    "scene": {},
    "input_ids": [[0]],
    "output_ids": [[]],
    "seed": 0,
    "errors": {},
    "ics": {"behavior": "..."},
}


def sample(reads: Any) -> bytes:
    robot = [[[0, 0, 1, 0, 0, 0, 0, 0, []]], None, [True], [], reads]
    return orjson.dumps(
        {"type": "sample", "seq": 1, "gen": 1, "t": 0, "wall": 0.0, "speed": 1.0, "robots": [robot]}
        | {"scene": {}, "status": {}}
    )


def test_reads_arrive_as_the_host_sent_them_and_null_is_unknown() -> None:
    message = decode_from_host(sample([1, [0, True], ["st", 10.5]]))
    assert isinstance(message, Sample) and orjson.loads(message.reads[0]) == [1, [0, True], ["st", 10.5]]
    unknown = decode_from_host(sample(None))
    assert isinstance(unknown, Sample) and unknown.reads == (b"",)


@pytest.mark.parametrize("reads", ["x", [1.5], [[0, {"deep": 1}]], [True]])
def test_reads_of_another_shape_are_refused(reads: Any) -> None:
    with pytest.raises(WireError, match="read"):
        decode_from_host(sample(reads))


def test_enums_name_host_values_and_must_be_integers() -> None:
    good = decode_from_host(orjson.dumps(GENERATION | {"enums": {"behavior": {"mode": {"7": "mode.walk"}}}}))
    assert good.generation.enums == {"behavior": {"mode": {7: "mode.walk"}}}  # type: ignore[union-attr]
    with pytest.raises(WireError, match="integers"):
        decode_from_host(orjson.dumps(GENERATION | {"enums": {"behavior": {"mode": {"walk": "mode.walk"}}}}))
    with pytest.raises(WireError, match="element"):
        decode_from_host(orjson.dumps(GENERATION | {"enums": {"behavior": {"mode": {"1": 2}}}}))


def test_sources_need_their_agents_file_among_texts() -> None:
    sources = {"behavior": {"agents": "agents.xabsl", "files": {"agents.xabsl": "agent a ('A', root);"}}}
    good = decode_from_host(orjson.dumps(GENERATION | {"sources": sources}))
    assert good.sources == sources  # type: ignore[union-attr]
    for bad in ({"agents": "missing.xabsl", "files": {}}, {"agents": "a", "files": {"a": 1}}, "text"):
        with pytest.raises(WireError, match="sources"):
            decode_from_host(orjson.dumps(GENERATION | {"sources": {"behavior": bad}}))
