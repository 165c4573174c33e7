"""Every query docs/queries.md shows runs on a soccer match, and the names it documents exist."""

from __future__ import annotations

import re
from pathlib import Path

from xabsl_studio.engine.query import query_recording
from xabsl_studio.engine.query.language import symbol_program
from xabsl_studio.engine.record import Recording

DOC = Path(__file__).resolve().parents[2] / "docs" / "queries.md"


def example_queries() -> list[str]:
    """The second column of the examples table, one query per row."""
    text = DOC.read_text(encoding="utf-8")
    section = text.split("## Examples", 1)[1].split("\n## ", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("| ") and "`" in line]
    queries = []
    for row in rows:
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", row)[1:-1]]
        queries.append(cells[1].strip("`").replace("\\|", "|"))
    return queries


def test_the_examples_run(match: Path) -> None:
    queries = example_queries()
    assert len(queries) >= 10
    matched = 0
    for condition in queries:
        result = query_recording(match, condition)  # raises on a condition with errors
        assert result.ticks > 0, condition
        matched += result.matched > 0
    assert matched >= len(queries) // 2, "most examples should find something in a 40 s match"


def test_the_documented_names_are_offered(match: Path) -> None:
    with Recording(match) as recording:
        description = recording.programs[("behavior", 0)].description
    _program, predicates = symbol_program(description)
    text = DOC.read_text(encoding="utf-8")
    for suffix in ("active", "state", "decided_in", "leaf", "option_time", "state_time"):
        assert f"`O.{suffix}`" in text
        assert f"striker.{suffix}" in predicates
    assert "kick.active" in predicates and "kick.strength" in predicates and "go_to_position.x" in predicates
