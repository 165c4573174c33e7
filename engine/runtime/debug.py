"""Reading an engine for debugging: input values and why a decision chose what it chose (§2.12).

A :class:`Debugger` observes an :class:`~engine.runtime.engine.Engine` between ticks: the values
of all input symbols without parameters (:meth:`Debugger.input_values`) and why an option's
decision chose its leaf (:meth:`Debugger.explain`); the activation tree is
``engine.activation()``. Steering (selecting an agent, forcing roots, overriding inputs) belongs
to the engine's :class:`~engine.runtime.roots.RootActions` (``engine.root_actions``).

:meth:`Debugger.explain` **re-evaluates** the conditions on the path to the recorded leaf after
the tick, with the option's parameters and the ``state_time``/``option_time`` its decision saw
(both recorded); inputs are read again (overrides included) and ``action_done`` sees the
children's state after the tick, so values may differ from the decision's if the world moved
on. Decisions themselves record only the leaf, to keep ticks cheap.
"""

from __future__ import annotations

from dataclasses import dataclass

from engine.codegen.python import expression_source
from engine.codegen.support import MS_MASK
from engine.errors import DebugError
from engine.ir.model import If, Transition, leaf_path
from engine.runtime.engine import Engine
from engine.types import Span, Value

__all__ = ["Condition", "Debugger", "Explanation"]


@dataclass(frozen=True, slots=True)
class Condition:
    """One ``if`` on the path to a leaf: its text, its value now, the branch the decision took."""

    text: str
    source: str
    value: Value
    branch: bool
    span: Span | None


@dataclass(frozen=True, slots=True)
class Explanation:
    """Why option ``option`` in state ``decided_in`` took leaf ``leaf`` (to ``target``)."""

    option: str
    decided_in: str
    leaf: int
    target: str
    stay: bool
    conditions: tuple[Condition, ...]

    def __str__(self) -> str:
        lines = [f"{self.option}.{self.decided_in}: leaf {self.leaf} -> {'stay' if self.stay else self.target}"]
        for c in self.conditions:
            lines.append(f"  {'if' if c.branch else 'else of'} ({c.text or c.source}) = {c.value!r}")
        return "\n".join(lines)


class Debugger:
    """Debug reads of one engine; cheap to create (``Debugger(engine)``)."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine

    # -- reading -----------------------------------------------------------------------------

    def input_values(self) -> dict[str, Value]:
        """The current value of every input symbol without parameters (overrides included)."""
        loaded = self.engine.loaded
        return {
            name: loaded.input_reads[name]()
            for name, symbol in loaded.program.inputs.items()
            if not symbol.params and name in loaded.input_reads
        }

    def explain(self, option: str) -> Explanation:
        """The decision option ``option`` took in the last tick it ran (see module docstring).

        Raises:
            DebugError: unknown option, or it has not decided anything since the last load.
        """
        loaded = self.engine.loaded
        slot = loaded.layout.options.get(option)
        if slot is None:
            raise DebugError(f"unknown option {option}")
        record = loaded.decisions[slot.index]
        if record is None:
            raise DebugError(f"option {option} has not run yet")
        _, leaf, decided = record
        ir_option = loaded.program.options[option]
        state = ir_option.states[decided]
        namespace = {
            "st": loaded.decision_state_time[slot.index],
            "ot": float((self.engine.now - loaded.activated[slot.index]) & MS_MASK),
            "tick": self.engine.tick,
        }
        conditions = []
        for node, branch in leaf_path(state.decision, leaf):
            assert isinstance(node, If)
            source = expression_source(loaded.layout, ir_option, state, node.condition)
            value = eval(compile(source, f"<xabsl-explain:{option}>", "eval"), loaded.globals, namespace)
            conditions.append(Condition(node.text, source, value, branch, node.condition.span))
        transition = _leaf(state.decision, leaf)
        target = transition.target or state.name
        return Explanation(option, state.name, leaf, target, target == state.name, tuple(conditions))


def _leaf(tree: If | Transition, leaf: int) -> Transition:
    if isinstance(tree, Transition):
        return tree
    path = leaf_path(tree, leaf)
    node: If | Transition = tree
    for _, branch in path:
        assert isinstance(node, If)
        node = node.then if branch else node.otherwise
    assert isinstance(node, Transition)
    return node
