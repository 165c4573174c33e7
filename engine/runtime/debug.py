"""The debug interface of one engine (§2.12 and architecture "Engine").

A :class:`Debugger` observes and steers an :class:`~engine.runtime.engine.Engine` between
ticks:

* read: the activation tree (``engine.activation()``), the values of all input symbols without
  parameters (:meth:`Debugger.input_values`), why an option's decision chose what it chose
  (:meth:`Debugger.explain`);
* steer: select an agent, replace the root by any option or basic behavior with given
  parameters and release it, override any input symbol with a value and release it, reset.

Forcing never corrupts state: a forced root is just another root action (§2.9
``setRootAction``), so options that stop being called become inactive after one tick and
restart when called again, exactly as after an agent switch; overriding an input swaps the
host callable the generated code calls and releasing puts the host's back.

:meth:`Debugger.explain` **re-evaluates** the conditions on the path to the recorded leaf after
the tick, with the option's parameters and the ``state_time``/``option_time`` its decision saw
(both recorded); inputs are read again (overrides included) and ``action_done`` sees the
children's state after the tick, so values may differ from the decision's if the world moved
on. Decisions themselves record only the leaf, to keep ticks cheap.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from engine.codegen.python import expression_source
from engine.codegen.support import MS_MASK
from engine.ir.model import If, Transition, leaf_path
from engine.runtime.activation import Root
from engine.runtime.engine import Engine
from engine.runtime.errors import DebugError
from engine.types import Kind, Span, Value

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
    """Debug operations on one engine; cheap to create (``engine.debug``)."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine

    # -- reading -----------------------------------------------------------------------------

    def input_values(self) -> dict[str, Value]:
        """The current value of every input symbol without parameters (overrides included)."""
        loaded = self.engine._loaded_program()
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
        loaded = self.engine._loaded_program()
        slot = loaded.layout.options.get(option)
        if slot is None:
            raise DebugError(f"unknown option {option}")
        record = loaded.LF[slot.index]
        if record is None:
            raise DebugError(f"option {option} has not run yet")
        _, leaf, decided = record
        ir_option = loaded.program.options[option]
        state = ir_option.states[decided]
        namespace = {
            "st": loaded.SD[slot.index],
            "ot": float((self.engine.now - loaded.TA[slot.index]) & MS_MASK),
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

    # -- steering ----------------------------------------------------------------------------

    def select_agent(self, name: str) -> None:
        """Select an agent (no option state is reset, §2.9)."""
        self.engine.select_agent(name)

    def reset(self) -> None:
        """Restart every option on the next tick and clear a fault (§2.9)."""
        self.engine.reset()

    def force_option(self, name: str, params: Mapping[str, Value | str] | None = None, *, add: bool = False) -> None:
        """Run option ``name`` as the root with ``params`` (others default) until :meth:`release`.

        Enum parameters accept a qualified element name or a host value. With ``add=True`` the
        option runs after the current root actions instead of replacing them (``addRootAction``).

        Raises:
            DebugError: unknown option or parameter, or a value of the wrong kind.
            LoadError: the option's graph fails the load-time checks.
        """
        loaded = self.engine._loaded_program()
        slot = loaded.layout.options.get(name)
        if slot is None:
            raise DebugError(f"unknown option {name}")
        enums = {p.name: p.enum for p in loaded.program.options[name].params}
        values = self._params(name, slot.params, enums, params or {})
        self.engine._force(Root("option", name), values, add=add)

    def force_behavior(self, name: str, params: Mapping[str, Value | str] | None = None, *, add: bool = False) -> None:
        """Run basic behavior ``name`` as the root with ``params`` until :meth:`release` (``add``: append)."""
        loaded = self.engine._loaded_program()
        slot = loaded.layout.behaviors.get(name)
        if slot is None:
            raise DebugError(f"unknown basic behavior {name}")
        enums = {p[0]: p[2] for p in loaded.behavior_params[name]}
        values = self._params(name, slot.params, enums, params or {})
        self.engine._force(Root("behavior", name), values, add=add)

    def add_output(self, name: str, value: Value | str) -> None:
        """Append a root action that assigns ``value`` to output symbol ``name`` every tick (§2.9).

        Enum values accept a qualified element name or a host value.
        """
        loaded = self.engine._loaded_program()
        symbol = loaded.program.outputs.get(name)
        if symbol is None:
            raise DebugError(f"unknown output symbol {name}")
        values = self._params(name, ((name, symbol.kind),), {name: symbol.enum}, {name: value})
        self.engine._force(Root("output", name), {"value": values[name]}, add=True)

    def release(self) -> None:
        """Return to the selected agent's root option (releases every forced root action)."""
        self.engine._force(None, {})

    @property
    def forced(self) -> Root | None:
        """The forced root, if any."""
        return self.engine.forced

    def override_input(self, name: str, value: Value | str) -> None:
        """Make input symbol ``name`` read ``value`` (for any parameters) until released."""
        loaded = self.engine._loaded_program()
        symbol = loaded.program.inputs.get(name)
        if symbol is None:
            raise DebugError(f"unknown input symbol {name}")
        self.engine._apply_override(name, self._value(name, symbol.kind, symbol.enum, value))

    def release_input(self, name: str) -> None:
        """Read input symbol ``name`` from the host again."""
        loaded = self.engine._loaded_program()
        if name not in loaded.layout.inputs:
            raise DebugError(f"unknown input symbol {name}")
        self.engine._apply_override(name, None)

    def release_inputs(self) -> None:
        """Release every input override."""
        for name in list(self.engine.overrides):
            self.release_input(name)

    # -- helpers -----------------------------------------------------------------------------

    def _params(
        self,
        owner: str,
        declared: tuple[tuple[str, Kind], ...],
        enums: Mapping[str, str | None],
        given: Mapping[str, Value | str],
    ) -> dict[str, Value]:
        kinds = dict(declared)
        values: dict[str, Value] = {}
        for key, value in given.items():
            name = key if key in kinds else f"{owner}.{key}"
            if name not in kinds:
                raise DebugError(f"{owner} has no parameter {key}")
            values[name] = self._value(name, kinds[name], enums.get(name), value)
        return values

    def _value(self, name: str, kind: Kind, enum: str | None, value: Any) -> Value:
        if kind is Kind.DECIMAL:
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise DebugError(f"{name} is decimal, got {value!r}")
            return float(value)
        if kind is Kind.BOOLEAN:
            if not isinstance(value, bool):
                raise DebugError(f"{name} is boolean, got {value!r}")
            return value
        if isinstance(value, str):
            try:
                return self.engine.enum_value(value)
            except KeyError:
                raise DebugError(f"{name}: unknown enum element {value!r} of {enum}") from None
        if isinstance(value, bool) or not isinstance(value, int):
            raise DebugError(f"{name} is an enum, give an element name or host value, got {value!r}")
        return value


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
