"""Profile numbers against hand counts of the scripted ``cycle`` behavior (tests/profile/conftest.py).

At 40 Hz (25 ms ticks) ``cycle`` is in ``a`` at seqs 0-3, ``b`` at 4-5, ``a`` at 6-9, ... (its
decision in ``a`` fires at ``state_time`` 100, in ``b`` at 50): 60 ticks are 10 periods. A state
entered by a transition does not decide in its first tick (the decision that ran was the old
state's), so ``a``'s stay leaf fires 4 times in the first period and 3 times in the 9 others.
``sub`` runs while ``cycle`` is in ``a``: ``x`` in its first tick (its decision runs there,
``state_time`` 0: stay), ``y`` in the three others.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.profile.conftest import record
from xabsl_studio.engine.profile import ProfileError, profile
from xabsl_studio.engine.record import Recording


def _profile(path: Path, **options: Any) -> dict[str, Any]:
    with Recording(path) as recording:
        return profile(recording, **options)


def test_times_and_activations(cycle_recording: Path) -> None:
    report = _profile(cycle_recording)
    assert report["ticks"] == 60 and report["tick_ms"] == 25.0
    agent = report["agents"]["robot1"]
    cycle, sub = agent["options"]["cycle"], agent["options"]["sub"]
    assert (cycle["activations"], cycle["active_ticks"], cycle["share"]) == (1, 60, 1.0)
    a, b = cycle["states"]["a"], cycle["states"]["b"]
    assert (a["activations"], a["active_ticks"], a["mean_ms"], a["longest_ms"]) == (10, 40, 100.0, 100.0)
    assert (b["activations"], b["active_ticks"], b["mean_ms"], b["longest_at_seq"]) == (10, 20, 50.0, 4)
    assert (sub["activations"], sub["active_ticks"], sub["mean_ms"]) == (10, 40, 100.0)
    assert sub["states"]["x"]["active_ticks"] == 10 and sub["states"]["y"]["active_ticks"] == 30
    assert "z" not in sub["states"] and "unused" not in agent["options"]


def test_transitions_and_leaves(cycle_recording: Path) -> None:
    options = _profile(cycle_recording)["agents"]["robot1"]["options"]
    assert options["cycle"]["transitions"] == [
        {"from": "a", "to": "b", "leaf": 0, "count": 10},  # seqs 4, 10, ..., 58
        {"from": "b", "to": "a", "leaf": 0, "count": 9},  # seqs 6, 12, ..., 54
    ]
    leaves = {(x["state"], x["leaf"]): x["count"] for x in options["cycle"]["leaves"]}
    assert leaves == {("a", 0): 10, ("a", 1): 4 + 9 * 3, ("b", 0): 9, ("b", 1): 10}
    assert options["sub"]["transitions"] == [{"from": "x", "to": "y", "leaf": 0, "count": 10}]
    leaves = {(x["state"], x["leaf"]): x["count"] for x in options["sub"]["leaves"]}
    assert leaves == {("x", 0): 10, ("x", 1): 10, ("y", 0): 20}


def test_coverage(cycle_recording: Path) -> None:
    report = _profile(cycle_recording)
    # the agent counts against what its root reaches: cycle and sub (5 states, 3 transitions)
    agent = report["agents"]["robot1"]["coverage"]
    assert (agent["options"]["reached"], agent["options"]["total"]) == (2, 2)
    assert (agent["states"]["reached"], agent["states"]["total"], agent["states"]["never"]) == (4, 5, ["sub.z"])
    assert agent["transitions"]["never"] == [{"option": "sub", "from": "z", "to": "x", "leaf": 0}]
    assert (agent["transitions"]["reached"], agent["transitions"]["total"], agent["transitions"]["percent"]) == (
        3,
        4,
        75.0,
    )
    assert (agent["leaves"]["reached"], agent["leaves"]["total"]) == (7, 8)
    # the team counts against the whole behavior set, with the option only the other agent runs
    team = report["teams"]["cycler"]["coverage"]
    assert team["options"] == {"reached": 2, "total": 3, "percent": 66.67, "never": ["unused"]}
    assert team["states"]["never"] == ["sub.z", "unused.only"]
    assert (team["leaves"]["reached"], team["leaves"]["total"]) == (7, 9)


def test_oscillations(cycle_recording: Path) -> None:
    report = _profile(cycle_recording)
    oscillations = report["oscillations"]
    kinds: dict[tuple[str, str, str | None], list[dict[str, Any]]] = {}
    for o in oscillations:
        kinds.setdefault((o["kind"], o["option"], o["state"]), []).append(o)
    # sub left at 4 and back at 6 (50 ms), a left at 4 and back at 6 via b, b left at 6 and back
    # at 10 (100 ms) via a: 9 times each; sub's states restart with each activation: none
    assert {k: len(v) for k, v in kinds.items()} == {
        ("option", "sub", None): 9,
        ("state", "cycle", "a"): 9,
        ("state", "cycle", "b"): 9,
    }
    first_a = kinds[("state", "cycle", "a")][0]
    assert first_a == {
        "agent": "robot1",
        "kind": "state",
        "option": "cycle",
        "state": "a",
        "via": ["b"],
        "left_seq": 4,
        "reentered_seq": 6,
        "left_t": 100,
        "reentered_t": 150,
        "left_ms": 100.0,
        "reentered_ms": 150.0,
        "away_ms": 50.0,
    }
    assert [o["left_seq"] for o in kinds[("state", "cycle", "b")]] == list(range(6, 55, 6))
    assert report["agents"]["robot1"]["oscillations"] == 27
    # away must be shorter than the threshold: 50 ms is not under 50, it is under 51
    assert _profile(cycle_recording, oscillation_ms=50)["oscillations"] == []
    assert len(_profile(cycle_recording, oscillation_ms=51)["oscillations"]) == 18


def test_team_adds_up_its_agents(team_recording: Path) -> None:
    report = _profile(team_recording)
    assert list(report["agents"]) == ["robot1", "robot2"]
    team = report["teams"]["cycler"]
    assert team["agents"] == ["robot1", "robot2"] and team["ticks"] == 120
    assert team["options"]["sub"]["activations"] == 20 and team["options"]["sub"]["share"] == pytest.approx(2 / 3)
    assert team["options"]["cycle"]["transitions"][0]["count"] == 20
    only = _profile(team_recording, agents=["robot2"])
    assert list(only["agents"]) == ["robot2"] and only["teams"]["cycler"]["agents"] == ["robot2"]


def test_activity_intervals(cycle_recording: Path) -> None:
    activity = _profile(cycle_recording)["activity"]["robot1"]
    assert activity["cycle"] == [(0, 60)]
    assert activity["sub"] == [(k, k + 4) for k in range(0, 60, 6)]


def test_bad_requests(cycle_recording: Path) -> None:
    with Recording(cycle_recording) as recording:
        with pytest.raises(ProfileError, match="no agent 'nobody'"):
            profile(recording, ["nobody"])
        for bad in (0, -5, float("nan"), float("inf")):
            with pytest.raises(ProfileError, match="threshold"):
                profile(recording, oscillation_ms=bad)


def test_no_cpu_times_said(cycle_recording: Path) -> None:
    report = _profile(cycle_recording)
    assert report["cpu"] is None and "no CPU times" in report["cpu_note"]


def test_open_intervals_close_at_the_end(tmp_path: Path) -> None:
    """A short recording cut mid-period closes the open intervals at its end."""
    report = _profile(record(tmp_path / "short.mcap", ticks=5))
    cycle = report["agents"]["robot1"]["options"]["cycle"]
    assert cycle["states"]["a"]["active_ticks"] == 4 and cycle["states"]["b"]["active_ticks"] == 1
    assert report["activity"]["robot1"]["sub"] == [(0, 4)]
