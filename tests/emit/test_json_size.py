"""The program description grows linearly with an ``else if`` chain.

Each transition used to repeat the conditions on its leaf's whole path, so a chain of n
``else if`` made n transitions of up to n condition texts: 13 MB of JSON for a team-sized set
(issue 11). The conditions are the decision tree's; the transitions name only their leaf.
"""

from __future__ import annotations

from pathlib import Path

from xabsl_studio.engine.emit.json import dumps, program_to_json
from xabsl_studio.engine.lang import compile_file


def _chain(folder: Path, n: int) -> int:
    """The description's size (bytes) of one option whose state decides through ``n`` conditions."""
    branches = "\n    else ".join(f"if (x > {i}) {{ goto s{i % 3}; }}" for i in range(n))
    states = "\n".join(
        f"  {'initial ' if i == 0 else ''}state s{i} {{\n"
        f"    decision {{\n    {branches}\n    else {{ stay; }}\n    }}\n"
        "    action { b(); }\n  }"
        for i in range(3)
    )
    (folder / "s.xabsl").write_text('namespace s("s") { float input x; }\n', encoding="utf-8")
    (folder / "b.xabsl").write_text('namespace b("b") { behavior b {} }\n', encoding="utf-8")
    (folder / "chain.xabsl").write_text(
        f'include "s.xabsl";\ninclude "b.xabsl";\noption chain {{\n{states}\n}}\n', encoding="utf-8"
    )
    (folder / "agents.xabsl").write_text('include "chain.xabsl";\nagent a("a", chain);\n', encoding="utf-8")
    compilation = compile_file(str(folder / "agents.xabsl"))
    assert compilation.program is not None, compilation.diagnostics
    return len(dumps(program_to_json(compilation.program, compilation.source_text), indent=False))


def test_the_description_grows_linearly_with_an_else_if_chain(tmp_path: Path) -> None:
    short, long = tmp_path / "short", tmp_path / "long"
    short.mkdir()
    long.mkdir()
    ratio = _chain(long, 160) / _chain(short, 40)
    assert 3.5 < ratio < 4.5  # four times the conditions, four times the bytes (it was about 10x)
