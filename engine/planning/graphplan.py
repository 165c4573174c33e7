"""GRAPHPLAN over grounded STRIPS tasks, with layered plans and per-level statistics (doc §2).

This module owns the planning graph (proposition and action levels with no-ops and the four
mutex kinds of §2.1), backward extraction with memoised nogoods, level-off termination, and the
layered plan that the plan monitor executes. It is our own implementation of Blum & Furst (AIJ
90, 1997) as summarised in dual-dynamics.md §2.1; no third-party planner code is used.

Determinism (§2.2 "Recommendation"): goals are assigned in lexical order of their fact names and
each goal's achievers are tried no-op first, then real actions in lexical order of their names.
On the errands problem this makes level 5 try ``goto b a`` before ``goto c a``, which yields the
paper's a→c→b→a tour (§2.4).

Output (§2.1 item 6): a :class:`LayeredPlan`, one tuple of real ground actions per step, sorted by
name, no-ops removed. A step whose chosen actions are all no-ops would be an empty layer; we drop
such layers because they carry no information (nothing happens in that step) and, GRAPHPLAN being
step-optimal, they cannot occur in a plan found at the first successful stage anyway: the plan
with that step removed would have been found one stage earlier. The only empty plan is the one
for a goal that already holds initially (zero layers).

Statistics (§2.4 table): one :class:`LevelStats` per graph level with |P_i|, |A_i|, mutex counts,
whether the goals are present and pairwise non-mutex, and what extraction did at that stage.
"""

from __future__ import annotations

import dataclasses
import itertools
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field

from xabsl_studio.engine.planning.strips import Fact, GroundAction, Task


@dataclass(frozen=True, slots=True)
class LevelStats:
    """One row of the planning-graph table (§2.4), for graph level ``level``.

    Attributes:
        level: i; level 0 is the initial proposition level P0 (no action level).
        props: |P_i|.
        actions: |A_i| counting real actions only (0 at level 0).
        noops: no-ops in A_i (one per proposition of P_{i-1}).
        prop_mutexes: unordered mutex pairs in P_i.
        action_mutexes: unordered mutex pairs in A_i, no-ops included.
        goals_present: every goal is in P_i.
        goals_nonmutex: goals present and pairwise non-mutex in P_i (extraction may start).
        extraction: ``"none"`` (not attempted), ``"failed"`` or ``"success"`` for the stage that
            ended with the graph at this level.
        attempts: goal sets searched during that stage (memo hits excluded).
        memo_hits: goal sets pruned by a stored nogood during that stage.
        nogoods_added: nogoods memoised during that stage, at any level.
        nogoods: nogoods stored for *this* level at the end of the search.
    """

    level: int
    props: int
    actions: int
    noops: int
    prop_mutexes: int
    action_mutexes: int
    goals_present: bool
    goals_nonmutex: bool
    extraction: str
    attempts: int
    memo_hits: int
    nogoods_added: int
    nogoods: int

    def to_json(self) -> dict[str, object]:
        """Plain data for the studio's planning-graph drawer (§4.3 item 3)."""
        return {k: getattr(self, k) for k in self.__slots__}


@dataclass(frozen=True, slots=True)
class LayeredPlan:
    """A GRAPHPLAN plan: steps of pairwise non-mutex actions; any order within a step is valid."""

    layers: tuple[tuple[GroundAction, ...], ...]

    def __len__(self) -> int:
        return len(self.layers)

    def names(self) -> list[list[str]]:
        """Layer-by-layer action names, e.g. ``[["goto a c"], ..., ["unload book a", ...]]``."""
        return [[a.name for a in layer] for layer in self.layers]

    def actions(self) -> list[GroundAction]:
        """All actions, layer by layer, each layer in name order (the monitor's queue order)."""
        return [a for layer in self.layers for a in layer]

    def linearizations(self) -> Iterator[list[GroundAction]]:
        """Every total order consistent with the steps (product of per-layer permutations)."""
        per_layer = [list(itertools.permutations(layer)) for layer in self.layers]
        for choice in itertools.product(*per_layer):
            yield [a for perm in choice for a in perm]

    def __str__(self) -> str:
        return " | ".join(" ∥ ".join(a.name for a in layer) for layer in self.layers)

    def to_json(self) -> list[list[dict[str, object]]]:
        """Serialise the layers for the editor (``POST /plan`` answers with this)."""
        return [[a.to_json() for a in layer] for layer in self.layers]


@dataclass(frozen=True, slots=True)
class GraphplanResult:
    """What :func:`graphplan` found: a plan or the reason there is none, plus the level table."""

    plan: LayeredPlan | None
    stats: tuple[LevelStats, ...]
    leveled_off_at: int | None
    reason: str
    seconds: float

    @property
    def solved(self) -> bool:
        """Whether a plan was found."""
        return self.plan is not None


def execute(task: Task, sequence: Sequence[GroundAction]) -> frozenset[Fact]:
    """Apply ``sequence`` from the task's initial state; raise ``ValueError`` on a failed precondition."""
    state = task.init
    for a in sequence:
        if not a.applicable(state):
            missing = ", ".join(sorted(a.pre - state))
            raise ValueError(f"{a.name}: precondition not satisfied ({missing})")
        state = a.apply(state)
    return state


# --- the planning graph --------------------------------------------------------------------------


@dataclass(slots=True)
class _Op:
    name: str
    pre: frozenset[int]
    add: frozenset[int]
    delete: frozenset[int]
    noop: bool


@dataclass(slots=True)
class _Level:
    props: frozenset[int]
    prop_mutex: set[tuple[int, int]]
    actions: list[int] = field(default_factory=list)
    action_mutex: set[tuple[int, int]] = field(default_factory=set)
    #: fact -> its achievers in A_i, no-op first then real actions by name (the tie-break order).
    achievers: dict[int, list[int]] = field(default_factory=dict)


def _pair(a: int, b: int) -> tuple[int, int]:
    return (a, b) if a < b else (b, a)


class _Planner:
    """One GRAPHPLAN run: the graph, the nogood tables and the per-stage counters."""

    def __init__(self, task: Task) -> None:
        self.task = task
        self.fact_names: list[Fact] = list(task.facts)
        fid = {f: i for i, f in enumerate(self.fact_names)}
        self.fid = fid
        # Real actions keep the task's name order, so comparing ids compares names.
        self.ops: list[_Op] = [
            _Op(
                a.name,
                frozenset(fid[p] for p in a.pre),
                frozenset(fid[p] for p in a.add),
                frozenset(fid[p] for p in a.delete),
                False,
            )
            for a in task.actions
        ]
        self.n_real = len(self.ops)
        for i, f in enumerate(self.fact_names):
            one = frozenset((i,))
            self.ops.append(_Op(f"noop {f}", one, one, frozenset(), True))
        self.levels: list[_Level] = [_Level(frozenset(fid[f] for f in task.init), set())]
        self.nogoods: list[set[frozenset[int]]] = [set()]
        self.attempts = 0
        self.memo_hits = 0
        self.nogoods_added = 0

    # -- expansion --

    def expand(self) -> None:
        prev = self.levels[-1]
        pm = prev.prop_mutex
        acts = [
            i
            for i in range(self.n_real)
            if self.ops[i].pre <= prev.props
            and not any(_pair(p, q) in pm for p, q in itertools.combinations(self.ops[i].pre, 2))
        ]
        acts += [self.n_real + p for p in sorted(prev.props)]
        amutex: set[tuple[int, int]] = set()
        for a, b in itertools.combinations(acts, 2):
            if self._actions_mutex(self.ops[a], self.ops[b], pm):
                amutex.add(_pair(a, b))
        achievers: dict[int, list[int]] = {}
        for a in acts:
            for p in self.ops[a].add:
                achievers.setdefault(p, []).append(a)
        for lst in achievers.values():
            # No-op first, then real actions by name: the deterministic tie-break of §2.2.
            lst.sort(key=lambda a: (not self.ops[a].noop, a))
        props = frozenset(achievers)
        pmutex: set[tuple[int, int]] = set()
        for p, q in itertools.combinations(sorted(props), 2):
            if all(a != b and _pair(a, b) in amutex for a in achievers[p] for b in achievers[q]):
                pmutex.add((p, q))
        self.levels.append(_Level(props, pmutex, acts, amutex, achievers))
        self.nogoods.append(set())

    @staticmethod
    def _actions_mutex(a: _Op, b: _Op, prev_mutex: set[tuple[int, int]]) -> bool:
        # Inconsistent effects: one deletes what the other adds.
        if a.delete & b.add or b.delete & a.add:
            return True
        # Interference: one deletes a precondition of the other.
        if a.delete & b.pre or b.delete & a.pre:
            return True
        # Competing needs: some pair of preconditions is mutex one level down.
        return any(_pair(p, q) in prev_mutex for p in a.pre for q in b.pre if p != q)

    # -- queries --

    def goals_status(self, level: int) -> tuple[bool, bool]:
        lv = self.levels[level]
        goals = [self.fid[g] for g in sorted(self.task.goal)]
        present = all(g in lv.props for g in goals)
        nonmutex = present and not any(_pair(p, q) in lv.prop_mutex for p, q in itertools.combinations(goals, 2))
        return present, nonmutex

    def leveled(self) -> bool:
        """Whether the newest level equals the one before (same propositions and mutexes)."""
        if len(self.levels) < 2:
            return False
        a, b = self.levels[-2], self.levels[-1]
        return a.props == b.props and a.prop_mutex == b.prop_mutex

    # -- extraction --

    def extract(self, goals: frozenset[int], level: int) -> list[list[int]] | None:
        """Backward search: layers of chosen op ids for levels 1..level, or None (then memoised)."""
        if level == 0:
            return []
        if goals in self.nogoods[level]:
            self.memo_hits += 1
            return None
        self.attempts += 1
        ordered = sorted(goals, key=lambda g: self.fact_names[g])
        found = self._assign(ordered, 0, [], level)
        if found is None:
            self.nogoods[level].add(goals)
            self.nogoods_added += 1
        return found

    def _assign(self, goals: list[int], k: int, chosen: list[int], level: int) -> list[list[int]] | None:
        if k == len(goals):
            sub = frozenset().union(*(self.ops[a].pre for a in chosen))
            below = self.extract(sub, level - 1)
            return None if below is None else [*below, sorted(chosen)]
        g = goals[k]
        if any(g in self.ops[a].add for a in chosen):
            return self._assign(goals, k + 1, chosen, level)
        amutex = self.levels[level].action_mutex
        for a in self.levels[level].achievers.get(g, []):
            if any(_pair(a, c) in amutex for c in chosen):
                continue
            chosen.append(a)
            found = self._assign(goals, k + 1, chosen, level)
            chosen.pop()
            if found is not None:
                return found
        return None

    def row(self, level: int, extraction: str) -> LevelStats:
        lv = self.levels[level]
        present, nonmutex = self.goals_status(level)
        real = sum(1 for a in lv.actions if not self.ops[a].noop)
        return LevelStats(
            level=level,
            props=len(lv.props),
            actions=real,
            noops=len(lv.actions) - real,
            prop_mutexes=len(lv.prop_mutex),
            action_mutexes=len(lv.action_mutex),
            goals_present=present,
            goals_nonmutex=nonmutex,
            extraction=extraction,
            attempts=self.attempts,
            memo_hits=self.memo_hits,
            nogoods_added=self.nogoods_added,
            nogoods=0,  # filled in at the end, when the tables are final
        )


def graphplan(task: Task, max_levels: int | None = None) -> GraphplanResult:
    """Plan with GRAPHPLAN; returns the layered plan (or why there is none) and the level table.

    Termination (§2.1 item 5): the graph has leveled off at level L when P_L equals P_{L-1} with
    the same mutex pairs. After that, no plan exists if the goals are absent or mutex at L, or if
    two successive failed stages leave the number of nogoods memoised at level L unchanged.

    Args:
        task: a grounded STRIPS task (:func:`xabsl_studio.engine.planning.strips.load_task`).
        max_levels: optional safety cap on graph levels; level-off alone guarantees termination.

    Returns:
        A :class:`GraphplanResult`; ``result.plan`` is None when the task is unsolvable.
    """
    started = time.perf_counter()
    pl = _Planner(task)
    rows: list[LevelStats] = []
    leveled_at: int | None = None
    prev_nogoods_at_leveled: int | None = None
    plan: LayeredPlan | None = None
    reason = ""
    while True:
        n = len(pl.levels) - 1
        pl.attempts = pl.memo_hits = pl.nogoods_added = 0
        _, nonmutex = pl.goals_status(n)
        if nonmutex:
            found = pl.extract(frozenset(pl.fid[g] for g in task.goal), n)
            rows.append(pl.row(n, "success" if found is not None else "failed"))
            if found is not None:
                plan = _to_plan(task, pl, found)
                reason = f"plan found with {len(plan)} steps at level {n}"
                break
            if leveled_at is not None:
                count = len(pl.nogoods[leveled_at])
                if count == prev_nogoods_at_leveled:
                    reason = (
                        f"no plan: graph leveled off at level {leveled_at} and the nogoods "
                        f"memoised there stayed at {count} over two failed stages"
                    )
                    break
                prev_nogoods_at_leveled = count
        else:
            rows.append(pl.row(n, "none"))
            if leveled_at is not None:
                reason = f"no plan: graph leveled off at level {leveled_at} with the goals absent or mutually exclusive"
                break
        if max_levels is not None and n >= max_levels:
            reason = f"no plan within {max_levels} levels"
            break
        pl.expand()
        if leveled_at is None and pl.leveled():
            leveled_at = len(pl.levels) - 2
            if prev_nogoods_at_leveled is None and rows[-1].extraction == "failed":
                prev_nogoods_at_leveled = len(pl.nogoods[leveled_at])
    final = tuple(dataclasses.replace(r, nogoods=len(pl.nogoods[r.level])) for r in rows)
    return GraphplanResult(plan, final, leveled_at, reason, time.perf_counter() - started)


def _to_plan(task: Task, pl: _Planner, found: list[list[int]]) -> LayeredPlan:
    layers = []
    for step in found:
        real = [task.actions[a] for a in step if a < pl.n_real]
        if real:
            layers.append(tuple(sorted(real)))
    return LayeredPlan(tuple(layers))


def format_stats(stats: Sequence[LevelStats]) -> str:
    """Render the §2.4 table as text (what the CLI and the docs print)."""
    head = "level |P| |A| noops p-mutex a-mutex goals        extraction attempts nogoods"
    lines = [head]
    for s in stats:
        goals = "non-mutex" if s.goals_nonmutex else ("mutex" if s.goals_present else "absent")
        lines.append(
            f"{s.level:5d} {s.props:3d} {s.actions:3d} {s.noops:5d} {s.prop_mutexes:7d} "
            f"{s.action_mutexes:7d} {goals:12s} {s.extraction:10s} {s.attempts:8d} {s.nogoods:7d}"
        )
    return "\n".join(lines)
