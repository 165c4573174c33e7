"""Where two runs first act differently: the first tick each robot's activation path differs (``xabsl diverge``).

Two recordings of the same seed whose behaviors differ by an edit (or a fork and the run it was
forked from) run tick for tick alike until some decision goes another way. :func:`diverge` reads
both recordings' activation paths over the ticks they share (a fork starts at its fork tick)
and, per robot, finds the first tick whose paths differ: options by name and state, basic
behaviors by name, at their depths (ids may differ between two versions of a behavior set;
parameter values are not compared, as a path that differs shows first by them only after some
decision already went another way). The *first differing decision* is the option where the
two paths part: the first option in both with another state, else the option whose action
calls something else. Its "why" on each side comes from that side's recorded reads
(:mod:`xabsl_studio.engine.record.why`).
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from xabsl_studio.engine.record.reader import Recording, RecordingError
from xabsl_studio.engine.record.why import explain_at, recorded_decision
from xabsl_studio.engine.runtime.debug import Explanation

__all__ = ["Divergence", "DivergenceReport", "diverge", "path_lines"]

#: option node: kind, depth, option id, state id (docs/protocol.md "path"); behavior node: kind, depth, id
KIND, DEPTH, ID, STATE = 0, 1, 2, 3


@dataclass(frozen=True, slots=True)
class Divergence:
    """The first tick where one robot's activation paths differ, and the decision where they part."""

    agent: str
    seq: int
    t: int
    #: the two paths as text lines (``option.state`` / ``behavior``, indented by depth)
    path_a: tuple[str, ...]
    path_b: tuple[str, ...]
    #: the first differing decision's option (None: the paths part without one, e.g. a fault)
    option: str | None
    why_a: Explanation | None
    why_b: Explanation | None

    def to_json(self) -> dict[str, Any]:
        """This divergence as the ``--json`` document's entry."""
        return {
            "agent": self.agent,
            "seq": self.seq,
            "t": self.t,
            "path_a": list(self.path_a),
            "path_b": list(self.path_b),
            "option": self.option,
            "why_a": _why_json(self.why_a),
            "why_b": _why_json(self.why_b),
        }


@dataclass(frozen=True, slots=True)
class DivergenceReport:
    """Where recordings ``a`` and ``b`` first act differently, per robot."""

    a: str
    b: str
    seed_a: int | None
    seed_b: int | None
    #: the ticks both hold, ``first`` .. ``end - 1``, compared up to the last robot's divergence
    first: int
    end: int
    agents: tuple[str, ...]
    #: per robot compared: its divergence, None if its paths never differ
    divergences: dict[str, Divergence | None]
    only_a: tuple[str, ...] = ()
    only_b: tuple[str, ...] = ()

    @property
    def earliest(self) -> Divergence | None:
        """The first divergence of any robot (the earliest tick; ties by robot order)."""
        found = [d for d in self.divergences.values() if d is not None]
        return min(found, key=lambda d: d.seq) if found else None

    def to_json(self) -> dict[str, Any]:
        """The ``xabsl diverge --json`` document."""
        earliest = self.earliest
        return {
            "a": self.a,
            "b": self.b,
            "seed_a": self.seed_a,
            "seed_b": self.seed_b,
            "first": self.first,
            "end": self.end,
            "agents": list(self.agents),
            "only_a": list(self.only_a),
            "only_b": list(self.only_b),
            "earliest": earliest.to_json() if earliest else None,
            "divergences": {name: d.to_json() if d else None for name, d in self.divergences.items()},
        }

    def lines(self) -> list[str]:
        """The report as text: per robot its divergence, the paths side by side, both whys."""
        out = [f"A: {self.a} (seed {self.seed_a})", f"B: {self.b} (seed {self.seed_b})"]
        if self.seed_a != self.seed_b:
            out.append("note: the seeds differ; the runs may differ from the first tick")
        out.append(f"ticks compared: {self.first}..{self.end - 1}")
        for name in self.only_a:
            out.append(f"{name}: only in A")
        for name in self.only_b:
            out.append(f"{name}: only in B")
        for name, d in sorted(self.divergences.items(), key=lambda item: (item[1] is None, item[1] and item[1].seq)):
            if d is None:
                out.append(f"{name}: the same in every tick compared")
                continue
            out.append("")
            out.append(f"{name}: first differs at tick {d.seq} ({d.t / 1000:.2f} s), decision of {d.option or '?'}")
            width = max((len(line) for line in d.path_a), default=1) + 4
            out.append(f"  {'A'.ljust(width)}B")
            for left, right in itertools.zip_longest(d.path_a, d.path_b, fillvalue=""):
                mark = " " if left == right else "≠"
                out.append(f"{mark} {left.ljust(width)}{right}")
            for side, why in (("A", d.why_a), ("B", d.why_b)):
                if why is not None:
                    out.append(f"  why in {side}: " + str(why).replace("\n", "\n  "))
        return out


def path_lines(description: dict[str, Any], path: list[list[Any]]) -> tuple[str, ...]:
    """A recorded path as text lines (``option.state`` / ``behavior``), indented by depth."""
    options, behaviors = description["options"], description["behaviors"]
    lines = []
    for node in path:
        if node[KIND] == 0:
            option = options[node[ID]]
            lines.append("  " * node[DEPTH] + f"{option['name']}.{option['states'][node[STATE]]['name']}")
        else:
            lines.append("  " * node[DEPTH] + behaviors[node[ID]]["name"])
    return tuple(lines)


def diverge(a: Recording, b: Recording, agents: list[str] | None = None) -> DivergenceReport:
    """Where ``a`` and ``b`` first act differently, per robot both recorded (or those of ``agents``).

    Raises:
        RecordingError: the recordings share no tick or no robot, or a robot of ``agents`` is missing.
    """
    shared = [name for name in a.agents if name in b.agents]
    if agents is not None:
        for name in agents:
            if name not in shared:
                raise RecordingError(f"no robot {name!r} in both recordings (both hold: {', '.join(shared)})")
        shared = [name for name in shared if name in agents]
    if not shared:
        raise RecordingError(f"{a.path} and {b.path} have no robot in common")
    first, end = max(a.first, b.first), min(a.end, b.end)
    if first >= end:
        raise RecordingError(f"{a.path} ({a.first}..{a.end - 1}) and {b.path} ({b.first}..{b.end - 1}) share no tick")
    found: dict[str, Divergence | None] = dict.fromkeys(shared)
    open_ = set(shared)
    # per pair of generations: do both number options, states and behaviors alike (then ids compare)?
    alike: dict[tuple[str, int, int], bool] = {}
    # a tick missing on one side shows as two seqs meeting (a file cut short just ends the comparison)
    pairs = zip(_ticks(a, first, end, shared), _ticks(b, first, end, shared), strict=False)
    for (seq, t, ticks_a), (seq_b, _, ticks_b) in pairs:
        if seq != seq_b:
            raise RecordingError(f"tick {seq} of {a.path} meets tick {seq_b} of {b.path}: a tick is missing")
        for name in sorted(open_ & ticks_a.keys() & ticks_b.keys()):
            (gen_a, path_a), (gen_b, path_b) = ticks_a[name], ticks_b[name]
            desc_a, desc_b = a.program(name, gen_a).description, b.program(name, gen_b).description
            pair = (name, gen_a, gen_b)
            if pair not in alike:
                alike[pair] = _names(desc_a) == _names(desc_b)
            if alike[pair] and _ids(path_a) == _ids(path_b):
                continue
            if _keys(desc_a, path_a) != _keys(desc_b, path_b):
                found[name] = _divergence(a, b, name, seq, t, desc_a, path_a, desc_b, path_b)
                open_.discard(name)
        if not open_:
            break
    return DivergenceReport(
        a.path,
        b.path,
        _seed(a),
        _seed(b),
        first,
        end,
        tuple(shared),
        found,
        tuple(n for n in a.agents if n not in b.agents),
        tuple(n for n in b.agents if n not in a.agents),
    )


def _ticks(
    recording: Recording, start: int, stop: int, agents: list[str]
) -> Iterator[tuple[int, int, dict[str, tuple[int, list[list[Any]]]]]]:
    """Per tick ``(seq, t, {agent: (gen, path)})`` from the recording's paths (file order is tick order)."""
    last = start - 1
    for seq, rows in itertools.groupby(recording.paths(start, stop, agents), key=lambda row: row[0]):
        if seq <= last:
            raise RecordingError(f"{recording.path}: tick {seq} is stored after tick {last}")
        last = seq
        ticks: dict[str, tuple[int, list[list[Any]]]] = {}
        t = 0
        for _, at, agent, gen, path in rows:
            ticks[agent], t = (gen, path), at
        yield seq, t, ticks


def _names(description: dict[str, Any]) -> tuple[Any, ...]:
    """What ids stand for: the options with their states, the basic behaviors, in id order."""
    options = tuple((o["name"], tuple(s["name"] for s in o["states"])) for o in description["options"])
    return options, tuple(b["name"] for b in description["behaviors"])


def _ids(path: list[list[Any]]) -> list[tuple[Any, ...]]:
    """A path's nodes by ids (kind, depth, id, an option's state), for two generations that number alike."""
    return [(n[KIND], n[DEPTH], n[ID], n[STATE] if n[KIND] == 0 else -1) for n in path]


def _keys(description: dict[str, Any], path: list[list[Any]]) -> list[tuple[Any, ...]]:
    """What is compared of a path: per node its kind, depth, name (and an option's state name)."""
    options, behaviors = description["options"], description["behaviors"]
    keys: list[tuple[Any, ...]] = []
    for node in path:
        if node[KIND] == 0:
            option = options[node[ID]]
            keys.append((0, node[DEPTH], option["name"], option["states"][node[STATE]]["name"]))
        else:
            keys.append((1, node[DEPTH], behaviors[node[ID]]["name"]))
    return keys


def _divergence(
    a: Recording,
    b: Recording,
    agent: str,
    seq: int,
    t: int,
    desc_a: dict[str, Any],
    path_a: list[list[Any]],
    desc_b: dict[str, Any],
    path_b: list[list[Any]],
) -> Divergence:
    keys_a, keys_b = _keys(desc_a, path_a), _keys(desc_b, path_b)
    common = min(len(keys_a), len(keys_b))
    parting = next((i for i in range(common) if keys_a[i] != keys_b[i]), common)
    option: str | None = None
    if parting < common and keys_a[parting][0] == 0 and keys_a[parting][:3] == keys_b[parting][:3]:
        option = str(keys_a[parting][2])  # the same option went to another state
    else:
        # below the same nodes the paths call something else: the nearest option above calls it
        depth = (keys_a if parting < len(keys_a) else keys_b)[parting][1]
        option = next((str(k[2]) for k in reversed(keys_a[:parting]) if k[0] == 0 and k[1] < depth), None)
    return Divergence(
        agent,
        seq,
        t,
        path_lines(desc_a, path_a),
        path_lines(desc_b, path_b),
        option,
        _why(a, agent, seq, option),
        _why(b, agent, seq, option),
    )


def _why(recording: Recording, agent: str, seq: int, option: str | None) -> Explanation | None:
    """The why of ``option``'s decision at tick ``seq`` (None when it did not decide there or cannot be told)."""
    if option is None:
        return None
    try:
        return explain_at(recorded_decision(recording, agent, seq, option))
    except RecordingError:
        return None


def _seed(recording: Recording) -> int | None:
    seed = recording.header.get("seed")
    return int(seed) if isinstance(seed, int) else None


def _why_json(why: Explanation | None) -> dict[str, Any] | None:
    if why is None:
        return None
    return {
        "option": why.option,
        "decided_in": why.decided_in,
        "leaf": why.leaf,
        "target": why.target,
        "stay": why.stay,
        "conditions": [
            {
                "text": c.text or c.source,
                "value": c.value if isinstance(c.value, bool | int | float) or c.value is None else str(c.value),
                "branch": c.branch,
                "comparisons": [str(k) for k in c.comparisons],
            }
            for c in why.conditions
        ],
    }
