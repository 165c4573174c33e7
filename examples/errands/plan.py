"""The errands domain's rule for partial plans, on the generic plan board (``xabsl_studio.engine.planning.monitor``).

The plan monitor is the XABSL option ``execute_plan`` (behavior/execute_plan.xabsl, pattern P2
of doc §4.2); the data it reads and drives is an :class:`xabsl_studio.engine.planning.monitor.PlanBoard`
(``plan.next.*``, ``plan.goal_holds``, ``plan.solved``, ``plan.replans``, ``plan.can_extend``,
the basic behaviors ``plan_from_facts`` and ``complete_operator``). What is the errands' own:

Replanning from derived facts (§4.1 ``replan(F)``) with one addition [D]: when the derived facts
no longer place an object anywhere (it was searched for and not found), the full goal is
unsolvable, so the board plans for the goal facts that do not need that object and marks the
plan *partial* (:class:`UnlocatedItems`). As soon as the derived facts place the object again
(the robot saw it somewhere), ``plan.can_extend`` becomes true and the monitor replans for the
whole goal.
"""

from __future__ import annotations

from collections.abc import Iterable

from xabsl_studio.engine.planning.monitor import PlanBoard
from xabsl_studio.engine.planning.strips import Fact, Task


class UnlocatedItems:
    """Partial goals of the errands domain: leave out the goals about objects no fact places."""

    def relax(self, goal: frozenset[Fact], facts: frozenset[Fact]) -> tuple[frozenset[Fact], str] | None:
        """Return the goals that need no unlocated object, and which objects are unlocated."""
        unknown = sorted(o for o in _items_of(goal) if not _located(o, facts))
        if not unknown:
            return None
        keep = frozenset(g for g in goal if not (set(g.split()[1:]) & set(unknown)))
        return keep, f"location of {', '.join(unknown)} unknown"

    def can_extend(self, dropped: frozenset[Fact], facts: frozenset[Fact]) -> bool:
        """Return whether an object of a dropped goal is located again."""
        return any(_located(o, facts) for o in _items_of(dropped))


def errands_board(task: Task) -> PlanBoard:
    """The plan board of the errands robot: ``task`` with the :class:`UnlocatedItems` rule."""
    return PlanBoard(task, UnlocatedItems())


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
