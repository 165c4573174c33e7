"""The ``explain`` result as the protocol sends it, built from an engine ``Explanation``.

One shape for every way the studio answers "why", each from what the decision read in its tick
(``ReadValues`` over ``Engine.reads()``): the live engine's last tick (``Debugger.explain``), a
past tick of the ring (``explain_decision`` over the reads the ring kept) and a tick of a
replayed recording (``explain_decision`` over the recording's reads and the program rebuilt from
its intermediate code). The decisions themselves are evaluated by ``xabsl_studio.engine.runtime.debug``; this
module only lays the answer out: ids, names, the leaf's span, each condition with its value,
branch and comparisons, and the decision tree with the path taken.
"""

from __future__ import annotations

from typing import Any

from xabsl_studio.engine.ir.model import If, Option, Transition, leaf_path
from xabsl_studio.engine.runtime.debug import Explanation, Values, decision_tree, render

__all__ = ["explanation_result", "if_text", "mark_values", "source_texts", "tree_result"]


def explanation_result(option: Option, explanation: Explanation) -> dict[str, Any]:
    """The ``explain`` result of ``option``'s decision (ids are the IR's: the description's ids)."""
    states = {s.name: s.index for s in option.states}
    decided = option.state(explanation.decided_in)
    # The leaf's own span, so the editor can point at the transition that fired.
    leaf_span = None
    try:
        node: If | Transition = decided.decision
        for _, branch in leaf_path(decided.decision, explanation.leaf):
            assert isinstance(node, If)
            node = node.then if branch else node.otherwise
        leaf_span = node.span.as_dict() if node.span else None
    except KeyError:
        pass
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
        "conditions": [
            {
                "text": c.text,
                "source": c.source,
                "value": _plain(c.value),
                "branch": c.branch,
                "span": c.span.as_dict() if c.span else None,
                "comparisons": [
                    {
                        "text": k.text,
                        "op": k.op,
                        "left": k.left,
                        "left_value": k.left_value,
                        "right": k.right,
                        "right_value": k.right_value,
                        "value": k.value,
                        "shown": str(k),
                    }
                    for k in c.comparisons
                ],
            }
            for c in explanation.conditions
        ],
    }


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
    node = described
    for condition in result["conditions"]:
        if "if" not in node:
            break
        condition["text"] = node["if"]
        node = node["then"] if condition["branch"] else node["else"]


def _plain(value: Any) -> Any:
    return value if isinstance(value, bool | int | float | str) or value is None else str(value)
