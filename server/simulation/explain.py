"""The ``explain`` result as the protocol sends it, built from an engine ``Explanation``.

One shape for every way the studio answers "why", each from what the decision read in its tick
(``ReadValues`` over ``Engine.reads()``): the live engine's last tick (``Debugger.explain``), a
past tick of the ring (``explain_decision`` over the reads the ring kept) and a tick of a
replayed recording (``explain_decision`` over the recording's reads and the program rebuilt from
its intermediate code). The decisions themselves are evaluated by ``xabsl_studio.engine.runtime.debug``; this
module only lays the answer out: ids, names, the leaf's span, each condition with its value,
branch and comparisons, the decision tree with the path taken, and "why not" a state (the routes
to it, ``xabsl_studio.engine.runtime.whynot``) from the same values.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

from xabsl_studio.engine.errors import DebugError
from xabsl_studio.engine.ir.model import Expression, If, Option, State, Transition, leaf_path
from xabsl_studio.engine.runtime.debug import Condition, Explanation, Values, decision_tree, render
from xabsl_studio.engine.runtime.whynot import explain_why_not
from xabsl_studio.engine.types import SpanJson

__all__ = [
    "condition_result",
    "copy_texts",
    "explanation_result",
    "if_text",
    "mark_values",
    "source_texts",
    "tree_result",
    "why_not_result",
    "why_not_state",
]


def explanation_result(option: Option, explanation: Explanation) -> dict[str, Any]:
    """The ``explain`` result of ``option``'s decision (ids are the IR's: the description's ids)."""
    states = {s.name: s.index for s in option.states}
    decided = option.state(explanation.decided_in)
    # The leaf's own span, so the editor can point at the transition that fired.
    try:
        leaf_span = _leaf_span(decided, explanation.leaf)
    except KeyError:
        leaf_span = None
    return {
        "option": option.index,
        "option_name": option.name,
        "decided_in": states[explanation.decided_in],
        "decided_in_name": explanation.decided_in,
        "leaf": explanation.leaf,
        "target": states.get(explanation.target, -1),
        "target_name": explanation.target,
        "stay": explanation.stay,
        "leaf_span": leaf_span,
        "conditions": [condition_result(c) for c in explanation.conditions],
    }


def condition_result(condition: Condition) -> dict[str, Any]:
    """One condition of a path: its text, value, branch, span and comparisons."""
    return {
        "text": condition.text,
        "source": condition.source,
        "value": _plain(condition.value),
        "branch": condition.branch,
        "span": condition.span.as_dict() if condition.span else None,
        "comparisons": [dataclasses.asdict(k) for k in condition.comparisons],
    }


def why_not_state(option: Option, state: int | str) -> str:
    """The name of ``option``'s state ``state`` (id or name).

    Raises:
        DebugError: no such state.
    """
    if isinstance(state, int):
        if not 0 <= state < len(option.states):
            raise DebugError(f"option {option.name} has no state {state}")
        return option.states[state].name
    if state not in {s.name for s in option.states}:
        raise DebugError(f"option {option.name} has no state {state}")
    return state


def why_not_result(
    option: Option,
    state: State,
    leaf: int,
    target: int | str,
    values: Values,
    text: Callable[[Expression], str] | None = None,
) -> dict[str, Any]:
    """The ``why_not`` part of an ``explain`` result: why ``state``'s decision did not go to ``target``."""
    answer = explain_why_not(option, state, leaf, why_not_state(option, target), values, text)
    return {
        "target": option.state(answer.target).index,
        "target_name": answer.target,
        "went": answer.went,
        "routes": [
            {
                "leaf": route.leaf,
                "stay": route.stay,
                "leaf_span": _leaf_span(state, route.leaf),
                "conditions": [condition_result(c) for c in route.conditions],
                "blocked_at": route.blocked_at,
                "parts_at": route.leaves_taken_path_at,
            }
            for route in answer.routes
        ],
    }


def _leaf_span(state: State, leaf: int) -> SpanJson | None:
    node: If | Transition = state.decision
    for _, branch in leaf_path(state.decision, leaf):
        assert isinstance(node, If)
        node = node.then if branch else node.otherwise
    return node.span.as_dict() if node.span else None


def tree_result(option: Option, state_name: str, leaf: int, values: Values | None) -> dict[str, Any]:
    """The decision tree of ``option``'s state ``state_name``, the path to ``leaf`` marked."""
    name = option.name
    return decision_tree(option.state(state_name).decision, leaf, values, lambda node: if_text(node, name))


def if_text(node: If, option: str) -> str:
    """A condition as the studio shows it: its source text, else the IR rendered."""
    return str(node.text or render(node.condition, option))


def mark_values(tree: dict[str, Any], explanation: Explanation) -> None:
    """Put the explanation's condition values on the taken path of ``tree`` (live: the last decision's)."""
    node = tree
    for condition in explanation.conditions:
        if "if" not in node:
            return
        node["value"] = condition.value if isinstance(condition.value, bool) else None
        node = node["then"] if condition.branch else node["else"]


def source_texts(result: dict[str, Any], tree: dict[str, Any], described: dict[str, Any]) -> None:
    """Copy the description's condition texts onto the tree and the conditions (same shapes).

    A program read back from intermediate code has no source text: the description has it.
    """

    def copy(node: dict[str, Any], source: dict[str, Any]) -> None:
        if "if" in node and "if" in source:
            node["if"] = source["if"]
            copy(node["then"], source["then"])
            copy(node["else"], source["else"])

    copy(tree, described)
    copy_texts(result["conditions"], described)


def copy_texts(conditions: list[dict[str, Any]], described: dict[str, Any]) -> None:
    """The description's texts onto the conditions of one path down ``described``, by their branches."""
    node = described
    for condition in conditions:
        if "if" not in node:
            break
        condition["text"] = node["if"]
        node = node["then"] if condition["branch"] else node["else"]


def _plain(value: Any) -> Any:
    return value if isinstance(value, bool | int | float | str) or value is None else str(value)
