"""Why an option's decision did *not* go to a state: what stood in the way on each route there.

"Why" (:func:`~xabsl_studio.engine.runtime.debug.explain_decision`) walks the decision tree to
the leaf the decision took. "Why not" walks it to every *other* leaf that targets a given state
(a ``goto target`` or, for the decided-in state itself, a ``stay``) and evaluates each condition
on the way from **the same values** (a :class:`~xabsl_studio.engine.runtime.debug.Values`
source, :class:`~xabsl_studio.engine.runtime.debug.ReadValues` for what the decision read).

A route is blocked by the first condition whose value is not the branch it needs. The decision
evaluated every condition shared with the path it took, so the first blocker of a route that
leaves that path is the ``if`` where it leaves it, with the value the decision saw there: "why
not" cannot contradict "why". Conditions past that point were not evaluated by the decision;
their values are known only when the decision read the same values elsewhere, else unknown
(None, ``?``), never asked of a host again.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator
from dataclasses import dataclass

from xabsl_studio.engine.errors import DebugError
from xabsl_studio.engine.ir.model import Expression, If, Option, State, Transition, leaf_path
from xabsl_studio.engine.runtime.debug import (
    Condition,
    Unknown,
    Values,
    comparisons,
    evaluate,
    explain_decision,
    show_value,
    span_text,
)
from xabsl_studio.engine.types import Value

__all__ = ["Route", "WhyNot", "explain_why_not", "leaves"]


@dataclass(frozen=True, slots=True)
class Route:
    """One leaf targeting the asked-for state and the conditions on the way to it.

    Each condition's ``branch`` is the branch this route needs (not the one the decision took).
    """

    leaf: int
    stay: bool
    conditions: tuple[Condition, ...]
    #: index into ``conditions`` of the first one whose known value is not the branch needed
    #: (None: nothing known blocks it: the leaf taken, or values the source does not have)
    blocked_at: int | None
    #: the index of the ``if`` where this route leaves the path the decision took (None: the leaf taken)
    leaves_taken_path_at: int | None

    @property
    def blocker(self) -> Condition | None:
        """The condition that stood in the way (None: none known)."""
        return None if self.blocked_at is None else self.conditions[self.blocked_at]


@dataclass(frozen=True, slots=True)
class WhyNot:
    """Why ``option``'s decision in ``decided_in`` (which took ``leaf`` to ``went_to``) did not go to ``target``."""

    option: str
    decided_in: str
    target: str
    leaf: int
    went_to: str
    #: the decision did go to ``target`` (then one route is the leaf taken)
    went: bool
    routes: tuple[Route, ...]

    def __str__(self) -> str:
        head = f"{self.option}.{self.decided_in}: why not {self.target} (went to {self.went_to}, leaf {self.leaf})"
        if self.went:
            head += f": the decision went to {self.target}"
        if not self.routes:
            return f"{head}\n  no transition of {self.decided_in} leads to {self.target}"
        lines = [head]
        for route in self.routes:
            lines.append(f"  leaf {route.leaf}{' (taken)' if route.leaves_taken_path_at is None else ''}:")
            for i, c in enumerate(route.conditions):
                mark = "✗" if i == route.blocked_at else " "
                value = "?" if c.value is None else show_value(c.value)
                lines.append(f"   {mark} ({c.text or c.source}) needs {show_value(c.branch)}, is {value}")
                lines.extend(f"        {comparison}" for comparison in c.comparisons)
        return "\n".join(lines)


def leaves(tree: If | Transition) -> Iterator[Transition]:
    """The leaves of a decision tree, in pre-order (their ``leaf`` ids)."""
    if isinstance(tree, Transition):
        yield tree
    else:
        yield from leaves(tree.then)
        yield from leaves(tree.otherwise)


def explain_why_not(
    option: Option,
    state: State,
    leaf: int,
    target: str,
    values: Values,
    text: Callable[[Expression], str] | None = None,
) -> WhyNot:
    """Why ``option``'s decision in ``state``, which took ``leaf``, did not go to state ``target``.

    ``values`` are the decision's (the same source "why" reads); ``text`` gives an operand's source
    as in :func:`~xabsl_studio.engine.runtime.debug.explain_decision`.

    Raises:
        DebugError: ``target`` is no state of ``option``.
        KeyError: ``state`` has no leaf ``leaf``.
    """
    if target not in {s.name for s in option.states}:
        raise DebugError(f"option {option.name} has no state {target}")
    taken = explain_decision(option, state, leaf, values, text)
    taken_path = leaf_path(state.decision, leaf)
    routes = []
    for transition in leaves(state.decision):
        goes_to = transition.target or state.name
        if goes_to != target:
            continue
        path = leaf_path(state.decision, transition.leaf)
        conditions = tuple(_condition(option, node, branch, values, text) for node, branch in path)
        blocked_at = next(
            (i for i, c in enumerate(conditions) if c.value is not None and bool(c.value) is not c.branch), None
        )
        routes.append(Route(transition.leaf, goes_to == state.name, conditions, blocked_at, _parting(taken_path, path)))
    return WhyNot(option.name, state.name, target, leaf, taken.target, taken.target == target, tuple(routes))


def _parting(taken: list[tuple[If, bool]], route: list[tuple[If, bool]]) -> int | None:
    """Where ``route`` leaves the ``taken`` path: the index of the first ``if`` whose branch differs."""
    for i, ((node, branch), (other, needed)) in enumerate(zip(taken, route, strict=False)):
        assert node is other  # both paths start at the root and share nodes until they part
        if branch is not needed:
            return i
    return None


def _condition(
    option: Option, node: If, branch: bool, values: Values, text: Callable[[Expression], str] | None
) -> Condition:
    try:
        value: Value | None = evaluate(node.condition, values)
    except (Unknown, ArithmeticError, DebugError, ValueError, TypeError):
        value = None
    cut = text if text is not None else functools.partial(span_text, node, option.name)
    return Condition(
        node.text, cut(node.condition), value, branch, node.condition.span, comparisons(node.condition, values, cut)
    )
