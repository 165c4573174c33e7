"""Host registration: input and output symbols, enum element values and basic behaviors (§3.5).

A host fills a :class:`Bindings` before it loads a program, exactly as a host of the original
engine registers everything before ``createOptionGraph`` (§2.10). Internal symbols and
enumerations are engine storage and must not be registered (§2.1).

* **Input symbols** are read through a getter (a callable without arguments) on every
  reference; an input symbol with parameters is a host *function* called with its parameters
  positionally, in the order they are registered. A symbol that is one attribute of a host
  object (``world_model.ball_x``) can be registered as such (:meth:`Bindings.input_attribute`):
  generated code then reads the attribute itself, about 4x cheaper than calling a getter; one
  that is one item of a host mapping (``values["ball.x"]``) likewise (:meth:`Bindings.input_item`).
* **Output symbols** are plain storage kept by the engine (``initial`` value, read back with
  ``Engine.output``), or a ``setter``/``getter`` pair of the host. Writes go through at once
  (§2.2).
* **Enumerations** map qualified element names to host integers; several names may share a
  value (they then compare equal, §2.8).
* **Basic behaviors** are :class:`BasicBehavior` subclasses with declared parameters.

Value conventions: decimals are Python floats (return floats from decimal getters: an ``int``
works but integer arithmetic is exact where the engine's doubles round), booleans are bools,
enum values are host ints.
"""

from __future__ import annotations

import keyword
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from operator import attrgetter, itemgetter
from typing import Any, ClassVar

from xabsl_studio.engine.ir.model import Parameter, short_name
from xabsl_studio.engine.types import Kind, Ms, Value

__all__ = ["BasicBehavior", "Bindings", "InputBinding", "OutputBinding"]


def _qualify(owner: str, name: str) -> str:
    return name if name.startswith(owner + ".") else f"{owner}.{name}"


def _parameters(owner: str, params: Iterable[Parameter | tuple[str, Kind]]) -> tuple[Parameter, ...]:
    result = []
    for p in params:
        if isinstance(p, Parameter):
            result.append(Parameter(_qualify(owner, p.name), p.kind, p.enum, owner=owner))
        else:
            name, kind = p
            result.append(Parameter(_qualify(owner, name), kind, owner=owner))
    return tuple(result)


@dataclass(frozen=True, slots=True)
class InputBinding:
    """An input symbol as the host provides it: a getter, or a function of ``params``.

    ``source``/``attribute``: the symbol is ``source.<attribute>`` (``read`` reads exactly that);
    ``source``/``key``: the symbol is ``source[key]`` (likewise).
    """

    name: str
    kind: Kind
    read: Callable[..., Value]
    params: tuple[Parameter, ...] = ()
    enum: str | None = None
    source: object | None = None
    attribute: str | None = None
    key: str | None = None


@dataclass(frozen=True, slots=True)
class OutputBinding:
    """An output symbol: engine storage (``setter is None``) or a host setter/getter pair."""

    name: str
    kind: Kind
    enum: str | None = None
    initial: Value | None = None
    setter: Callable[[Value], None] | None = None
    getter: Callable[[], Value] | None = None


class BasicBehavior:
    """A basic behavior: the host's leaf skill that options call (§2.2, §3.5).

    Subclass it, set ``name`` and ``parameters`` (qualified as ``"walk.speed"`` or short as
    ``"speed"``), and override the hooks. The engine creates one instance per engine from the
    class (or uses a registered instance as is).

    Framework attributes, valid inside the hooks:

    * ``time_of_execution``: ms since the behavior was activated (0 on its first tick, §2.6).
    * ``param(name)`` / ``params``: the values set by the current call (every parameter is set
      on every call; unassigned ones are 0.0, false or enum raw value 0, §2.5).
    * ``parameter_values[parameter_offset + k]``: the same value of the ``k``-th declared
      parameter, by position: a list read, for ``execute`` methods on a hot path (``param``
      looks the name up in a dict). Both attributes are set by the engine when it loads a
      program (again on a hot reload), so read them in the hook, do not keep them.
    """

    #: The name options use to call this behavior.
    name: ClassVar[str] = ""
    #: Declared parameters, in registration order (the engine's evaluation order groups them
    #: decimals, booleans, enums, each in this order, §2.5).
    parameters: ClassVar[Sequence[Parameter | tuple[str, Kind]]] = ()

    def __init__(self) -> None:
        self.time_of_execution: Ms = 0
        #: The engine's basic-behavior parameter storage (shared by all behaviors of an engine).
        self.parameter_values: list[Any] = []
        #: Where this behavior's parameters start in ``parameter_values`` (declaration order).
        self.parameter_offset = 0
        self._index: dict[str, int] = {}
        self._names: tuple[str, ...] = ()

    # -- framework --------------------------------------------------------------------------

    @classmethod
    def declared_parameters(cls) -> tuple[Parameter, ...]:
        """The parameters with qualified names."""
        return _parameters(cls.name, cls.parameters)

    def bind_parameters(self, store: list[Any], offset: int, params: Sequence[Parameter]) -> None:
        """Called by the engine on (re)load: the parameters live at ``store[offset:]`` in ``params`` order."""
        self.parameter_values = store
        self.parameter_offset = offset
        self._index = {}
        self._names = tuple(p.name for p in params)
        for i, p in enumerate(params):
            self._index[p.name] = i
            # the declared name: only the behavior's prefix goes ("walk.to.robot.x" -> "robot.x")
            self._index.setdefault(short_name(p.name, self.name), i)

    def param(self, name: str) -> Value:
        """The current value of parameter ``name`` (qualified or short)."""
        value: Value = self.parameter_values[self.parameter_offset + self._index[name]]
        return value

    @property
    def params(self) -> dict[str, Value]:
        """All parameter values by qualified name."""
        store, offset = self.parameter_values, self.parameter_offset
        return {name: store[offset + i] for i, name in enumerate(self._names)}

    # -- hooks ------------------------------------------------------------------------------

    def parameters_changed(self) -> None:
        """Override to react when a call set different parameter values than the previous one.

        Called before ``execute`` in the same call. Must not call back into the engine.
        """

    def execute(self) -> None:
        """Override to act: called once per call, after the parameters and time are set.

        May raise: the engine then records a fault for the agent and stops it until reset.
        Must not call back into the engine.
        """


class Bindings:
    """Everything a host registers before loading a program (§3.5).

    Example::

        b = Bindings()
        b.enum("mode", ["mode.idle", "mode.walk"])               # values 0, 1
        b.input("ball.distance", Kind.DECIMAL, lambda: world.ball_distance)
        b.input("clamp", Kind.DECIMAL, clamp, params=[("value", Kind.DECIMAL), ...])
        b.output("motion.mode", Kind.ENUM, enum="mode")          # engine storage
        b.behavior(StandUp)
    """

    def __init__(self) -> None:
        self.inputs: dict[str, InputBinding] = {}
        self.outputs: dict[str, OutputBinding] = {}
        self.enums: dict[str, dict[str, int]] = {}
        self.behaviors: dict[str, type[BasicBehavior] | BasicBehavior] = {}

    def input(
        self,
        name: str,
        kind: Kind,
        read: Callable[..., Value],
        *,
        params: Iterable[Parameter | tuple[str, Kind]] = (),
        enum: str | None = None,
    ) -> None:
        """Register an input symbol: a getter, or (with ``params``) a host function.

        ``read`` should answer from the world's state alone: caching within a tick is fine, but
        an answer must not depend on whether or when it was asked before, since the studio and
        recordings read every plain input every tick and a fork reads only what the run read.
        """
        self.inputs[name] = InputBinding(name, kind, read, _parameters(name, params), enum)

    def input_attribute(
        self, name: str, kind: Kind, source: object, attribute: str, *, enum: str | None = None
    ) -> None:
        """Register an input symbol that is ``getattr(source, attribute)`` at every reference.

        The same as ``input(name, kind, lambda: getattr(source, attribute))``, but the generated
        code reads the attribute directly instead of calling a getter (~30 ns instead of ~120 ns
        a reference; behaviors read such symbols dozens of times per tick).
        """
        if not attribute.isidentifier() or keyword.iskeyword(attribute):
            raise ValueError(f"input symbol {name}: {attribute!r} is not an attribute name")
        read = partial(attrgetter(attribute), source)
        self.inputs[name] = InputBinding(name, kind, read, (), enum, source, attribute)

    def input_item(
        self, name: str, kind: Kind, source: Mapping[str, Any], key: str, *, enum: str | None = None
    ) -> None:
        """Register an input symbol that is ``source[key]`` at every reference.

        The same as ``input(name, kind, lambda: source[key])``, but the generated code subscripts
        the mapping directly instead of calling a getter (as cheap as :meth:`input_attribute`, and
        for any key: XABSL names have dots). ``source`` is held, not copied: assign its items to
        change the symbol.
        """
        read = partial(itemgetter(key), source)
        self.inputs[name] = InputBinding(name, kind, read, (), enum, source, None, key)

    def output(
        self,
        name: str,
        kind: Kind,
        *,
        enum: str | None = None,
        initial: Value | None = None,
        setter: Callable[[Value], None] | None = None,
        getter: Callable[[], Value] | None = None,
    ) -> None:
        """Register an output symbol: engine storage, or a host ``setter`` + ``getter`` pair."""
        if (setter is None) != (getter is None):
            raise ValueError(f"output symbol {name}: give both setter and getter, or neither")
        self.outputs[name] = OutputBinding(name, kind, enum, initial, setter, getter)

    def enum(self, name: str, elements: Mapping[str, int] | Sequence[str]) -> None:
        """Register enum elements: a mapping to host values, or names valued 0..n-1 in order."""
        if isinstance(elements, Mapping):
            values = {_qualify(name, k): int(v) for k, v in elements.items()}
        else:
            values = {_qualify(name, k): i for i, k in enumerate(elements)}
        self.enums.setdefault(name, {}).update(values)

    def enum_element(self, enum: str, element: str, value: int) -> None:
        """Register one element (``registerEnumElement("mode", "mode.walk", 1)``)."""
        self.enums.setdefault(enum, {})[_qualify(enum, element)] = int(value)

    def behavior(self, behavior: type[BasicBehavior] | BasicBehavior) -> None:
        """Register a basic behavior class (one instance per engine) or a shared instance."""
        if not behavior.name:
            raise ValueError(f"basic behavior {behavior!r} has no name")
        self.behaviors[behavior.name] = behavior
