"""Facts of the errands world: the derivation rules the robot uses, the ground truth, their agreement.

The robot derives its symbolic facts from the history of its own signals (doc §1.6) with
:class:`xabsl_studio.engine.planning.facts.FactDeriver`; this module configures the rule table for the
errands world and measures how well the derived facts match the truth of the simulation
(§4.4 claims 18–20).

Rules (§1.6, with two additions marked [D]):

* ``at-robot x``: δ_x = 1 for 0.3 s; cleared by δ_x = 0 for 0.3 s; at most one location.
* ``has-robot o``: the object vanished into the closing gripper while gather_o was in charge
  (α_gather_o > 0.5, g_o > 0.5, γ_o fell from ≥ 0.8 to 0), confirmed after 1 s without
  γ_o > 0.3; retracted if seen again while gathering.
* ``at o x``: evidence for o at x while ``at-robot x`` for 0.3 s, where the evidence signal
  ``placed_o`` is *either* the §1.6 dump evidence (α_dump_o > 0.5 and d_o > 0.5) *or* [D]
  seeing the object (γ_o > 0.3). ``FactRule`` conditions are conjunctions and one rule derives
  one fact, so the disjunction is computed here as a signal; the cause of an event names it and
  :func:`evidence_signals` documents its inputs.
* [D] ``at o x`` is cleared after gathering o at x for 12 s without ever seeing it (γ_o ≤ 0.3):
  "searched, not found". Without it a teleported or removed object stays at its old place in
  the robot's beliefs forever and replanning from derived facts repeats the failing LOAD.

Ground truth uses the same vocabulary: ``at-robot x`` within 0.6 m of beacon x (the δ radius),
``has-robot o`` while the gripper holds o, ``at o x`` for an object lying within 1.2 m of beacon
x (the region a robot standing at x can see).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from xabsl_studio.engine.planning.facts import FactRule, errands_rules
from xabsl_studio.engine.planning.strips import Fact
from xabsl_studio.examples.errands.arena import Arena

#: How long gathering without seeing the object clears its believed location (s) [D].
SEARCH_GIVE_UP_S = 12.0
#: Radius around a beacon inside which a lying object is "at" that location (truth), m.
LOCATION_RADIUS = 1.2
#: Width of the "designed lag" window after a truth change (§4.4 claim 19), s.
LAG_WINDOW_S = 1.2


def fact_rules(locations: Sequence[str] = ("a", "b", "c"), items: Sequence[str] = ("book", "mug")) -> list[FactRule]:
    """Build the rule table above: §1.6's at-robot and has-robot rules, our at-object rules."""
    rules = [r for r in errands_rules(locations, items) if r.fact.startswith(("at-robot ", "has-robot "))]
    for o in items:
        for x in locations:
            rules.append(
                FactRule.make(
                    f"at {o} {x}",
                    [f"placed_{o} >= 0.5", f"fact(at-robot {x})"],
                    set_dwell=0.3,
                    clear_when=[f"alpha.gather_{o} > 0.5", f"γ_{o} <= 0.3", f"fact(at-robot {x})"],
                    clear_dwell=SEARCH_GIVE_UP_S,
                    clears=[f"has-robot {o}"],
                    group=f"at {o}",
                )
            )
    return rules


def evidence_signals(signals: dict[str, float], items: Iterable[str]) -> None:
    """Add ``placed_<o>`` (1 or 0) to a signal snapshot: dumped here, or seen here.

    dumped: α_dump_o > 0.5 and d_o > 0.5 (§1.6); seen: γ_o > 0.3 (the object is in front of the
    robot, closer than 0.65 m).
    """
    for o in items:
        dumped = signals["alpha.dump_" + o] > 0.5 and signals["d_" + o] > 0.5
        signals["placed_" + o] = 1.0 if dumped or signals["γ_" + o] > 0.3 else 0.0


def truth_facts(arena: Arena) -> frozenset[Fact]:
    """The fluent facts that really hold in the arena now."""
    return frozenset(_robot_truth(arena) + _object_truth(arena))


def _robot_truth(arena: Arena) -> list[Fact]:
    x, y = arena.robot.position
    near2 = arena.geom.near**2
    return [f for f, bx, by in arena.beacon_facts if (bx - x) ** 2 + (by - y) ** 2 < near2]


def _object_truth(arena: Arena) -> list[Fact]:
    out: list[Fact] = []
    r2 = LOCATION_RADIUS**2
    for o, it in arena.items.items():
        if not it.present:
            continue
        if it.held:
            out.append(f"has-robot {o}")
            continue
        for name, (bx, by) in arena.beacons.items():
            if (bx - it.x) ** 2 + (by - it.y) ** 2 < r2:
                out.append(f"at {o} {name}")
    return out


class Truth:
    """:func:`truth_facts` for every tick, cheaply.

    Objects only move while held (then the fact is Has-Robot wherever they are) or when grabbed,
    released, teleported or removed, which bump ``arena.item_version``; so the object facts are
    recomputed on those events only, and the robot's location each tick.
    """

    def __init__(self, arena: Arena) -> None:
        self.arena = arena
        self._version = -1
        self._objects: list[Fact] = []
        self._last: tuple[tuple[str, ...], frozenset[Fact]] = ((), frozenset())

    def __call__(self) -> frozenset[Fact]:
        """The facts that hold now, derived from the activation history."""
        arena = self.arena
        if arena.item_version != self._version:
            self._version = arena.item_version
            self._objects = _object_truth(arena)
            self._last = ((), frozenset())
        robot = tuple(_robot_truth(arena))
        if robot != self._last[0] or not self._last[1]:
            self._last = (robot, frozenset((*robot, *self._objects)))
        return self._last[1]


@dataclass
class Agreement:
    """Per-tick comparison of derived facts with the truth (§4.4 claims 18 and 19).

    Attributes:
        ticks: ticks compared.
        equal: ticks where the derived set equals the truth.
        outside_lag: ticks farther than ``lag_window`` after any truth change.
        equal_outside_lag: of those, ticks with equal sets.
        mismatches: the first few (t, missing, extra) disagreements outside the lag window.
    """

    lag_window: float = LAG_WINDOW_S
    ticks: int = 0
    equal: int = 0
    outside_lag: int = 0
    equal_outside_lag: int = 0
    last_truth: frozenset[Fact] | None = None
    last_change: float = -math.inf
    mismatches: list[tuple[float, list[Fact], list[Fact]]] = field(default_factory=list)

    def update(self, t: float, derived: frozenset[Fact], truth: frozenset[Fact]) -> bool:
        """Record one tick; return whether the sets were equal."""
        if truth != self.last_truth:
            if self.last_truth is not None:
                self.last_change = t
            self.last_truth = truth
        same = derived == truth
        self.ticks += 1
        self.equal += same
        if t - self.last_change > self.lag_window:
            self.outside_lag += 1
            self.equal_outside_lag += same
            if not same and len(self.mismatches) < 20:
                self.mismatches.append((round(t, 3), sorted(truth - derived), sorted(derived - truth)))
        return same

    @property
    def fraction(self) -> float:
        """Share of ticks with derived facts equal to the truth (1.0 before any tick)."""
        return self.equal / self.ticks if self.ticks else 1.0

    @property
    def fraction_outside_lag(self) -> float:
        """Share of equal ticks among those outside the designed-lag windows."""
        return self.equal_outside_lag / self.outside_lag if self.outside_lag else 1.0

    def to_json(self) -> Mapping[str, object]:
        """The event as plain JSON data (the studio's facts panel and recordings)."""
        return {
            "fraction": round(self.fraction, 5),
            "fraction_outside_lag": round(self.fraction_outside_lag, 5),
            "ticks": self.ticks,
        }
