"""Counting a recording: per agent and option/state the active intervals, leaves, transitions.

One pass over :meth:`xabsl_studio.engine.record.Recording.paths` (the compact per-tick activation paths, no
trees). Per agent and program generation a :class:`_Counter` keeps, for each option in the
path, when its current activation and its current state began; an interval is closed when the
option leaves the path, restarts (its ``option_time`` went back) or changes state. Every tick's
fired decision leaf (``decided-in`` state, ``leaf``) is counted, and a leaf whose ``decided-in``
state differs from the active state is a transition ``from -> to``.

Rules (docs/profile.md):

* an *activation* of an option is a run of consecutive ticks in which it is in the path without
  its ``option_time`` going back; an activation of a state is a run of ticks with that state
  active within one activation of its option;
* an *oscillation* is an option, or a state within one activation of its option, re-entered less
  than the threshold after it was left (the time away is ``(re-entered seq - left seq) x tick``);
* a state is *reached* when it was active or its decision ran (an initial state left in the
  option's first tick was reached but holds no time).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

from xabsl_studio.engine.record import Recording

__all__ = ["AgentCounts", "Oscillation", "count_paths", "count_recording"]


@dataclass(slots=True)
class Oscillation:
    """An option or state left at ``left_seq`` and entered again at ``reentered_seq``."""

    agent: str
    kind: str  # "option" or "state"
    option: str
    state: str | None
    left_seq: int
    reentered_seq: int
    via: list[str]


@dataclass(slots=True)
class AgentCounts:
    """What one agent did under one program generation, by option and state names."""

    agent: str
    key: str
    gen: int
    ticks: int = 0
    #: option name -> [(start seq, stop seq)] (stop exclusive)
    options: dict[str, list[tuple[int, int]]] = field(default_factory=dict)
    #: (option, state) -> intervals
    states: dict[tuple[str, str], list[tuple[int, int]]] = field(default_factory=dict)
    #: (option, decided-in state, leaf) -> ticks it fired
    leaves: dict[tuple[str, str, int], int] = field(default_factory=dict)
    #: (option, from, to, leaf) -> count
    transitions: dict[tuple[str, str, str, int], int] = field(default_factory=dict)
    #: states whose decision ran (reached), (option, state)
    decided: set[tuple[str, str]] = field(default_factory=set)
    #: root options seen at depth 0
    roots: set[str] = field(default_factory=set)
    oscillations: list[Oscillation] = field(default_factory=list)


class _Counter:
    """The running counts of one agent under one generation, by ids (names at :meth:`finish`)."""

    __slots__ = (
        "away",
        "decided",
        "history",
        "last_option_stop",
        "last_state_stop",
        "leaves",
        "option_intervals",
        "option_start",
        "oscillations",
        "prev",
        "roots",
        "state_intervals",
        "state_start",
        "threshold",
        "ticks",
        "transitions",
    )

    def __init__(self, threshold_ticks: int) -> None:
        self.threshold = threshold_ticks
        self.prev: dict[int, list[Any]] = {}
        self.option_start: dict[int, int] = {}
        self.state_start: dict[int, int] = {}
        self.option_intervals: dict[int, list[tuple[int, int]]] = {}
        self.state_intervals: dict[tuple[int, int], list[tuple[int, int]]] = {}
        self.last_option_stop: dict[int, int] = {}
        self.last_state_stop: dict[tuple[int, int], int] = {}
        #: per option the states entered in its current activation: [(state id, start seq)]
        self.history: dict[int, list[tuple[int, int]]] = {}
        self.leaves: dict[tuple[int, int, int], int] = {}
        self.transitions: dict[tuple[int, int, int, int], int] = {}
        self.decided: set[tuple[int, int]] = set()
        self.roots: set[int] = set()
        #: (kind, option id, state id or -1, left seq, re-entered seq, via state ids)
        self.oscillations: list[tuple[str, int, int, int, int, list[int]]] = []
        self.ticks = 0
        self.away = 0

    def _close_state(self, oid: int, sid: int, seq: int) -> None:
        key = (oid, sid)
        self.state_intervals.setdefault(key, []).append((self.state_start[oid], seq))
        self.last_state_stop[key] = seq

    def _close_option(self, oid: int, sid: int, seq: int) -> None:
        self._close_state(oid, sid, seq)
        self.option_intervals.setdefault(oid, []).append((self.option_start[oid], seq))
        self.last_option_stop[oid] = seq

    def _enter_option(self, oid: int, sid: int, seq: int) -> None:
        left = self.last_option_stop.get(oid)
        if left is not None and seq - left < self.threshold:
            self.oscillations.append(("option", oid, -1, left, seq, []))
        self.option_start[oid] = seq
        self.state_start[oid] = seq
        self.history[oid] = [(sid, seq)]

    def _enter_state(self, oid: int, sid: int, seq: int) -> None:
        left = self.last_state_stop.get((oid, sid))
        history = self.history[oid]
        if left is not None and left >= self.option_start[oid] and seq - left < self.threshold:
            via: list[int] = []
            for other, start in reversed(history):
                if other == sid:
                    break
                via.append(other)
                if start < left:  # pragma: no cover - the loop finds sid first
                    break
            via.reverse()
            self.oscillations.append(("state", oid, sid, left, seq, via))
        self.state_start[oid] = seq
        history.append((sid, seq))
        if len(history) > 64:  # only the recent past matters for oscillations
            del history[:32]

    def tick(self, seq: int, path: list[list[Any]]) -> None:
        """Count one tick's path (the hot loop: the common case, same option in the same state, first)."""
        self.ticks += 1
        prev = self.prev
        cur: dict[int, list[Any]] = {}
        leaves = self.leaves
        for node in path:
            if node[0]:
                continue
            oid = node[2]
            if oid in cur:
                continue
            cur[oid] = node
            sid = node[3]
            before = prev.get(oid)
            if before is None:
                self._enter_option(oid, sid, seq)
                if node[1] == 0:
                    self.roots.add(oid)
            elif node[4] < before[4]:  # option_time went back: the option restarted
                self._close_option(oid, before[3], seq)
                self._enter_option(oid, sid, seq)
            elif before[3] != sid:
                self._close_state(oid, before[3], seq)
                self._enter_state(oid, sid, seq)
            leaf = node[7]
            if leaf < 0:
                continue
            decided = node[6]
            key = (oid, decided, leaf)
            try:
                leaves[key] += 1
            except KeyError:
                leaves[key] = 1
                self.decided.add((oid, decided))
            if decided != sid:
                tkey = (oid, decided, sid, leaf)
                self.transitions[tkey] = self.transitions.get(tkey, 0) + 1
        if len(prev) != len(cur) or any(oid not in cur for oid in prev):
            for oid, node in prev.items():
                if oid not in cur:
                    self._close_option(oid, node[3], seq)
        self.prev = cur

    def finish(self, seq: int) -> None:
        """Close every open interval at ``seq`` (the tick after the last one counted)."""
        for oid, node in self.prev.items():
            self._close_option(oid, node[3], seq)
        self.prev = {}

    def named(self, agent: str, key: str, gen: int, description: dict[str, Any]) -> AgentCounts:
        """The counts by option and state names of ``description`` (the generation's program)."""
        options = description["options"]

        def o(oid: int) -> str:
            return str(options[oid]["name"])

        def s(oid: int, sid: int) -> str:
            return str(options[oid]["states"][sid]["name"])

        out = AgentCounts(agent, key, gen, self.ticks)
        for oid, intervals in self.option_intervals.items():
            out.options.setdefault(o(oid), []).extend(intervals)
        for (oid, sid), intervals in self.state_intervals.items():
            out.states.setdefault((o(oid), s(oid, sid)), []).extend(intervals)
        for (oid, sid, leaf), n in self.leaves.items():
            out.leaves[(o(oid), s(oid, sid), leaf)] = n
        for (oid, a, b, leaf), n in self.transitions.items():
            out.transitions[(o(oid), s(oid, a), s(oid, b), leaf)] = n
        out.decided = {(o(oid), s(oid, sid)) for oid, sid in self.decided}
        out.roots = {o(oid) for oid in self.roots}
        for kind, oid, sid, left, back, via in self.oscillations:
            out.oscillations.append(
                Oscillation(
                    agent, kind, o(oid), s(oid, sid) if sid >= 0 else None, left, back, [s(oid, v) for v in via]
                )
            )
        return out


def count_paths(
    rows: Iterable[tuple[int, int, str, int, list[list[Any]]]],
    names: list[str],
    program_of: Callable[[str, int], tuple[str, dict[str, Any]]],
    tick_ms: float,
    oscillation_ms: float = 1000.0,
) -> tuple[list[AgentCounts], dict[int, int]]:
    """Count ``(seq, t, agent, gen, path)`` rows (per agent in seq order) in one pass.

    ``program_of(agent, gen)`` gives the program key and description that the ids of that
    generation index. A recording gives the rows through ``Recording.paths``; the studio from its
    ring buffer.

    Returns:
        the counts per agent and program generation (in ``names`` order), and per seq the world's
        engine clock ``t`` in ms (seq -> t, for the times of oscillations).
    """
    threshold = max(1, math.ceil(oscillation_ms / tick_ms))  # away for fewer ticks than this
    counters: dict[tuple[str, int], _Counter] = {}
    current: dict[str, tuple[int, _Counter, int]] = {}  # agent -> (gen, counter, last seq)
    times: dict[int, int] = {}
    for seq, t, agent, gen, path in rows:
        times[seq] = t
        entry = current.get(agent)
        if entry is None or entry[0] != gen:
            if entry is not None:
                entry[1].finish(entry[2] + 1)
            counter = counters.get((agent, gen))
            if counter is None:
                counter = counters[(agent, gen)] = _Counter(threshold)
            entry = (gen, counter, seq)
        entry[1].tick(seq, path)
        current[agent] = (gen, entry[1], seq)
    for _gen, counter, last in current.values():
        counter.finish(last + 1)
    result = []
    order = {name: i for i, name in enumerate(names)}
    for (agent, gen), counter in sorted(counters.items(), key=lambda item: (order[item[0][0]], item[0][1])):
        key, description = program_of(agent, gen)
        result.append(counter.named(agent, key, gen, description))
    return result, times


def count_recording(
    recording: Recording, agents: list[str] | None = None, oscillation_ms: float = 1000.0
) -> tuple[list[AgentCounts], dict[int, int]]:
    """:func:`count_paths` over every tick of ``agents`` (default: all) of ``recording``."""
    names = recording.agents if agents is None else agents

    def program_of(agent: str, gen: int) -> tuple[str, dict[str, Any]]:
        program = recording.program(agent, gen)
        return program.key, program.description

    return count_paths(recording.paths(agents=names), names, program_of, 1000.0 / recording.behavior_hz, oscillation_ms)
