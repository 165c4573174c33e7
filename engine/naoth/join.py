"""A NaoTH robot's behavior messages joined with our compile of the same sources.

NaoTH's messages name things by *engine array index* (an option is its position in the robot
engine's option list, a state its index in the option, a symbol its position in its typed
array, a parameter its position among the option's parameters of its type) and carry neither
transitions nor option calls. :class:`BehaviorJoin` reads the ``BehaviorStateComplete`` of a
loaded behavior (the names behind every index, and every symbol's value at load time) and
joins it by name with the :class:`~xabsl_studio.engine.ir.model.Program` our compiler built
from the same sources; every difference is a named :attr:`BehaviorJoin.mismatches` entry (a
source that does not match what the robot runs is detected, never guessed around).

:meth:`BehaviorJoin.frame` turns one ``BehaviorStateSparse`` into what the studio and the
recordings hold: the activation path in the frame layout of docs/protocol.md (our ids), and the
input and output symbol values in our program's order. Values:

* a symbol's value is the sparse message's when it lists it, else its value at load time (the
  sparse lists hold exactly the symbols whose values differ from those: exact, not a guess);
  a symbol the robot does not have is None (``?``);
* decimals as sent (exact), booleans, enums as the element index of our enumeration (the
  robot's host value named by the complete message's enumerations); an element we do not know
  is None;
* an option node's decision is not on the wire. :func:`infer_decisions` fills in what the
  structure makes certain: an option active in two consecutive frames whose state changed from
  A to B took the one leaf of A's decision that leads to B, when A's decision has exactly one;
  every other node keeps leaf -1 ("not known to have decided", shown as no decision) with its
  active state as decided-in state;
* a basic behavior is identified by its place among the active state's actions in our compile
  (the robot sends its host registration index, which the sources do not determine); an action
  whose kind differs from our compile's is a mismatch and leaves its subtree out.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from xabsl_studio.engine.ir.model import Assignment, BehaviorCall, Option, OptionCall, Program, leaves
from xabsl_studio.engine.naoth.messages import ActionType, SymbolType
from xabsl_studio.engine.types import Kind, Value

__all__ = ["BehaviorJoin", "JoinedFrame", "infer_decisions"]

#: Symbol lists of the messages, by our kind, in the typed-array order of the robot's engine.
_LISTS = ((Kind.DECIMAL, "decimal"), (Kind.BOOLEAN, "boolean"), (Kind.ENUM, "enumerated"))
_SYMBOL_KIND = {SymbolType.DECIMAL: Kind.DECIMAL, SymbolType.BOOLEAN: Kind.BOOLEAN, SymbolType.ENUM: Kind.ENUM}
#: Mismatches listed at most (a completely different behavior names every option once).
MAX_MISMATCHES = 200


@dataclass(frozen=True, slots=True)
class JoinedFrame:
    """One sparse message in our terms (see the module docstring)."""

    frame_number: int | None
    agent: str | None
    path: list[list[Any]]
    inputs: tuple[Value | None, ...]
    outputs: tuple[Value | None, ...]
    error: str | None
    #: actions of the message the join could not place (kinds or ids our compile does not have)
    unplaced: int = 0


@dataclass(slots=True)
class _Symbols:
    """One direction (inputs or outputs): robot (kind, index) -> our position, load-time values."""

    positions: dict[tuple[Kind, int], int] = field(default_factory=dict)
    load: list[Value | None] = field(default_factory=list)


class BehaviorJoin:
    """The names behind a robot's indices, joined with ``program`` (see the module docstring).

    Args:
        program: our compile of the sources the robot runs.
        complete: the robot's ``BehaviorStateComplete`` of the loaded behavior.
    """

    def __init__(self, program: Program, complete: Any) -> None:
        self.program = program
        self.mismatches: list[str] = []
        self.agents: tuple[tuple[str, str], ...] = tuple((a.name, a.rootOption) for a in complete.agents)
        self.frame_number: int | None = complete.frameNumber if complete.HasField("frameNumber") else None
        self._enums = self._join_enums(complete)
        self._options: list[Option | None] = []
        #: per robot option: per robot state index our state index (None: we do not have it)
        self._states: list[list[int | None]] = []
        #: per robot option: per our parameter (declaration order) its (kind, typed index) on the robot
        self._params: list[tuple[tuple[Kind, int] | None, ...]] = []
        self._join_options(complete)
        self._join_agents()
        self._inputs_of = tuple(s for s in program.inputs.values() if not s.params)
        self._outputs_of = tuple(program.outputs.values())
        self._in = self._join_symbols(complete.inputSymbolList, self._inputs_of, "input")
        self._out = self._join_symbols(
            complete.outputSymbolList,
            self._outputs_of,
            "output",
            skip_missing={s.name for s in self._outputs_of if s.internal},
        )

    @property
    def matches(self) -> bool:
        """Whether the robot runs what our sources say (as far as the complete message shows)."""
        return not self.mismatches

    def _mismatch(self, text: str) -> None:
        if len(self.mismatches) < MAX_MISMATCHES:
            self.mismatches.append(text)

    # -- the tables -----------------------------------------------------------------------------

    def _join_enums(self, complete: Any) -> list[tuple[str | None, dict[int, int]]]:
        """Per robot enumeration: our enum's name and host value -> our element index."""
        joined: list[tuple[str | None, dict[int, int]]] = []
        for enum in complete.enumerations:
            ours = self.program.enums.get(enum.name)
            if ours is None:
                self._mismatch(f"enumeration {enum.name!r} is on the robot, not in the sources")
                joined.append((None, {}))
                continue
            index = {element: i for i, element in enumerate(ours.elements)}
            table: dict[int, int] = {}
            seen: set[str] = set()
            for element in enum.elements:
                name = element.name if element.name.startswith(enum.name + ".") else f"{enum.name}.{element.name}"
                seen.add(name)
                if name in index:
                    table[element.value] = index[name]
                else:
                    self._mismatch(f"enumeration {enum.name!r}: element {name!r} is on the robot, not in the sources")
            for name in ours.elements:
                if name not in seen:
                    self._mismatch(f"enumeration {enum.name!r}: element {name!r} is in the sources, not on the robot")
            joined.append((enum.name, table))
        robot_names = {e.name for e in complete.enumerations}
        for name, enum in self.program.enums.items():
            if name not in robot_names and not enum.internal:
                self._mismatch(f"enumeration {name!r} is in the sources, not on the robot")
        return joined

    def _join_options(self, complete: Any) -> None:
        seen: set[str] = set()
        for option in complete.options:
            seen.add(option.name)
            ours = self.program.options.get(option.name)
            self._options.append(ours)
            if ours is None:
                self._mismatch(f"option {option.name!r} is on the robot, not in the sources")
                self._states.append([])
                self._params.append(())
                continue
            states: list[int | None] = []
            robot_states = [s.name for s in option.states]
            for i, state in enumerate(option.states):
                our_state = next((s for s in ours.states if s.name == state.name), None)
                states.append(our_state.index if our_state is not None else None)
                if our_state is None:
                    self._mismatch(f"option {option.name!r}: state {state.name!r} is on the robot, not in the sources")
                elif our_state.index != i:
                    self._mismatch(
                        f"option {option.name!r}: state {state.name!r} is state {i} on the robot, "
                        f"{our_state.index} in the sources"
                    )
                elif state.HasField("target") and state.target != our_state.target:
                    self._mismatch(f"option {option.name!r}: state {state.name!r} differs in being a target state")
            for state in ours.states:
                if state.name not in robot_states:
                    self._mismatch(f"option {option.name!r}: state {state.name!r} is in the sources, not on the robot")
            self._states.append(states)
            self._params.append(self._join_params(option, ours))
        for name in self.program.options:
            if name not in seen:
                self._mismatch(f"option {name!r} is in the sources, not on the robot")

    def _join_params(self, robot: Any, ours: Option) -> tuple[tuple[Kind, int] | None, ...]:
        """Our parameters in declaration order -> (kind, position among the robot's of that kind)."""
        counters: dict[Kind, int] = {}
        by_name: dict[str, tuple[Kind, int]] = {}
        for parameter in robot.parameters:
            kind = _SYMBOL_KIND.get(parameter.type)
            if kind is None:
                continue
            # the robot numbers each type's parameters from 0 (``id``); its list order is the same
            position = parameter.id if parameter.HasField("id") and parameter.id >= 0 else counters.get(kind, 0)
            counters[kind] = counters.get(kind, 0) + 1
            by_name[parameter.name] = (kind, position)
        joined: list[tuple[Kind, int] | None] = []
        for parameter in ours.params:
            found = by_name.pop(parameter.name, None) or by_name.pop(parameter.short_name, None)
            if found is None or found[0] is not parameter.kind:
                self._mismatch(f"option {ours.name!r}: parameter {parameter.name!r} is not on the robot as declared")
                found = None
            joined.append(found)
        for name in by_name:
            self._mismatch(f"option {ours.name!r}: parameter {name!r} is on the robot, not in the sources")
        return tuple(joined)

    def _join_agents(self) -> None:
        ours = {a.name: a.root for a in self.program.agents}
        for name, root in self.agents:
            if name not in ours:
                self._mismatch(f"agent {name!r} is on the robot, not in the sources")
            elif ours[name] != root:
                self._mismatch(f"agent {name!r} starts at {root!r} on the robot, at {ours[name]!r} in the sources")
        robot = {name for name, _ in self.agents}
        for name in ours:
            if name not in robot:
                self._mismatch(f"agent {name!r} is in the sources, not on the robot")

    def _join_symbols(
        self, lists: Any, symbols: tuple[Any, ...], what: str, skip_missing: set[str] | None = None
    ) -> _Symbols:
        position = {s.name: i for i, s in enumerate(symbols)}
        joined = _Symbols(load=[None] * len(symbols))
        seen: set[str] = set()
        for kind, attribute in _LISTS:
            for i, symbol in enumerate(getattr(lists, attribute)):
                index = symbol.id if symbol.HasField("id") and symbol.id >= 0 else i
                at = position.get(symbol.name)
                if at is None:
                    self._mismatch(f"{what} symbol {symbol.name!r} is on the robot, not in the sources")
                    continue
                seen.add(symbol.name)
                if symbols[at].kind is not kind:
                    self._mismatch(f"{what} symbol {symbol.name!r} is {kind.value} on the robot")
                    continue
                joined.positions[(kind, index)] = at
                if symbol.HasField("value"):
                    joined.load[at] = self._value(kind, symbols[at].enum, symbol.value, getattr(symbol, "typeId", None))
        for symbol in symbols:
            if symbol.name not in seen and symbol.name not in (skip_missing or ()):
                self._mismatch(f"{what} symbol {symbol.name!r} is in the sources, not on the robot")
        return joined

    def _value(self, kind: Kind, enum: str | None, value: Any, type_id: int | None = None) -> Value | None:
        if kind is Kind.DECIMAL:
            return float(value)
        if kind is Kind.BOOLEAN:
            return bool(value)
        table = next((t for name, t in self._enums if name == enum), None)
        if table is None:
            return None
        return table.get(int(value))

    # -- one frame ------------------------------------------------------------------------------

    def frame(self, sparse: Any) -> JoinedFrame:
        """One ``BehaviorStateSparse`` as a path and symbol values in our program's terms."""
        path: list[list[Any]] = []
        unplaced = 0
        for root in sparse.activeRootActions:
            unplaced += self._action(root, None, 0, path)
        return JoinedFrame(
            frame_number=sparse.frameNumber if sparse.HasField("frameNumber") else None,
            agent=sparse.agent if sparse.HasField("agent") else None,
            path=path,
            inputs=self._symbols(sparse.inputSymbolList, self._in, self._inputs_of),
            outputs=self._symbols(sparse.outputSymbolList, self._out, self._outputs_of),
            error=sparse.errorMessage or None if sparse.HasField("errorMessage") else None,
            unplaced=unplaced,
        )

    def _symbols(self, lists: Any, joined: _Symbols, symbols: tuple[Any, ...]) -> tuple[Value | None, ...]:
        values = list(joined.load)
        positions = joined.positions
        for kind, attribute in _LISTS:
            for symbol in getattr(lists, attribute):
                at = positions.get((kind, symbol.id))
                if at is not None and symbol.HasField("value"):
                    values[at] = self._value(kind, symbols[at].enum, symbol.value)
        return tuple(values)

    def _action(self, action: Any, expected: Any, depth: int, path: list[list[Any]]) -> int:
        """Append ``action``'s subtree; ``expected`` is our compile's action at its place (None: a root)."""
        if action.type == ActionType.SYMBOL_ASSIGNMENT:
            # values are the output symbols'; the frames' paths hold no assignment nodes
            return 0 if expected is None or isinstance(expected, Assignment) else 1
        body = action.option
        if action.type == ActionType.BASIC_BEHAVIOR:
            if not isinstance(expected, BehaviorCall):
                return 1  # a root behavior, or not where our compile has one: its id names nothing we know
            behavior = self.program.behaviors.get(expected.behavior)
            if behavior is None:
                return 1
            typed = self._typed(body)
            counters: dict[Kind, int] = {}
            params: list[Value | None] = []
            for parameter in behavior.params:
                i = counters.get(parameter.kind, 0)
                counters[parameter.kind] = i + 1
                values = typed[parameter.kind]
                params.append(self._value(parameter.kind, parameter.enum, values[i]) if i < len(values) else None)
            path.append([1, depth, behavior.index, max(0, int(body.timeOfExecution)), params])
            return 0
        if action.type != ActionType.OPTION or not 0 <= body.id < len(self._options):
            return 1
        option = self._options[body.id]
        if option is None or (isinstance(expected, OptionCall) and expected.option != option.name):
            return 1
        if expected is not None and not isinstance(expected, OptionCall):
            return 1
        states = self._states[body.id]
        state = states[body.activeState] if 0 <= body.activeState < len(states) else None
        if state is None:
            return 1
        typed = self._typed(body)
        params = []
        for parameter, place in zip(option.params, self._params[body.id], strict=True):
            if place is None:
                params.append(None)
                continue
            kind, i = place
            values = typed[kind]
            params.append(self._value(kind, parameter.enum, values[i]) if i < len(values) else None)
        option_time = max(0, int(body.timeOfExecution))
        state_time = max(0, int(body.stateTime)) if body.HasField("stateTime") else option_time
        path.append([0, depth, option.index, state, option_time, state_time, state, -1, params])
        actions = option.states[state].actions
        unplaced = 0
        for k, child in enumerate(body.activeSubActions):
            unplaced += self._action(child, actions[k] if k < len(actions) else _NOWHERE, depth + 1, path)
        return unplaced

    @staticmethod
    def _typed(body: Any) -> dict[Kind, Any]:
        return {
            Kind.DECIMAL: body.decimalParameters,
            Kind.BOOLEAN: body.booleanParameters,
            Kind.ENUM: body.enumeratedParameters,
        }


def infer_decisions(program: Program, path: list[list[Any]], previous: list[list[Any]] | None) -> int:
    """Fill in the decisions of ``path`` that the previous frame's path makes certain; how many.

    ``previous`` is the path of the frame right before (None: not consecutive, e.g. a gap, a
    first frame or a reload). Rule: see the module docstring.
    """
    if not previous:
        return 0
    states = {node[2]: node[3] for node in previous if node[0] == 0}
    by_index = {o.index: o for o in program.options.values()}
    filled = 0
    for node in path:
        if node[0] != 0:
            continue
        before = states.get(node[2])
        if before is None or before == node[3]:
            continue
        option = by_index.get(node[2])
        if option is None or not 0 <= before < len(option.states):
            continue
        target = option.states[node[3]].name
        taken = [leaf.leaf for leaf in leaves(option.states[before].decision) if leaf.target == target]
        if len(taken) == 1:
            node[6], node[7] = before, taken[0]
            filled += 1
    return filled


#: The action our compile has at a place past its state's last action (nothing matches it).
_NOWHERE = object()
