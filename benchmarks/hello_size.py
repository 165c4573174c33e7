"""How big is the first message of a session (``hello``), and what does each step of packing it save?

The hello carries every behavior description a browser needs (docs/protocol.md "hello"). For the
soccer example and a team-sized generated set (``tests/navset.py``: 200 options in 15 folders),
prints the structure's size as the descriptions are (plain JSON, the baseline), with the spans
packed, with the derived transitions and calls left to the receiver, and the whole hello as the
studio sends it (compressed above ``packing.COMPRESS_FROM``), each with its ratio to the baseline
and the time the server spends on it once per generation. Goal (issue: performance): at most
500 KB for a team's set.

    .venv/bin/python benchmarks/hello_size.py
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import orjson
from _sets import navset  # benchmarks/ is the script's folder

from xabsl_studio.engine.emit.json import program_to_json
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.server.protocol.packing import compress_structure, derived_calls, derived_transitions, pack_structure
from xabsl_studio.server.protocol.replies import encode_hello

REPO = Path(__file__).resolve().parents[1]
GOAL = 500_000


def measure(name: str, agents: Path) -> None:
    compilation = compile_file(str(agents))
    assert compilation.program is not None, [d.format() for d in compilation.errors[:3]]
    description = program_to_json(compilation.program, compilation.source_text)
    structure = {"programs": {"behavior": description}, "robots": []}
    plain = len(orjson.dumps(structure))
    started = time.perf_counter()
    packed = pack_structure(structure)
    encoded = orjson.dumps(packed)
    packing_ms = 1000 * (time.perf_counter() - started)
    description_packed = packed["programs"]["behavior"]
    kept = [
        {**o, "transitions": derived_transitions(o), "calls": derived_calls(o)} for o in description_packed["options"]
    ]
    spans_only = len(orjson.dumps({**packed, "programs": {"behavior": {**description_packed, "options": kept}}}))
    started = time.perf_counter()
    compressed = compress_structure(encoded)
    compress_ms = 1000 * (time.perf_counter() - started)
    hello = encode_hello("connect", 1, {"example": name}, encoded, b"{}", None, compressed)  # type: ignore[arg-type]
    options = len(description["options"])
    print(f"{name}: {options} options")

    def row(label: str, size: int, note: str = "") -> None:
        print(f"  {label:<44} {size / 1000:9.1f} KB  {size / plain:5.2f} x plain  {note}")

    row("descriptions as they are (baseline)", plain)
    row("spans packed", spans_only)
    row("transitions and calls left to the receiver", len(encoded), f"packing {packing_ms:.0f} ms once")
    verdict = "within" if len(hello) <= GOAL else "OVER"
    how = f"compressed, {compress_ms:.0f} ms once" if compressed is not None else "sent as it is"
    row("the hello as sent", len(hello), f"{how}; {verdict} the 500 KB goal")


def main() -> None:
    measure("soccer", REPO / "examples" / "soccer" / "behavior" / "agents.xabsl")
    with tempfile.TemporaryDirectory() as folder:
        measure("team-sized set (tests/navset.py)", navset().write_set(Path(folder) / "team"))


if __name__ == "__main__":
    main()
