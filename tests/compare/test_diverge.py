"""Divergence of two runs of one seed: the first tick each robot acts differently, and why (issue 28).

The runs differ by one known edit (tests/compare/runs.py): ``approach_ball`` goes ``near`` below
600 mm instead of 900 mm. The first divergence must be that decision, on the robot that first
approached the ball between 600 and 900 mm; the whole tick range before it is checked against an
independent scan of both recordings' ticks.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.compare.runs import EDITED, ORIGINAL, Runs, record_runs, xabsl
from xabsl_studio.engine.compare.diverge import diverge
from xabsl_studio.engine.record import Recording, RecordingError


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Runs]:
    yield record_runs(tmp_path_factory.mktemp("diverge"))


def names(view_agent: Any) -> list[tuple[str, ...]]:
    """A recorded tick's path by names, read through the activation tree (not the module under test)."""
    found: list[tuple[str, ...]] = []

    def walk(nodes: list[Any]) -> None:
        for node in nodes:
            if hasattr(node, "option"):
                found.append((node.option, node.state))
            elif hasattr(node, "behavior"):
                found.append((node.behavior,))
            walk(list(getattr(node, "sub", ())))

    walk(view_agent.tree())
    return found


def first_difference(a: Path, b: Path, agent: str) -> int | None:
    """The brute-force answer: decode every tick of both and compare the trees by names."""
    with Recording(a) as ra, Recording(b) as rb:
        start, stop = max(ra.first, rb.first), min(ra.end, rb.end)
        for va, vb in zip(ra.ticks(start, stop), rb.ticks(start, stop), strict=True):
            assert va.seq == vb.seq
            if names(va.agents[agent]) != names(vb.agents[agent]):
                return va.seq
    return None


def test_the_edit_is_the_first_differing_decision(runs: Runs) -> None:
    with Recording(runs.original) as a, Recording(runs.edited) as b:
        report = diverge(a, b)
    print("\n".join(report.lines()))
    earliest = report.earliest
    assert earliest is not None and earliest.option == "approach_ball"
    assert earliest.why_a is not None and earliest.why_b is not None
    assert (earliest.why_a.decided_in, earliest.why_a.target) == ("far", "near")
    assert (earliest.why_b.decided_in, earliest.why_b.target, earliest.why_b.stay) == ("far", "far", True)
    (cond_a,), (cond_b,) = earliest.why_a.conditions, earliest.why_b.conditions
    assert f"if ({cond_a.text})" == ORIGINAL and f"if ({cond_b.text})" == EDITED
    assert (cond_a.value, cond_b.value) == (True, False)
    # the same distance on both sides: the runs were the same up to this decision
    (left_a,), (left_b,) = (c.left_value for c in cond_a.comparisons), (c.left_value for c in cond_b.comparisons)
    assert left_a == left_b and 600 <= float(left_a) < 900
    assert any("approach_ball.near" in line for line in earliest.path_a)
    assert not any("approach_ball.near" in line for line in earliest.path_b)
    # every robot's divergence is where an independent scan of all ticks finds it
    for agent, found in report.divergences.items():
        assert (found.seq if found else None) == first_difference(runs.original, runs.edited, agent), agent


def test_a_fork_diverges_from_its_original_where_the_edited_run_does(runs: Runs) -> None:
    with Recording(runs.original) as a, Recording(runs.edited) as b, Recording(runs.fork) as f:
        whole, forked = diverge(a, b), diverge(a, f)
    assert (forked.first, forked.seed_a, forked.seed_b) == (runs.fork_at, 4, 4)
    assert whole.earliest is not None and forked.earliest is not None
    assert runs.fork_at < whole.earliest.seq < forked.end
    assert (forked.earliest.agent, forked.earliest.seq) == (whole.earliest.agent, whole.earliest.seq)
    assert forked.earliest.why_b == whole.earliest.why_b


def test_a_run_never_diverges_from_itself_and_a_robot_can_be_chosen(runs: Runs) -> None:
    with Recording(runs.original) as a, Recording(runs.original) as same:
        report = diverge(a, same, ["blue1", "red2"])
        assert report.agents == ("blue1", "red2") and report.earliest is None
        assert set(report.divergences.values()) == {None}
        with pytest.raises(RecordingError, match="no robot 'blue9' in both"):
            diverge(a, same, ["blue9"])


def test_the_command_line_prints_the_report_and_its_json(runs: Runs) -> None:
    text = xabsl("diverge", str(runs.original), str(runs.edited))
    assert text.returncode == 0, text.stderr
    assert "decision of approach_ball" in text.stdout and "≠" in text.stdout
    assert "ball.distance < 600" in text.stdout and "ball.distance < 900" in text.stdout
    done = xabsl("diverge", str(runs.original), str(runs.edited), "--json")
    document = json.loads(done.stdout)
    earliest = document["earliest"]
    assert earliest["option"] == "approach_ball" and earliest["why_a"]["target"] == "near"
    assert document["divergences"][earliest["agent"]]["seq"] == earliest["seq"]
    missing = xabsl("diverge", str(runs.original), "no/such.mcap")
    assert missing.returncode == 2 and missing.stderr.strip() == "xabsl diverge: no such file: no/such.mcap"
    not_mcap = xabsl("diverge", str(runs.original), str(runs.edited_behavior / "agents.xabsl"))
    assert not_mcap.returncode == 2 and "not an MCAP file" in not_mcap.stderr
