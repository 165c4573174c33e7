"""The descriptions a browser gets have their spans packed, and unpack to exactly the plain ones."""

from __future__ import annotations

from pathlib import Path

import orjson
import pytest

from tests.server.conftest import REPO
from xabsl_studio.engine.emit.json import program_to_json
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.server.protocol.packing import derived_calls, derived_transitions, pack_structure, unpack_description


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


def test_a_team_sized_description_leaves_its_derived_data_off_the_wire(tmp_path: Path) -> None:
    from tests.navset import write_set

    compilation = compile_file(write_set(tmp_path / "team"))
    assert compilation.program is not None and len(compilation.program.options) >= 200
    plain = program_to_json(compilation.program, compilation.source_text)
    packed = pack_structure({"programs": {"team": plain}, "robots": []})["programs"]["team"]
    assert packed["derived"] == ["transitions", "calls"]
    assert all("transitions" not in o and "calls" not in o for o in packed["options"])
    assert unpack_description(packed) == plain
    # a fifth of what the hello carried for such a set (918 KB with the spans packed, 733 KB now)
    options = [{**o, "transitions": derived_transitions(o), "calls": derived_calls(o)} for o in packed["options"]]
    assert len(orjson.dumps(packed)) < 0.85 * len(orjson.dumps({**packed, "options": options}))


def test_a_foreign_description_keeps_transitions_that_differ_from_its_trees() -> None:
    leaf = {"to": "s", "stay": True, "leaf": 0, "span": None}
    option = {"name": "a", "span": None, "states": [{"name": "s", "span": None, "actions": [], "decision": leaf}]}
    plain = {"options": [{**option, "transitions": [], "calls": []}]}  # no transition said, one derivable
    packed = pack_structure({"programs": {"k": plain}, "robots": []})["programs"]["k"]
    assert packed["derived"] == ["calls"] and packed["options"][0]["transitions"] == []
    assert unpack_description(packed) == plain


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


def test_a_large_structure_travels_compressed_and_decodes_to_the_same(tmp_path: Path) -> None:
    from tests.navset import write_set
    from xabsl_studio.server.protocol.packing import COMPRESS_FROM, compress_structure, decode_hello
    from xabsl_studio.server.protocol.replies import encode_hello

    compilation = compile_file(write_set(tmp_path / "team"))
    assert compilation.program is not None
    structure = pack_structure({"programs": {"team": program_to_json(compilation.program)}, "robots": []})
    encoded = orjson.dumps(structure)
    packed = compress_structure(encoded)
    assert packed is not None and len(encoded) > COMPRESS_FROM
    session = {"example": "team"}
    hello = encode_hello("connect", 1, session, encoded, b"{}", None, packed)  # type: ignore[arg-type]
    # the first message of a session with a 200-option set: at most 500 KB (694 KB uncompressed)
    assert len(hello) < 500_000 and len(hello) < 0.2 * len(encoded), len(hello)
    message = orjson.loads(hello)
    assert message["structure"] is None
    assert decode_hello(message)["structure"] == structure
    assert "structure_z" not in decode_hello(message)
    # a small one goes as it is
    assert compress_structure(orjson.dumps({"robots": [], "programs": {}})) is None
    plain = orjson.loads(encode_hello("connect", 1, session, b'{"robots":[]}', b"{}"))  # type: ignore[arg-type]
    assert decode_hello(plain) is plain and "structure_z" not in plain


@pytest.mark.parametrize("packed", ["not base64!", "aGVsbG8=", "bomb"])
def test_a_compressed_structure_that_does_not_decode_is_one_clear_error(
    packed: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    import base64
    import zlib

    from xabsl_studio.server.protocol import packing

    if packed == "bomb":  # inflates past the bound (lowered here: the real one is 256 MiB)
        monkeypatch.setattr(packing, "MAX_STRUCTURE_BYTES", 1024 * 1024)
        packed = base64.b64encode(zlib.compress(b'{"a":"' + b"0" * (4 * 1024 * 1024) + b'"}')).decode()
    with pytest.raises(ValueError, match="structure"):
        packing.decode_hello({"type": "hello", "structure": None, "structure_z": packed})
