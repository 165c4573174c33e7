"""The profile report: counts of :mod:`xabsl_studio.engine.profile.analysis` as the JSON document of docs/profile.md.

:func:`profile` opens nothing itself: it takes an opened :class:`~xabsl_studio.engine.record.Recording`,
counts it and returns a plain dict (JSON-ready) with per agent and per team (the agents that ran
one program key) the options and states (share, activations, mean and longest duration),
each option's transitions and decision leaves, the oscillations with their ticks and times, and
coverage against the program description recorded in the file.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from xabsl_studio.engine.profile.analysis import AgentCounts, count_recording
from xabsl_studio.engine.record import Recording, RecordingError

__all__ = ["FORMAT", "ProfileError", "build_report", "profile"]

#: ``format`` of the report document (docs/profile.md).
FORMAT = "xabsl-profile/1"
CPU_NOTE = "the recording has no CPU times (the recorder does not measure time per option)"


class ProfileError(RecordingError):
    """The profile cannot be made (an unknown agent, a bad threshold)."""


def _durations(intervals: list[tuple[int, int]], tick_ms: float, ticks: int) -> dict[str, Any]:
    lengths = [stop - start for start, stop in intervals]
    active = sum(lengths)
    longest = max(lengths, default=0)
    at = intervals[lengths.index(longest)][0] if lengths else None
    return {
        "share": round(active / ticks, 6) if ticks else 0.0,
        "activations": len(intervals),
        "active_ticks": active,
        "active_ms": round(active * tick_ms, 3),
        "mean_ms": round(active * tick_ms / len(intervals), 3) if intervals else 0.0,
        "longest_ms": round(longest * tick_ms, 3),
        "longest_at_seq": at,
    }


def _universe(description: dict[str, Any], roots: Iterable[str] | None) -> list[dict[str, Any]]:
    """The options a coverage counts against: reachable from ``roots`` (all if None)."""
    options = description["options"]
    if roots is None:
        return list(options)
    by_name = {o["name"]: o for o in options}
    seen: set[str] = set()
    stack = [r for r in roots if r in by_name]
    while stack:
        name = stack.pop()
        if name in seen:
            continue
        seen.add(name)
        for state in by_name[name]["states"]:
            stack.extend(a["name"] for a in state["actions"] if a["type"] == "option" and a["name"] in by_name)
    return [o for o in options if o["name"] in seen]


def _ratio(reached: int, total: int) -> dict[str, Any]:
    return {"reached": reached, "total": total, "percent": round(100.0 * reached / total, 2) if total else 100.0}


def _coverage(c: AgentCounts, options: list[dict[str, Any]]) -> dict[str, Any]:
    reached_states = set(c.states) | c.decided
    never_options, never_states, never_transitions, never_leaves = [], [], [], []
    n_states = n_transitions = n_leaves = 0
    fired_leaves = {(o, s, leaf) for (o, s, leaf) in c.leaves}
    fired_transitions = {(o, a, leaf) for (o, a, _b, leaf) in c.transitions}
    for option in options:
        name = option["name"]
        if name not in c.options:
            never_options.append(name)
        for state in option["states"]:
            n_states += 1
            if (name, state["name"]) not in reached_states:
                never_states.append(f"{name}.{state['name']}")
        for t in option["transitions"]:
            n_leaves += 1
            if (name, t["from"], t["leaf"]) not in fired_leaves:
                never_leaves.append({"option": name, "state": t["from"], "leaf": t["leaf"], "to": t["to"]})
            if t["stay"] or t["to"] == t["from"]:
                continue
            n_transitions += 1
            if (name, t["from"], t["leaf"]) not in fired_transitions:
                never_transitions.append({"option": name, "from": t["from"], "to": t["to"], "leaf": t["leaf"]})
    return {
        "options": {**_ratio(len(options) - len(never_options), len(options)), "never": never_options},
        "states": {**_ratio(n_states - len(never_states), n_states), "never": never_states},
        "transitions": {**_ratio(n_transitions - len(never_transitions), n_transitions), "never": never_transitions},
        "leaves": {**_ratio(n_leaves - len(never_leaves), n_leaves), "never": never_leaves},
    }


def _merge(name: str, parts: list[AgentCounts]) -> AgentCounts:
    """One agent's counts over its generations, or a team's over its agents (same program key)."""
    out = AgentCounts(name, parts[0].key, parts[-1].gen)
    for part in parts:
        out.ticks += part.ticks
        for option, intervals in part.options.items():
            out.options.setdefault(option, []).extend(intervals)
        for state, intervals in part.states.items():
            out.states.setdefault(state, []).extend(intervals)
        for leaf, n in part.leaves.items():
            out.leaves[leaf] = out.leaves.get(leaf, 0) + n
        for transition, n in part.transitions.items():
            out.transitions[transition] = out.transitions.get(transition, 0) + n
        out.decided |= part.decided
        out.roots |= part.roots
        out.oscillations.extend(part.oscillations)
    return out


def _section(c: AgentCounts, description: dict[str, Any], tick_ms: float, per_agent: bool) -> dict[str, Any]:
    options: dict[str, Any] = {}
    order = {o["name"]: i for i, o in enumerate(description["options"])}
    for option in sorted(c.options, key=lambda n: order.get(n, len(order))):
        entry = _durations(c.options[option], tick_ms, c.ticks)
        entry["states"] = {
            state: _durations(intervals, tick_ms, c.ticks)
            for (o, state), intervals in sorted(c.states.items())
            if o == option
        }
        entry["transitions"] = [
            {"from": a, "to": b, "leaf": leaf, "count": n}
            for (o, a, b, leaf), n in sorted(c.transitions.items())
            if o == option
        ]
        entry["leaves"] = [
            {"state": s, "leaf": leaf, "count": n} for (o, s, leaf), n in sorted(c.leaves.items()) if o == option
        ]
        options[option] = entry
    universe = _universe(description, sorted(c.roots) if per_agent else None)
    return {
        "program": c.key,
        "ticks": c.ticks,
        "roots": sorted(c.roots),
        "options": options,
        "coverage": _coverage(c, universe),
        "oscillations": len(c.oscillations),
    }


def profile(recording: Recording, agents: list[str] | None = None, oscillation_ms: float = 1000.0) -> dict[str, Any]:
    """The profile of ``agents`` (default: every XABSL agent) of ``recording`` (docs/profile.md).

    Raises:
        ProfileError: an agent that is not in the recording, or a threshold that is not a finite
            positive number of ms.
    """
    if not (isinstance(oscillation_ms, int | float) and 0 < oscillation_ms < float("inf")):
        raise ProfileError(f"the oscillation threshold must be a positive number of ms, got {oscillation_ms!r}")
    names = list(recording.agents) if agents is None else list(agents)
    for name in names:
        if name not in recording.agents:
            raise ProfileError(f"no agent {name!r} in the recording (agents: {', '.join(recording.agents)})")
    tick_ms = 1000.0 / recording.behavior_hz
    counts, times = count_recording(recording, names, oscillation_ms)
    latest: dict[str, dict[str, Any]] = {}
    for c in counts:  # the latest generation of each program key is what coverage counts against
        latest[c.key] = recording.program(c.agent, c.gen).description
    meta = {
        "recording": recording.path,
        "example": recording.header.get("example"),
        "seed": recording.header.get("seed"),
        "ticks": len(recording),
    }
    return build_report(counts, times, names, latest, tick_ms, oscillation_ms, meta)


def build_report(
    counts: list[AgentCounts],
    times: dict[int, int],
    names: list[str],
    latest: dict[str, dict[str, Any]],
    tick_ms: float,
    oscillation_ms: float,
    meta: dict[str, Any],
) -> dict[str, Any]:
    """The report document of ``counts`` (:func:`~xabsl_studio.engine.profile.analysis.count_paths`).

    ``latest``: per program key the description coverage counts against; ``meta``: ``recording``,
    ``example``, ``seed`` and ``ticks`` (the report's header fields).
    """
    by_agent: dict[str, list[AgentCounts]] = {}
    for c in counts:
        by_agent.setdefault(c.agent, []).append(c)
    agents_out: dict[str, Any] = {}
    merged: dict[str, AgentCounts] = {}
    for name in names:
        parts = by_agent.get(name)
        if not parts:
            continue
        merged[name] = _merge(name, parts)
        agents_out[name] = _section(merged[name], latest[parts[0].key], tick_ms, per_agent=True)
    teams: dict[str, Any] = {}
    for key, description in latest.items():
        members = [m for m in merged.values() if m.key == key]
        team = _merge(key, members)
        section = _section(team, description, tick_ms, per_agent=False)
        section["agents"] = [m.agent for m in members]
        teams[key] = section

    last_t = times[max(times)] if times else 0

    def when(seq: int) -> int:
        return times.get(seq, last_t)

    oscillations = sorted(
        (
            {
                "agent": o.agent,
                "kind": o.kind,
                "option": o.option,
                "state": o.state,
                "via": o.via,
                "left_seq": o.left_seq,
                "reentered_seq": o.reentered_seq,
                "left_t": when(o.left_seq),
                "reentered_t": when(o.reentered_seq),
                "left_ms": round(o.left_seq * tick_ms, 3),
                "reentered_ms": round(o.reentered_seq * tick_ms, 3),
                "away_ms": round((o.reentered_seq - o.left_seq) * tick_ms, 3),
            }
            for m in merged.values()
            for o in m.oscillations
        ),
        key=lambda o: (o["left_seq"], o["agent"], o["kind"], o["option"], o["state"] or ""),
    )
    return {
        "format": FORMAT,
        "recording": meta.get("recording"),
        "example": meta.get("example"),
        "seed": meta.get("seed"),
        "ticks": meta["ticks"],
        "first_seq": min(times, default=0),
        "tick_ms": tick_ms,
        "duration_ms": round(meta["ticks"] * tick_ms, 3),
        "oscillation_ms": oscillation_ms,
        "cpu": None,
        "cpu_note": CPU_NOTE,
        "agents": agents_out,
        "teams": teams,
        "oscillations": oscillations,
        "activity": {name: {o: iv for o, iv in sorted(m.options.items())} for name, m in merged.items()},
    }
