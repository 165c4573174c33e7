"""Where a live fork first acts differently from the run it was forked from, per robot.

After a ``fork`` the ring holds the original run's ticks at the seqs before the fork's first sample
and the fork's ticks after it. The original run is the one the fork's tick came from: the fork's
first sample is the world as the tick before ``ForkOrigin.seq`` left it, then tick ``seq`` runs
again; the original's ticks from there on count up to where time goes down (a reset, or an earlier
fork) or the fork began (:func:`original_run`, :func:`original_tick`). Both ran from the same world
state, so until some decision goes another way each fork tick's activation path equals the
original's at the same world time. :class:`ForkDivergence` scans the fork's ticks as they arrive
(each one once) and keeps, per robot, the first whose path differs, with how many fork ticks just
before it were not compared (a sample of either run the pipe dropped: the paths may have parted in
one of those). Paths compare by options by name and state, basic behaviors by name, at their depths
(the two runs may run different versions of a behavior set, so ids would not compare; parameter
values are not compared, as in ``xabsl diverge``). The first differing decision is the option where
the two paths part: the first option in both with another state, else the option above the first
node that differs (its action calls something else).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import orjson

from xabsl_studio.engine.runtime.activation import BEHAVIOR_NODE, OPTION_NODE
from xabsl_studio.server.protocol.replies import ForkOrigin
from xabsl_studio.server.protocol.rest import NamedNode, RobotDivergenceJson
from xabsl_studio.server.protocol.types import ID_INDEX
from xabsl_studio.server.session.frames import Entry, Ring

__all__ = ["ForkDivergence", "named_paths", "original_run", "original_tick"]


def named_paths(entry: Entry) -> list[dict[str, Any]]:
    """Every robot of ``entry``: id, name, path (``NamedNode`` s)."""
    structure = entry.gen.structure
    frame = orjson.loads(entry.delta)
    robots = []
    for robot in frame["robots"]:
        info = structure["robots"][robot["id"]]
        program = structure["programs"].get(info["program"]) if info["program"] is not None else None
        options = {o["id"]: o for o in program["options"]} if program else {}
        behaviors = {b["id"]: b["name"] for b in program["behaviors"]} if program else {}
        path: list[NamedNode] = []
        for node in robot["path"]:
            if node[0] == OPTION_NODE and node[ID_INDEX] in options:
                option = options[node[ID_INDEX]]
                state = node[ID_INDEX + 1]
                states = option["states"]
                path.append(
                    {
                        "depth": node[1],
                        "option": option["name"],
                        "state": states[state]["name"] if 0 <= state < len(states) else None,
                    }
                )
            elif node[0] == BEHAVIOR_NODE and node[ID_INDEX] in behaviors:
                path.append({"depth": node[1], "behavior": behaviors[node[ID_INDEX]]})
        robots.append({"id": robot["id"], "name": info["name"], "path": path})
    return robots


def parting_option(fork: list[NamedNode], original: list[NamedNode]) -> str | None:
    """The option whose decision makes the two paths part (see the module docstring); None: no option."""
    for i, (mine, theirs) in enumerate(zip(fork, original, strict=False)):
        if mine == theirs:
            continue
        if "option" in mine and mine.get("option") == theirs.get("option") and mine["depth"] == theirs["depth"]:
            return str(mine["option"])  # the same option, in another state
        return _caller(fork, i, min(mine["depth"], theirs["depth"]))
    if len(fork) == len(original):
        return None
    longer = fork if len(fork) > len(original) else original
    shorter = min(len(fork), len(original))
    return _caller(longer, shorter, longer[shorter]["depth"])


def _caller(path: list[NamedNode], index: int, depth: int) -> str | None:
    """The nearest option before ``path[index]`` above ``depth``: the one whose action calls what differs."""
    for node in reversed(path[:index]):
        if "option" in node and node["depth"] < depth:
            return str(node["option"])
    return None


@dataclass
class ForkDivergence:
    """The scan of one fork (see the module docstring)."""

    fork: ForkOrigin
    #: the last fork tick compared (every tick before it is compared too)
    scanned: int = -1
    #: the original's ticks by world time (the newest of each time before the fork)
    original: dict[int, Entry] | None = None
    #: the time of the original's last tick
    original_end: int = 0
    #: the original run ended (or left the ring) before this fork tick's time: nothing later compares
    beyond: bool = False
    #: per robot id its divergence (``why_fork`` and ``why_original`` not filled in here: null)
    found: dict[int, RobotDivergenceJson] = field(default_factory=dict)
    #: the ones the API has asked the decisions of (``why_fork``, ``why_original`` filled), by robot id
    explained: dict[int, RobotDivergenceJson] = field(default_factory=dict)
    #: fork ticks since the last compared one that could not be compared (a sample the pipe dropped)
    uncompared: int = 0

    def update(self, ring: Ring) -> None:
        """Compare the fork's ticks the ring received since the last update."""
        if self.original is None:
            self.original = original_run(ring, self.fork)
            self.original_end = max(self.original, default=0)
        latest = ring.latest
        if latest is None or self.beyond:
            return
        seq = max(self.scanned + 1, self.fork.start)
        while seq <= latest.seq:
            entry = ring.get(seq)
            before = self.original.get(entry.t) if entry is not None else None
            if entry is not None and before is not None:
                self._compare(entry, before)
                self.uncompared = 0
            elif entry is not None and (not self.original or entry.t > self.original_end):
                self.beyond = True  # the original did not run that far (or left the ring)
                break
            else:
                self.uncompared += 1
            self.scanned = seq
            seq += 1

    def _compare(self, entry: Entry, before: Entry) -> None:
        robots = named_paths(entry)
        if all(robot["id"] in self.found for robot in robots):
            return
        originals = {robot["id"]: robot for robot in named_paths(before)}
        for robot in robots:
            other = originals.get(robot["id"])
            if robot["id"] in self.found or other is None or robot["path"] == other["path"]:
                continue
            self.found[robot["id"]] = {
                "robot": robot["id"],
                "name": robot["name"],
                "seq": entry.seq,
                "t": entry.t,
                "original_seq": before.seq,
                "uncompared_before": self.uncompared,
                "fork_path": robot["path"],
                "original_path": other["path"],
                "option": parting_option(robot["path"], other["path"]),
                "why_fork": None,
                "why_original": None,
            }


def original_run(ring: Ring, fork: ForkOrigin) -> dict[int, Entry]:
    """The original run's ticks in the ring by world time (see the module docstring)."""
    found: dict[int, Entry] = {}
    previous = None
    for at in range(fork.seq - 1, fork.start):
        candidate = ring.get(at)
        if candidate is None:  # left the ring, or a sample the pipe dropped
            continue
        if previous is not None and candidate.t <= previous:
            break
        found[candidate.t] = candidate
        previous = candidate.t
    return found


def original_tick(ring: Ring, fork: ForkOrigin, seq: int) -> Entry | None:
    """The original run's tick at the time of the fork's tick ``seq`` (None: not in the ring, or not run that far)."""
    entry = ring.get(seq)
    if entry is None or seq < fork.start:
        return None
    return original_run(ring, fork).get(entry.t)
