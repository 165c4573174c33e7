"""Plan monitor support: the operator queue the XABSL plan monitor reads (doc §4.1 PlanLayer, §4.2 P2).

This module owns the *data* side of plan execution in the Hertzberg et al. (1998) style: which
operator of a layered GRAPHPLAN plan is current, which are done, which timed out, and replanning
from the derived facts. It does not bias behaviors (that is the switch variables s_OP of
:mod:`engine.dynamics`) and it does not decide when to call it (that is the XABSL option
``execute_plan``, whose states ``select``/``run_*``/``replan``/``finished``/``failed`` mirror
:class:`PlanStatus`).

Rules (§4.1, borrowing per-operator guards and timeouts from PlanSys2, §3):

* ``current`` is the first not-done operator in queue order (layer by layer, names sorted within
  a layer) whose preconditions hold in the derived facts F. One operator at a time, as the paper's
  monitor does; the two parallel UNLOADs of level 6 therefore run one after the other.
* ``done ⇔ add ⊆ F ∧ del ∩ F = ∅``, latched once observed. Done is only recognised for an
  operator that has been current or whose layer is open (all earlier layers done): otherwise
  ``goto b a`` would count as done at t=0 of the errands plan, simply because the robot starts at a.
* A current operator that stays not-done longer than its schema's timeout (GOTO 60 s, LOAD 30 s,
  UNLOAD 10 s by default) fails; the monitor then asks for a replan, and so it does when no
  remaining operator is executable.
* :meth:`PlanMonitor.replan` runs GRAPHPLAN from the current facts and restarts the queue.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

from engine.planning.graphplan import GraphplanResult, LayeredPlan, graphplan
from engine.planning.strips import Fact, GroundAction, Task

#: Per-schema timeouts in seconds (§4.1); any schema not listed uses ``default_timeout``.
DEFAULT_TIMEOUTS: Mapping[str, float] = {"goto": 60.0, "load": 30.0, "unload": 10.0}


class OpStatus(enum.Enum):
    """Where one queued operator stands."""

    PENDING = "pending"
    CURRENT = "current"
    DONE = "done"
    FAILED = "failed"


class PlanStatus(enum.Enum):
    """``plan.status`` of §4.2: what the monitor as a whole is doing."""

    IDLE = "idle"
    EXECUTING = "executing"
    REPLANNING = "replanning"
    DONE = "done"
    FAILED = "failed"


@dataclass(slots=True)
class QueuedOp:
    """One operator of the plan with its execution bookkeeping."""

    action: GroundAction
    layer: int
    status: OpStatus = OpStatus.PENDING
    started_at: float | None = None
    finished_at: float | None = None
    was_current: bool = False

    @property
    def name(self) -> str:
        """The ground action name, e.g. ``"goto a c"``."""
        return self.action.name


@dataclass(frozen=True, slots=True)
class MonitorEvent:
    """Something the monitor decided at time ``t``; the debugger's plan-view log."""

    t: float
    kind: str  # current | done | timeout | blocked | replanned | finished | failed
    op: str | None
    detail: str = ""


def is_done(action: GroundAction, facts: frozenset[Fact]) -> bool:
    """Check the §4.1 done test: all add effects hold and no delete effect does."""
    return action.add <= facts and not (action.delete & facts)


@dataclass
class PlanMonitor:
    """Operator queue over a layered plan: select, recognise done, time out, replan.

    Attributes:
        task: the grounded task (its goal decides ``DONE``; replanning changes its init).
        timeouts: per-schema timeouts in seconds.
        default_timeout: timeout for schemas missing from ``timeouts``.
        max_replans: after this many replans a further request ends in ``FAILED``.
    """

    task: Task
    plan: LayeredPlan | None = None
    timeouts: Mapping[str, float] = field(default_factory=lambda: dict(DEFAULT_TIMEOUTS))
    default_timeout: float = 60.0
    max_replans: int = 3
    status: PlanStatus = PlanStatus.IDLE
    reason: str = ""
    replans: int = 0
    queue: list[QueuedOp] = field(default_factory=list)
    events: list[MonitorEvent] = field(default_factory=list)
    last_result: GraphplanResult | None = None

    def __post_init__(self) -> None:
        if self.plan is not None:
            self._load(self.plan, 0.0)

    # -- queries --

    @property
    def current(self) -> GroundAction | None:
        """The operator to execute now (σ_OP = 1 for it), or None."""
        for q in self.queue:
            if q.status is OpStatus.CURRENT:
                return q.action
        return None

    def timeout_for(self, action: GroundAction) -> float:
        """Return the timeout of ``action``'s schema in seconds."""
        return float(self.timeouts.get(action.schema, self.default_timeout))

    def snapshot(self) -> dict[str, object]:
        """Plain data for input symbols and the plan view: status, current op, per-op state."""
        cur = self.current
        return {
            "status": self.status.value,
            "current_op": cur.name if cur is not None else None,
            "reason": self.reason,
            "replans": self.replans,
            "ops": [{"name": q.name, "layer": q.layer, "status": q.status.value} for q in self.queue],
        }

    # -- control --

    def start(self, facts: Iterable[Fact], t: float) -> GraphplanResult:
        """Plan from ``facts`` (usually the problem's init) and start executing."""
        return self._plan_from(facts, t, counts_as_replan=False)

    def replan(self, facts: Iterable[Fact], t: float) -> GraphplanResult | None:
        """Run GRAPHPLAN from the current derived facts and restart the queue on the new plan.

        Raises nothing for an unsolvable state: the monitor ends in ``FAILED`` with the reason.

        Returns:
            The planner's result, or None when ``max_replans`` was already used up (``FAILED``).
        """
        if self.replans >= self.max_replans:
            self._fail(t, f"gave up after {self.replans} replans")
            return None
        return self._plan_from(facts, t, counts_as_replan=True)

    def update(self, facts: Iterable[Fact], t: float) -> PlanStatus:
        """One monitor tick at time ``t`` (seconds) with derived facts ``facts``.

        Returns:
            The new status. ``REPLANNING`` means the caller should call :meth:`replan` (the XABSL
            option does so in its ``replan`` state); ``DONE`` and ``FAILED`` are final.
        """
        if self.status in (PlanStatus.IDLE, PlanStatus.DONE, PlanStatus.FAILED):
            return self.status
        state = frozenset(facts) - self.task.statics
        if self.task.goal <= state:
            self._set_current(None, t)
            self.status = PlanStatus.DONE
            self.reason = "goal holds"
            self.events.append(MonitorEvent(t, "finished", None, "goal holds"))
            return self.status
        self._recognise_done(state, t)
        cur = self._current_queued()
        if cur is not None and cur.started_at is not None:
            limit = self.timeout_for(cur.action)
            if t - cur.started_at > limit:
                cur.status = OpStatus.FAILED
                cur.finished_at = t
                self.status = PlanStatus.REPLANNING
                self.reason = f"{cur.name} timed out after {limit:g} s"
                self.events.append(MonitorEvent(t, "timeout", cur.name, self.reason))
                return self.status
        nxt = next(
            (q for q in self.queue if q.status in (OpStatus.PENDING, OpStatus.CURRENT) and q.action.pre <= state),
            None,
        )
        if nxt is None:
            self._set_current(None, t)
            self.status = PlanStatus.REPLANNING
            self.reason = "no remaining operator is executable in the derived facts"
            self.events.append(MonitorEvent(t, "blocked", None, self.reason))
            return self.status
        self._set_current(nxt, t)
        self.status = PlanStatus.EXECUTING
        return self.status

    # -- internals --

    def _plan_from(self, facts: Iterable[Fact], t: float, counts_as_replan: bool) -> GraphplanResult:
        task = self.task.with_init(facts)
        result = graphplan(task)
        self.task = task
        self.last_result = result
        if counts_as_replan:
            self.replans += 1
        if result.plan is None:
            self._fail(t, result.reason)
            return result
        self._load(result.plan, t)
        kind = "replanned" if counts_as_replan else "planned"
        self.events.append(MonitorEvent(t, kind, None, str(result.plan)))
        return result

    def _load(self, plan: LayeredPlan, t: float) -> None:
        self.plan = plan
        self.queue = [QueuedOp(a, i + 1) for i, layer in enumerate(plan.layers) for a in layer]
        self.status = PlanStatus.EXECUTING
        self.reason = ""

    def _fail(self, t: float, reason: str) -> None:
        self._set_current(None, t)
        self.status = PlanStatus.FAILED
        self.reason = reason
        self.events.append(MonitorEvent(t, "failed", None, reason))

    def _current_queued(self) -> QueuedOp | None:
        return next((q for q in self.queue if q.status is OpStatus.CURRENT), None)

    def _open_layer(self) -> int:
        return min((q.layer for q in self.queue if q.status is not OpStatus.DONE), default=0)

    def _recognise_done(self, state: frozenset[Fact], t: float) -> None:
        # Repeat because finishing a layer opens the next, whose ops may already be done.
        changed = True
        while changed:
            changed = False
            open_layer = self._open_layer()
            for q in self.queue:
                if q.status in (OpStatus.DONE, OpStatus.FAILED):
                    continue
                if not (q.was_current or q.layer == open_layer):
                    continue
                if is_done(q.action, state):
                    q.status = OpStatus.DONE
                    q.finished_at = t
                    self.events.append(MonitorEvent(t, "done", q.name))
                    changed = True

    def _set_current(self, q: QueuedOp | None, t: float) -> None:
        old = self._current_queued()
        if old is q:
            return
        if old is not None:
            old.status = OpStatus.PENDING
        if q is not None:
            q.status = OpStatus.CURRENT
            q.was_current = True
            if q.started_at is None:
                q.started_at = t
            self.events.append(MonitorEvent(t, "current", q.name))
