"""The host side of plan execution: the plan board an XABSL plan monitor reads and drives (§4.1, §4.2 P2).

The plan monitor itself is XABSL (in the errands example, the option ``execute_plan``): it
decides which operator runs, when an operator is done (from derived facts), when it timed out
(``state_time``), when to replan and when the errand is finished or failed. The host gives it a
:class:`PlanBoard` as input symbols and basic behaviors; this module is that board, for any
STRIPS domain:

* the *queue*: the operators of the layered GRAPHPLAN plan, layer by layer, names sorted inside
  a layer; operators the monitor marked done (:meth:`PlanBoard.complete`) stay done;
* :meth:`PlanBoard.next_executable`: the first not-done operator of the queue whose
  preconditions hold in the derived facts (evaluating STRIPS preconditions is data work; what to
  do about the answer is the monitor's);
* :meth:`PlanBoard.plan_from`: GRAPHPLAN from the derived facts (§4.1 ``replan(F)``), counted as
  a replan unless it is the first plan;
* partial plans, through a domain's :class:`PartialGoals`: when the full goal is unsolvable from
  the facts, the board may plan for the goal facts the domain says are still reachable and mark
  the plan *partial*; :meth:`PlanBoard.can_extend` tells the monitor when the domain says the
  dropped goals are reachable again. A partial plan that would be empty counts as no plan, so a
  monitor cannot loop on it.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Protocol

from xabsl_studio.engine.planning.graphplan import GraphplanResult, LayeredPlan, graphplan
from xabsl_studio.engine.planning.strips import Fact, GroundAction, Task


@dataclass(frozen=True, slots=True)
class BoardEvent:
    """Something the plan board did at time ``t`` (for the plan view and the run summary).

    ``kind`` is one of ``planned``, ``replanned``, ``partial``, ``no_plan``, ``done``.
    """

    t: float
    kind: str
    detail: str

    def to_json(self) -> dict[str, object]:
        """The event as plain data."""
        return {"t": round(self.t, 3), "kind": self.kind, "detail": self.detail}


class PartialGoals(Protocol):
    """A domain's rule for planning without the goals that cannot be reached from the facts."""

    def relax(self, goal: frozenset[Fact], facts: frozenset[Fact]) -> tuple[frozenset[Fact], str] | None:
        """Return the goal facts to plan for instead of the unsolvable ``goal``, and why in words.

        None: the domain sees no goal to drop (the board then reports GRAPHPLAN's reason).
        """
        ...

    def can_extend(self, dropped: frozenset[Fact], facts: frozenset[Fact]) -> bool:
        """Return whether some of the ``dropped`` goals look reachable again from ``facts``."""
        ...


@dataclass
class PlanBoard:
    """A layered plan with done marks, the queries an XABSL plan monitor needs, and replanning.

    Attributes:
        task: the grounded planning task; each (re)plan starts from the facts it is given.
        partial: the domain's rule for partial plans (None: an unsolvable goal is no plan).
        plan: the current layered plan (None before planning or when no plan exists).
        queue: the plan's operators in execution order.
        done: names of queue operators the monitor marked done.
        dropped: goal facts the current (partial) plan leaves out.
        replans: plans made after the first.
        solved: whether the last planning produced a usable plan.
        reason: why the last planning failed or was partial, in words.
        events: what the board did, in order.
        results: every GRAPHPLAN result (statistics), partial attempts included.
        plans: every plan the board executed.
    """

    task: Task
    partial: PartialGoals | None = None
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
        """Return the first not-done operator whose preconditions hold in ``facts``, or None."""
        for a in self.queue:
            if a.name not in self.done and a.pre <= facts:
                return a
        return None

    def goal_holds(self, facts: frozenset[Fact]) -> bool:
        """Return whether every goal fact of the task is derived."""
        return self.task.goal <= facts

    def can_extend(self, facts: frozenset[Fact]) -> bool:
        """Return whether a partial plan could now cover more of the goal (the domain decides)."""
        return bool(self.dropped) and self.partial is not None and self.partial.can_extend(self.dropped, facts)

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
            relaxed = self.partial.relax(full.goal, state) if self.partial is not None else None
            if relaxed is None:
                self.reason = f"no plan from the derived facts: {result.reason}"
                return self._no_plan(t, detail + self.reason, result)
            keep, why = relaxed
            partial = graphplan(full.with_goal(keep))
            self.results.append(partial)
            if partial.plan is None or len(partial.plan) == 0:
                self.reason = f"no plan from the derived facts: {why}"
                return self._no_plan(t, detail + self.reason, result)
            result = partial
            self.dropped = full.goal - keep
            kind = "partial"
            detail += f"{why}; planning without {', '.join(sorted(self.dropped))}: "
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
