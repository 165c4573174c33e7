"""Where the engine keeps every value a behavior touches: the contract between linker and codegen.

The runtime's linker (:mod:`xabsl_studio.engine.runtime.linker`) decides, from the program and the host's
bindings, which storage slot or host callable backs each option parameter, symbol and basic
behavior; the code generator (:mod:`xabsl_studio.engine.codegen.python`) only turns those decisions into
global names and list indices. Flat lists (one for all option parameters, one for all basic
behavior parameters, one for all stored symbols) let the engine snapshot a tick with a few
C-level tuple copies (§2.12 activation tree, recorded cheaply).

:data:`STORAGE` is the one schema of those lists: their names in Python and in generated code,
what they hold after a load, and whether snapshots, ``reset()`` and hot reload copy them.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

from xabsl_studio.engine.ir.model import Assignment, Program
from xabsl_studio.engine.types import Kind

#: A parameter as the engine sees it: qualified name and kind.
ParamSpec = tuple[str, Kind]

_GROUP = {Kind.DECIMAL: 0, Kind.BOOLEAN: 1, Kind.ENUM: 2}

#: Tick stamp of "never executed": never equal to ``tick - 1`` for a real tick (ticks start at 1).
NEVER = -10


class Per(enum.Enum):
    """What one element of a storage list belongs to (and so how long the list is)."""

    OPTION = "option"
    OPTION_PARAMETER = "option parameter"
    BEHAVIOR = "basic behavior"
    BEHAVIOR_PARAMETER = "basic behavior parameter"
    SYMBOL = "output or internal symbol"
    ASSIGNMENT = "output assignment"


class Start(enum.Enum):
    """What a storage list holds after a load."""

    #: :data:`NEVER` (a tick stamp)
    NEVER = "never"
    #: ``0`` (a clock value in ms)
    ZERO_MS = "0 ms"
    #: ``0.0`` (a time the decision saw)
    ZERO_TIME = "0.0"
    #: ``None`` (nothing recorded yet)
    NOTHING = "None"
    #: the option's initial state
    INITIAL_STATE = "initial state"
    #: the parameter's default value (:func:`default_value`)
    DEFAULT = "default value"
    #: the symbol's initial value (the host's, or the first enum element, §2.1)
    INITIAL_VALUE = "initial value"


@dataclass(frozen=True, slots=True)
class StorageList:
    """One flat list of the engine's storage (see :data:`STORAGE`)."""

    #: the name of the list in the Python API and in :class:`xabsl_studio.engine.runtime.activation.Snapshot`
    field: str
    #: the global the generated code reads it through (short: it is written thousands of times)
    name: str
    per: Per
    start: Start
    #: copied into every snapshot of a tick
    snapshot: bool
    #: kept across a hot reload, by name (options: only while their active state still exists)
    reload: bool
    #: set back to :data:`NEVER` by ``Engine.reset()`` (every option and behavior restarts)
    reset: bool = False


#: The engine's storage: every per-tick value a behavior touches lives in one of these lists.
#: The runtime's storage object, the generated code's globals, snapshots, ``reset()`` and hot
#: reload are all derived from this table (snapshot order is table order).
STORAGE: tuple[StorageList, ...] = (
    StorageList("states", "S", Per.OPTION, Start.INITIAL_STATE, snapshot=True, reload=True),
    StorageList("last_tick", "LT", Per.OPTION, Start.NEVER, snapshot=True, reload=True, reset=True),
    StorageList("previous_tick", "PV", Per.OPTION, Start.NEVER, snapshot=False, reload=True, reset=True),
    StorageList("activated", "TA", Per.OPTION, Start.ZERO_MS, snapshot=True, reload=True),
    StorageList("state_entered", "TS", Per.OPTION, Start.ZERO_MS, snapshot=True, reload=True),
    StorageList("decisions", "LF", Per.OPTION, Start.NOTHING, snapshot=True, reload=False),
    StorageList("decision_state_time", "SD", Per.OPTION, Start.ZERO_TIME, snapshot=True, reload=True),
    StorageList("option_params", "PP", Per.OPTION_PARAMETER, Start.DEFAULT, snapshot=True, reload=True),
    StorageList("behavior_params", "BP", Per.BEHAVIOR_PARAMETER, Start.DEFAULT, snapshot=True, reload=False),
    StorageList("behavior_last_tick", "BLT", Per.BEHAVIOR, Start.NEVER, snapshot=True, reload=True, reset=True),
    StorageList("behavior_previous_tick", "BPV", Per.BEHAVIOR, Start.NEVER, snapshot=False, reload=True, reset=True),
    StorageList("behavior_activated", "BTA", Per.BEHAVIOR, Start.ZERO_MS, snapshot=True, reload=True),
    StorageList("assignments", "AV", Per.ASSIGNMENT, Start.NOTHING, snapshot=True, reload=False),
    StorageList("outputs", "OV", Per.SYMBOL, Start.INITIAL_VALUE, snapshot=True, reload=True),
)


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
    """Where one option lives: its index in the per-option lists, its parameters, its states."""

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
    """How one input symbol is read: host callable ``I{index}`` (or attribute/item of ``IA{index}``)."""

    index: int
    #: the host function's parameters in registration order (also the positional call order)
    params: tuple[ParamSpec, ...] = ()
    #: the symbol is this attribute of a host object (global ``IA{index}``): read, not called
    attribute: str | None = None
    #: the symbol is this item of a host mapping (global ``IA{index}``): subscripted, not called
    key: str | None = None


@dataclass(frozen=True, slots=True)
class OutputSlot:
    """Where one output or internal symbol lives: the engine's list, or a host setter/getter."""

    index: int
    #: True: the value lives in the engine's flat symbol list; False: host setter/getter
    stored: bool


@dataclass(frozen=True, slots=True)
class BehaviorSlot:
    """Where one basic behavior lives: its index in the per-behavior lists, its parameters."""

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
