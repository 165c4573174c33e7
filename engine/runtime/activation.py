"""The activation tree of a tick: what ran, in which state, with which times and parameters.

Recording is two-stage so that ticks stay cheap (§2.12, architecture "Engine"):

1. :class:`Snapshot` copies the engine's flat storage lists into tuples (a few C-level copies,
   no walk, no dicts): active states, tick stamps, activation times, decision records, option
   and basic-behavior parameters, the values of this tick's output assignments.
2. :func:`build_tree` turns a snapshot into :class:`OptionNode` / :class:`BehaviorNode` /
   :class:`AssignmentNode` objects on request, by walking root actions -> active state ->
   actions, as the original debugging hosts reconstruct it (§2.12).

An option node appears when the option ran in the snapshot's tick; its children are the calls
of its active state in action order (common-action items first, §2.4) that ran. With policy B1 an
option executed twice shows its final values twice; a basic behavior called more than once in a
tick (which B2 rejects at load time) keeps each call's own parameter values: the storage holds
only the last call's, so under B1 the engine also records every call's values
(``Snapshot.behavior_calls``, ``LoadedProgram.calls_of_tick``), and the n-th node of a behavior in
the walk (pre-order is the order the calls ran) shows the n-th call's values.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, NamedTuple

from xabsl_studio.engine.codegen.layout import Layout
from xabsl_studio.engine.codegen.support import MS_MASK
from xabsl_studio.engine.ir.model import Assignment, BehaviorCall, OptionCall, Parameter, Program
from xabsl_studio.engine.types import Kind, Ms, Value

__all__ = [
    "BEHAVIOR_NODE",
    "OPTION_NODE",
    "PATH_FIELDS",
    "AssignmentNode",
    "BehaviorCalls",
    "BehaviorNode",
    "Node",
    "OptionNode",
    "PathPlan",
    "Root",
    "Snapshot",
    "build_tree",
    "compact_path",
    "node_to_dict",
]


@dataclass(frozen=True, slots=True)
class Root:
    """A root action: ``kind`` is ``"option"``, ``"behavior"`` or ``"output"`` (an output-symbol assignment)."""

    kind: str
    name: str


#: Per basic-behavior slot that ran more than once in a tick: each call's parameter values, in order.
BehaviorCalls = dict[int, tuple[tuple[Value, ...], ...]]


class Snapshot(NamedTuple):
    """The engine's storage after one tick, copied into tuples (cheap; see module docstring).

    After ``now``, ``tick`` and ``roots`` come the storage lists of
    :data:`xabsl_studio.engine.codegen.layout.STORAGE` that are snapshotted, in that table's order and with its
    field names (``xabsl_studio.engine.runtime.storage`` checks this on import).

    A NamedTuple rather than a frozen dataclass: it is built on every recorded tick, and a
    frozen dataclass's ``__init__`` (one ``object.__setattr__`` per field) costs several times more.
    """

    now: Ms
    tick: int
    roots: tuple[Root, ...]
    states: tuple[int, ...]
    last_tick: tuple[int, ...]
    activated: tuple[Ms, ...]
    state_entered: tuple[Ms, ...]
    decisions: tuple[tuple[int, int, int] | None, ...]
    #: the ``state_time`` each option's decision saw; kept only for options whose decisions read
    #: ``state_time`` (the generated code skips it elsewhere, where nothing can depend on it)
    decision_state_time: tuple[float, ...]
    option_params: tuple[Value, ...]
    behavior_params: tuple[Value, ...]
    behavior_last_tick: tuple[int, ...]
    behavior_activated: tuple[Ms, ...]
    assignments: tuple[Value | None, ...]
    outputs: tuple[Value, ...]
    #: not a STORAGE list: under B1, per basic-behavior slot called more than once in the tick,
    #: each call's parameter values in call order (None under B2, where no behavior runs twice)
    behavior_calls: BehaviorCalls | None = None


@dataclass(frozen=True, slots=True)
class AssignmentNode:
    """An output-symbol assignment executed in the tick, with the value it wrote."""

    symbol: str
    value: Value
    kind: Kind
    enum: str | None = None


@dataclass(frozen=True, slots=True)
class BehaviorNode:
    """A basic behavior call: its parameter values and time of execution."""

    behavior: str
    params: dict[str, Value]
    time: Ms
    enums: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True, slots=True)
class OptionNode:
    """An option that ran: active state after the tick, times, parameters, decision, calls.

    ``decided_in`` is the state whose decision ran this tick and ``leaf`` the id of the decision
    leaf that fired (pre-order within that state's tree); ``state_time`` is 0 for a state entered
    in this tick.
    """

    option: str
    state: str
    option_time: Ms
    state_time: Ms
    params: dict[str, Value]
    leaf: int
    decided_in: str
    sub: tuple[Node, ...]
    enums: dict[str, str] = field(default_factory=dict)


Node = OptionNode | BehaviorNode | AssignmentNode


def build_tree(
    snapshot: Snapshot,
    program: Program,
    layout: Layout,
    behavior_params: dict[str, tuple[Parameter, ...]],
) -> list[Node]:
    """The activation tree of ``snapshot`` (see the module docstring)."""
    tick = snapshot.tick
    options = list(program.options.values())
    calls = snapshot.behavior_calls
    #: per behavior slot: how many of its nodes the walk has made so far (B1 double calls)
    made: dict[int, int] = {}

    def option_node(name: str) -> OptionNode | None:
        slot = layout.options[name]
        i = slot.index
        if snapshot.last_tick[i] != tick:
            return None
        option = options[i]
        state = option.states[snapshot.states[i]]
        sub: list[Node] = []
        for position, action in enumerate(state.actions):
            if isinstance(action, OptionCall):
                child = option_node(action.option)
                if child is not None:
                    sub.append(child)
            elif isinstance(action, BehaviorCall):
                node = behavior_node(action.behavior)
                if node is not None:
                    sub.append(node)
            elif isinstance(action, Assignment):
                value = snapshot.assignments[layout.sites[(option.name, state.index, position)]]
                if value is not None:
                    sub.append(AssignmentNode(action.symbol, value, action.kind, _output_enum(program, action)))
        decision = snapshot.decisions[i]
        params = {p.name: snapshot.option_params[slot.offset + k] for k, p in enumerate(option.params)}
        enums = {p.name: p.enum for p in option.params if p.enum is not None}
        return OptionNode(
            option.name,
            state.name,
            (snapshot.now - snapshot.activated[i]) & MS_MASK,
            (snapshot.now - snapshot.state_entered[i]) & MS_MASK,
            params,
            decision[1] if decision is not None else -1,
            option.states[decision[2]].name if decision is not None else state.name,
            tuple(sub),
            enums,
        )

    def behavior_node(name: str) -> BehaviorNode | None:
        slot = layout.behaviors[name]
        if snapshot.behavior_last_tick[slot.index] != tick:
            return None
        declared = behavior_params[name]
        values: Any = snapshot.behavior_params[slot.offset : slot.offset + len(declared)]
        if calls is not None and slot.index in calls:
            values = _nth_call(calls[slot.index], made, slot.index, values)
        params = {p.name: values[k] for k, p in enumerate(declared)}
        enums = {p.name: p.enum for p in declared if p.enum is not None}
        time = (snapshot.now - snapshot.behavior_activated[slot.index]) & MS_MASK
        return BehaviorNode(name, params, time, enums)

    tree: list[Node] = []
    for root in snapshot.roots:
        if root.kind == "option":
            node: Node | None = option_node(root.name)
        elif root.kind == "behavior":
            node = behavior_node(root.name)
        else:  # an output-symbol root action is not part of the activation tree
            node = None
        if node is not None:
            tree.append(node)
    return tree


def _nth_call(recorded: tuple[tuple[Value, ...], ...], made: dict[int, int], slot: int, last: Any) -> Any:
    """The values of the next node of behavior ``slot``: its next recorded call (else ``last``).

    More nodes than calls happen only when B1 shows an option executed twice with its final
    state twice; those extra nodes show what the storage holds, as the option nodes do.
    """
    n = made.get(slot, 0)
    made[slot] = n + 1
    return recorded[n] if n < len(recorded) else last


def _output_enum(program: Program, action: Assignment) -> str | None:
    symbol = program.outputs.get(action.symbol)
    return symbol.enum if symbol is not None else action.enum


def node_to_dict(node: Node, enum_name: Callable[[str | None, Value], Any]) -> dict[str, Any]:
    """A JSON-ready dict of ``node`` (enum values as element names via ``enum_name``)."""
    if isinstance(node, OptionNode):
        return {
            "option": node.option,
            "state": node.state,
            "option_time": node.option_time,
            "state_time": node.state_time,
            "params": {k: enum_name(node.enums.get(k), v) for k, v in node.params.items()},
            "leaf": node.leaf,
            "decided_in": node.decided_in,
            "sub": [node_to_dict(n, enum_name) for n in node.sub],
        }
    if isinstance(node, BehaviorNode):
        return {
            "behavior": node.behavior,
            "params": {k: enum_name(node.enums.get(k), v) for k, v in node.params.items()},
            "time": node.time,
        }
    return {"output": node.symbol, "value": enum_name(node.enum, node.value)}


# -- the compact activation path -------------------------------------------------------------------

#: Node kinds of :func:`compact_path`.
OPTION_NODE = 0
BEHAVIOR_NODE = 1

#: The storage lists (:data:`xabsl_studio.engine.codegen.layout.STORAGE` fields) :func:`compact_path` reads, in order.
PATH_FIELDS = (
    "last_tick",
    "states",
    "activated",
    "state_entered",
    "decisions",
    "option_params",
    "behavior_params",
    "behavior_last_tick",
    "behavior_activated",
)

#: The lists of :data:`PATH_FIELDS`, in that order.
PathStorage = tuple[list[int], list[int], list[Ms], list[Ms], list[Any], list[Value], list[Value], list[int], list[Ms]]


@dataclass(frozen=True, slots=True)
class PathPlan:
    """What :func:`compact_path` needs of a program, precomputed once per load.

    ``options[slot]`` = (IR option index, parameter offset, parameter count, per state the calls
    in action order as ``(is_option, slot)``); ``behaviors[slot]`` = (IR index, offset, count).
    """

    options: tuple[tuple[int, int, int, tuple[tuple[tuple[bool, int], ...], ...]], ...]
    behaviors: tuple[tuple[int, int, int], ...]
    roots: dict[Root, tuple[bool, int]]

    @classmethod
    def of(cls, program: Program, layout: Layout) -> PathPlan:
        """The plan of ``program`` loaded with ``layout``."""
        options: list[tuple[int, int, int, tuple[tuple[tuple[bool, int], ...], ...]]] = [None] * len(layout.options)  # type: ignore[list-item]
        for name, slot in layout.options.items():
            option = program.options[name]
            calls = tuple(
                tuple(
                    (True, layout.options[a.option].index)
                    if isinstance(a, OptionCall)
                    else (False, layout.behaviors[a.behavior].index)
                    for a in state.actions
                    if isinstance(a, OptionCall | BehaviorCall)
                )
                for state in option.states
            )
            options[slot.index] = (option.index, slot.offset, len(slot.params), calls)
        behaviors: list[tuple[int, int, int]] = [None] * len(layout.behaviors)  # type: ignore[list-item]
        for name, bslot in layout.behaviors.items():
            behaviors[bslot.index] = (program.behaviors[name].index, bslot.offset, len(bslot.params))
        roots = {Root("option", n): (True, s.index) for n, s in layout.options.items()}
        roots.update({Root("behavior", n): (False, s.index) for n, s in layout.behaviors.items()})
        return cls(tuple(options), tuple(behaviors), roots)


def compact_path(
    plan: PathPlan,
    roots: tuple[Root, ...],
    tick: int,
    now: Ms,
    storage: PathStorage,
    behavior_calls: BehaviorCalls | None = None,
) -> list[list[Any]]:
    """The activation path of the last tick as flat lists, read straight from engine storage.

    Pre-order, one list per node, ids are IR indices (the JSON ids)::

        [0, depth, option, active state, option_time, state_time, decided-in state, leaf, [params]]
        [1, depth, basic behavior, time of execution, [params]]

    Parameter values are raw (enum values as host integers), in declaration order; ``behavior_calls``
    (B1, see the module docstring) gives the values of behaviors that ran more than once. This is
    the per-tick recording path of the studio: no snapshot copy, no node objects.
    """
    last_tick, states, activated, entered, decisions, option_params, behavior_params, b_last, b_activated = storage
    options, behaviors = plan.options, plan.behaviors
    out: list[list[Any]] = []
    append = out.append
    # A stack of the iterators over the calls of the options above (pre-order, no recursion): a
    # node's children are walked by iterating its state's call tuple from the plan, so nothing is
    # built per child; that and no closures per call matter, as paths are walked every tick.
    calls: Any = iter([found for found in map(plan.roots.get, roots) if found is not None])
    depth = 0
    stack: list[tuple[Any, int]] = []
    push, pop = stack.append, stack.pop
    made: dict[int, int] = {}
    while True:
        for is_option, i in calls:
            if is_option:
                if last_tick[i] != tick:
                    continue
                index, offset, count, state_calls = options[i]
                state = states[i]
                record = decisions[i]
                append(
                    [
                        OPTION_NODE,
                        depth,
                        index,
                        state,
                        (now - activated[i]) & MS_MASK,
                        (now - entered[i]) & MS_MASK,
                        record[2] if record is not None else state,
                        record[1] if record is not None else -1,
                        option_params[offset : offset + count],
                    ]
                )
                children = state_calls[state]
                if children:
                    push((calls, depth))
                    calls = iter(children)
                    depth += 1
                    break
            elif b_last[i] == tick:
                index, offset, count = behaviors[i]
                values = behavior_params[offset : offset + count]
                if behavior_calls is not None and i in behavior_calls:
                    values = list(_nth_call(behavior_calls[i], made, i, values))
                append([BEHAVIOR_NODE, depth, index, (now - b_activated[i]) & MS_MASK, values])
        else:  # these calls are done: back to the option above
            if not stack:
                return out
            calls, depth = pop()
