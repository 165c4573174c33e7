"""Input functions with enum arguments (the errands robot's facts), against the raw reads."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from xabsl_studio.engine.query import query_recording
from xabsl_studio.engine.record import Recording

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def errands(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("errands") / "errands.mcap"
    command = [sys.executable, "-m", "xabsl_studio.engine.cli", "run", "examples/errands", "--duration", "60"]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    subprocess.run([*command, "--record", str(path)], cwd=ROOT, env=env, check=True, capture_output=True)
    return path


@pytest.mark.parametrize("location", ["location.a", "location.b", "location.c"])
def test_a_fact_with_an_enum_argument_is_what_the_decision_got(errands: Path, location: str) -> None:
    true, unknown = set(), 0
    with Recording(errands) as recording:
        for view in recording.ticks():
            agent = view.agents["robot"]
            description = agent.program.description
            ident = next(s["id"] for s in description["inputs"] if s["name"] == "fact.at_robot")
            host = {e: int(v) for v, e in agent.program.read_enums()["location"].items()}[location]
            results = {e[-1] for e in agent.reads or [] if isinstance(e, list) and e[:2] == [ident, host]}
            if len(results) == 1:
                if results.pop() is True:
                    true.add(view.seq)
            else:
                unknown += 1
    result = query_recording(errands, f"fact.at_robot(loc = {location})")
    matched = {s for i in result.intervals for s in range(i.first_seq, i.last_seq + 1)}
    assert matched == true
    assert result.unknown == unknown
    assert result.ticks - result.unknown > 0  # the decisions asked about it in some ticks
