"""The descriptions a browser gets have their spans packed, and unpack to exactly the plain ones."""

from __future__ import annotations

from pathlib import Path

import orjson
import pytest

from tests.server.conftest import REPO
from xabsl_studio.engine.emit.json import program_to_json
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.server.protocol.packing import pack_structure, unpack_description


@pytest.mark.parametrize("agents", ["examples/soccer/behavior/agents.xabsl", "examples/demo/agents.xabsl"])
def test_packed_descriptions_unpack_to_the_plain_ones_and_are_smaller(agents: str) -> None:
    compilation = compile_file(Path(REPO / agents))
    assert compilation.program is not None
    plain = program_to_json(compilation.program, compilation.source_text)
    structure = {"programs": {"team": plain}, "robots": [{"name": "r1"}]}
    packed = pack_structure(structure)
    assert packed["robots"] == structure["robots"] and structure["programs"]["team"] is plain  # not changed in place
    description = packed["programs"]["team"]
    spans = orjson.dumps(description).count(b'"span":[')
    assert spans > 20 and b'"span":{' not in orjson.dumps(description)
    assert unpack_description(description) == plain
    # the paths are spelled once each: the packed description is far smaller
    assert len(orjson.dumps(description)) < 0.7 * len(orjson.dumps(plain))


def test_a_missing_span_stays_missing() -> None:
    plain = {
        "options": [
            {
                "name": "a",
                "span": None,
                "states": [
                    {"span": {"file": "f", "line": 1, "col": 2, "end_line": 3, "end_col": 4, "start": 5, "end": 6}}
                ],
            }
        ]
    }
    packed = pack_structure({"programs": {"k": plain}, "robots": []})["programs"]["k"]
    assert packed["options"][0]["span"] is None and packed["options"][0]["states"][0]["span"] == [0, 1, 2, 3, 4, 5, 6]
    assert packed["span_files"] == ["f"] and unpack_description(packed) == plain
