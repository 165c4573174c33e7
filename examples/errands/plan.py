"""The host side of plan execution: the GRAPHPLAN plan the XABSL monitor reads, and replanning.

The plan monitor itself is the XABSL option ``execute_plan`` (behavior/execute_plan.xabsl,
pattern P2 of doc §4.2): it decides which operator runs, when an operator is done (from derived
facts), when it timed out (``state_time``), when to replan and when the errand is finished or
failed. This module is what that option reads and calls, as input symbols and basic behaviors:

* ``plan.next.*``: the first operator of the plan, in queue order (layer by layer, names sorted
  inside a layer), that is not done and whose preconditions hold in the derived facts; schema
  ``none`` if there is none. Evaluating STRIPS preconditions is data work the host does for any
  domain; *deciding* what to do about it is the monitor's.
* ``plan.goal_holds``, ``plan.solved``, ``plan.replans``, ``plan.can_extend``.
* the basic behavior ``plan_from_facts(reason)``: run GRAPHPLAN from the derived facts, and
  ``complete_operator``: mark the monitor's operator done in the queue.

Replanning from derived facts (§4.1 ``replan(F)``) with one addition [D]: when the derived facts
no longer place an object anywhere (it was searched for and not found), the full goal is
unsolvable, so the board plans for the goal facts that do not need that object and marks the
plan *partial*. As soon as the derived facts place the object again (the robot saw it
somewhere), ``plan.can_extend`` becomes true and the monitor replans for the whole goal. A
partial plan that would be empty counts as no plan, so the monitor cannot loop on it.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

from engine.planning.graphplan import GraphplanResult, LayeredPlan, graphplan
from engine.planning.strips import Fact, GroundAction, Task


@dataclass(frozen=True, slots=True)
class BoardEvent:
    """Something the plan board did at time ``t`` (for the plan view and the run summary)."""

    t: float
    kind: str  # planned | replanned | partial | no_plan | done
    detail: str

    def to_json(self) -> dict[str, object]:
        return {"t": round(self.t, 3), "kind": self.kind, "detail": self.detail}


@dataclass
class PlanBoard:
    """A layered plan with done marks, the queries the XABSL monitor needs, and replanning.

    Attributes:
        task: the grounded planning task; its ``init`` is replaced on every (re)plan.
        plan: the current layered plan (None before planning or when no plan exists).
        done: names of queue operators the monitor marked done.
        dropped: goal facts the current (partial) plan leaves out.
        replans: plans made after the first.
        solved: whether the last planning produced a usable plan.
        reason: why the last planning failed or was partial, in words.
    """

    task: Task
    plan: LayeredPlan | None = None
    queue: list[GroundAction] = field(default_factory=list)
    done: set[str] = field(default_factory=set)
    dropped: frozenset[Fact] = frozenset()
    replans: int = 0
    solved: bool = False
    reason: str = ""
    events: list[BoardEvent] = field(default_factory=list)
    results: list[GraphplanResult] = field(default_factory=list)
    plans: list[LayeredPlan] = field(default_factory=list)

    # -- queries (input symbols) ----------------------------------------------------------------

    def next_executable(self, facts: frozenset[Fact]) -> GroundAction | None:
        """The first not-done operator whose preconditions hold in ``facts``, or None."""
        for a in self.queue:
            if a.name not in self.done and a.pre <= facts:
                return a
        return None

    def goal_holds(self, facts: frozenset[Fact]) -> bool:
        """Whether every goal fact of the task is derived."""
        return self.task.goal <= facts

    def can_extend(self, facts: frozenset[Fact]) -> bool:
        """A partial plan could now cover more: a dropped goal's object is located again."""
        return bool(self.dropped) and any(_located(o, facts) for o in _items_of(self.dropped))

    # -- actions (basic behaviors) ----------------------------------------------------------------

    def complete(self, name: str, t: float) -> None:
        """Mark operator ``name`` done (the monitor recognised its effects in the derived facts)."""
        if name not in self.done:
            self.done.add(name)
            self.events.append(BoardEvent(t, "done", name))

    def plan_from(self, facts: Iterable[Fact], t: float, reason: str = "start") -> GraphplanResult:
        """Run GRAPHPLAN from the derived ``facts`` and restart the queue on the result.

        Args:
            facts: the derived facts (the problem's init for the first plan).
            t: simulation time (s), for the event log.
            reason: why the monitor asked (``start`` for the first plan; any other counts as a replan).
        """
        state = frozenset(facts)
        if reason != "start":
            self.replans += 1
        full = self.task.with_init(state).with_goal(self.task.goal)
        result = graphplan(full)
        self.results.append(result)
        self.dropped = frozenset()
        kind = "planned" if reason == "start" else "replanned"
        detail = f"({reason}) "
        if result.plan is None:
            unknown = sorted(o for o in _items_of(full.goal) if not _located(o, state))
            if unknown:
                keep = frozenset(g for g in full.goal if not (set(g.split()[1:]) & set(unknown)))
                partial = graphplan(full.with_goal(keep))
                self.results.append(partial)
                where = ", ".join(unknown)
                if partial.plan is not None and len(partial.plan) > 0:
                    result = partial
                    self.dropped = full.goal - keep
                    kind = "partial"
                    detail += f"location of {where} unknown; planning without {', '.join(sorted(self.dropped))}: "
                else:
                    self.reason = f"no plan from the derived facts: location of {where} unknown"
                    return self._no_plan(t, detail + self.reason, result)
            else:
                self.reason = f"no plan from the derived facts: {result.reason}"
                return self._no_plan(t, detail + self.reason, result)
        assert result.plan is not None
        self.plan = result.plan
        self.plans.append(result.plan)
        self.queue = result.plan.actions()
        self.done = set()
        self.solved = True
        self.reason = "" if not self.dropped else f"partial plan: {', '.join(sorted(self.dropped))} left out"
        self.events.append(BoardEvent(t, kind, detail + str(result.plan)))
        return result

    def _no_plan(self, t: float, detail: str, result: GraphplanResult) -> GraphplanResult:
        self.plan = None
        self.queue = []
        self.done = set()
        self.solved = False
        self.events.append(BoardEvent(t, "no_plan", detail))
        return result

    # -- data -------------------------------------------------------------------------------------

    def to_json(self) -> dict[str, object]:
        """The plan view: layers with per-operator done marks, replans, dropped goals, reason."""
        layers = (
            []
            if self.plan is None
            else [[{"op": a.name, "done": a.name in self.done} for a in layer] for layer in self.plan.layers]
        )
        return {
            "layers": layers,
            "solved": self.solved,
            "replans": self.replans,
            "dropped": sorted(self.dropped),
            "reason": self.reason,
        }


def _items_of(goal: Iterable[Fact]) -> set[str]:
    """Objects that ``at``/``has-robot`` goal facts are about."""
    out = set()
    for g in goal:
        words = g.split()
        if words[0] in ("at", "has-robot"):
            out.add(words[1])
    return out


def _located(item: str, facts: Iterable[Fact]) -> bool:
    """Whether the facts say where ``item`` is (lying somewhere, or held)."""
    return any(f == f"has-robot {item}" or f.startswith(f"at {item} ") for f in facts)
