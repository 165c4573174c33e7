"""Where the engine keeps every value a behavior touches: the contract between linker and codegen.

The runtime's linker (:mod:`engine.runtime.linker`) decides, from the program and the host's
bindings, which storage slot or host callable backs each option parameter, symbol and basic
behavior; the code generator (:mod:`engine.codegen.python`) only turns those decisions into
global names and list indices. Flat lists (one for all option parameters, one for all basic
behavior parameters, one for all stored symbols) let the engine snapshot a tick with a few
C-level tuple copies (§2.12 activation tree, recorded cheaply).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from engine.ir.model import Assignment, Program
from engine.types import Kind

#: A parameter as the engine sees it: qualified name and kind.
ParamSpec = tuple[str, Kind]

_GROUP = {Kind.DECIMAL: 0, Kind.BOOLEAN: 1, Kind.ENUM: 2}


def engine_order(params: tuple[ParamSpec, ...]) -> list[int]:
    """Positions of ``params`` in the order the engine sets them (§2.5).

    Decimals first, then booleans, then enums, each group in registration/declaration order::

        engine_order((("f.on", BOOLEAN), ("f.k", DECIMAL))) == [1, 0]
    """
    return sorted(range(len(params)), key=lambda i: (_GROUP[params[i][1]], i))


def default_value(kind: Kind) -> float | bool | int:
    """The constant an unassigned call parameter gets on every call: 0.0, false, enum raw 0."""
    if kind is Kind.DECIMAL:
        return 0.0
    if kind is Kind.BOOLEAN:
        return False
    return 0


@dataclass(frozen=True, slots=True)
class OptionSlot:
    index: int
    #: start of this option's parameters in the flat option-parameter list
    offset: int
    params: tuple[ParamSpec, ...]
    initial: int
    #: per state: is it a target state (what ``action_done`` of a caller looks at, §2.7)
    targets: tuple[bool, ...]
    #: per state: is it a cooperative state (capacity/synchronized, §2.11)
    coop: tuple[bool, ...]


@dataclass(frozen=True, slots=True)
class InputSlot:
    index: int
    #: the host function's parameters in registration order (also the positional call order)
    params: tuple[ParamSpec, ...] = ()
    #: the symbol is this attribute of a host object (global ``IA{index}``): read, not called
    attribute: str | None = None


@dataclass(frozen=True, slots=True)
class OutputSlot:
    index: int
    #: True: the value lives in the engine's flat symbol list; False: host setter/getter
    stored: bool


@dataclass(frozen=True, slots=True)
class BehaviorSlot:
    index: int
    offset: int
    params: tuple[ParamSpec, ...]
    #: the host overrides ``parameters_changed``: generated calls track whether a value changed
    hook: bool


@dataclass(frozen=True)
class Layout:
    """Storage decisions for one program linked against one set of bindings."""

    options: dict[str, OptionSlot]
    inputs: dict[str, InputSlot]
    outputs: dict[str, OutputSlot]
    behaviors: dict[str, BehaviorSlot]
    enum_values: dict[str, int]
    #: (option, state index, action index) -> slot in the assignment-record list
    sites: dict[tuple[str, int, int], int] = field(default_factory=dict)
    #: B2: an option executed twice in one tick is an error; B1: a warning and it runs again
    double_execution_is_error: bool = True

    def key(self) -> tuple[object, ...]:
        """A hashable digest: two layouts with equal keys generate identical source."""
        return (
            tuple(sorted(self.options.items())),
            tuple(sorted(self.inputs.items())),
            tuple(sorted(self.outputs.items())),
            tuple(sorted(self.behaviors.items())),
            tuple(sorted(self.enum_values.items())),
            self.double_execution_is_error,
        )


def assignment_sites(program: Program) -> dict[tuple[str, int, int], int]:
    """Number every output assignment of every state (program order) for the tick record."""
    sites: dict[tuple[str, int, int], int] = {}
    for option in program.options.values():
        for state in option.states:
            for position, action in enumerate(state.actions):
                if isinstance(action, Assignment):
                    sites[(option.name, state.index, position)] = len(sites)
    return sites
