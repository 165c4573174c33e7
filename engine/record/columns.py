"""Recorded ticks as columns: per robot, one array per symbol and the activation paths as a table.

What a query evaluates over. :class:`ColumnsBuilder` takes one robot's ticks in order, either as
the recording's ``xabsl.AgentTick`` messages (key frames and changes, :meth:`ColumnsBuilder.message`)
or as decoded :class:`~xabsl_studio.engine.record.reader.AgentTick` views (:meth:`ColumnsBuilder.view`:
the live history, an attached session's), and :meth:`ColumnsBuilder.finish` turns them into a
:class:`RobotColumns`:

* per tick ``seq``, ``t`` and the program generation ``gen``;
* per plain input, output and internal symbol a value array and a "known" mask: known where the
  tick's recorded values hold it (a key frame that lacks it, a getter that raised (``unread``), a
  JSON null: unknown). Booleans are 0/1, enum elements codes of :class:`Codes`;
* the activation paths as one row per node (tick row, option or behavior, id, state, decided-in
  state, leaf, times, parameters), in the ids of the node's generation;
* optionally, for the input functions a query calls, every call the tick's decisions made (from
  ``reads``: arguments and result).

A :class:`Selection` limits what is kept to the names a query needs (the symbols it reads, the
options and basic behaviors it names, the input functions it calls), which is what makes a cold
query cheap. Values are exactly what the recording holds (plain symbols at its precision,
``decimals``; enum symbols as element names, or as element indices in studio recordings); no
value is carried over a key frame or guessed.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from xabsl_studio.engine.record.reader import AgentTick, ProgramView

__all__ = [
    "CallTable",
    "Calls",
    "Codes",
    "ColumnsBuilder",
    "NodeTable",
    "ProgramCodes",
    "RobotColumns",
    "RobotEvents",
    "Selection",
    "call_table",
    "collect_calls",
    "raw_number",
    "scalar",
    "seed_codes",
]

Floats = npt.NDArray[np.float64]
Ints = npt.NDArray[np.int64]
Mask = npt.NDArray[np.bool_]


class Codes:
    """One number per enum element name (qualified names are unique across enumerations)."""

    def __init__(self) -> None:
        self.by_name: dict[str, int] = {}

    def code(self, element: str) -> int:
        """The code of ``element`` (a new one the first time)."""
        code = self.by_name.get(element)
        if code is None:
            code = self.by_name[element] = len(self.by_name)
        return code


@dataclass(frozen=True)
class NodeTable:
    """The activation path nodes of a robot's ticks, one row per node (see the module docstring).

    ``kind`` 0 is an option (``state``, ``decided``, ``leaf``, ``option_time``, ``state_time``),
    1 a basic behavior (its time of execution in ``option_time``). Parameter values are
    ``params[param_start[i] : param_start[i] + param_count[i]]`` (enums as codes, unknown NaN).
    """

    row: Ints
    kind: Ints
    ident: Ints
    state: Ints
    decided: Ints
    leaf: Ints
    option_time: Floats
    state_time: Floats
    param_start: Ints
    param_count: Ints
    params: Floats
    params_known: Mask


@dataclass(frozen=True)
class CallTable:
    """Every recorded call of one input function: tick row, arguments (declaration order), result."""

    row: Ints
    args: list[tuple[float | None, ...]]
    result: Floats
    known: Mask
    #: per argument precision: (row, arguments) -> index of the call's result (-1: calls disagree),
    #: filled by the evaluator once (``xabsl_studio.engine.query.evaluate``)
    keys: dict[int | None, dict[tuple[Any, ...], int]] = field(default_factory=dict, compare=False)


@dataclass
class RobotColumns:
    """One robot's recorded ticks as columns (see the module docstring)."""

    robot: str
    seq: Ints
    t: Ints
    gen: Ints
    programs: dict[int, ProgramView]
    values: dict[str, tuple[Floats, Mask]]
    nodes: NodeTable
    calls: dict[str, CallTable] = field(default_factory=dict)
    #: the input functions whose calls were collected (a function not in it was not asked for)
    functions: frozenset[str] = frozenset()
    #: what was kept of the ticks (a name outside it was not read, not found missing)
    selection: Selection = field(default_factory=lambda: Selection())
    #: False when the ticks had no ``reads`` (a recording made before they were recorded)
    has_reads: bool = True

    def __len__(self) -> int:
        return len(self.seq)


@dataclass
class RobotEvents:
    """One robot's ticks with each value as its changes: a tick row per change, the value, known.

    What :class:`ColumnsBuilder` collects before the values are spread over every tick, and what a
    recording stores of its ticks (``xabsl_studio.engine.record.stored``); :meth:`columns` spreads
    them. ``functions`` are the input functions whose calls were collected.
    """

    robot: str
    seq: Ints
    t: Ints
    gen: Ints
    events: dict[str, tuple[Ints, Floats, Mask]]
    nodes: NodeTable
    calls: dict[str, CallTable]
    functions: frozenset[str]
    has_reads: bool

    def __len__(self) -> int:
        return len(self.seq)

    def columns(self, programs: dict[int, ProgramView], selection: Selection) -> RobotColumns:
        """The columns: each value in force at each tick (the last change at or before it)."""
        n = len(self.seq)
        positions = np.arange(n)
        values: dict[str, tuple[Floats, Mask]] = {}
        for name, (rows, event_values, known_event) in self.events.items():
            index = np.searchsorted(rows, positions, side="right") - 1
            has = index >= 0
            index = np.where(has, index, 0)
            values[name] = (event_values[index], has & known_event[index])
        return RobotColumns(
            self.robot,
            self.seq,
            self.t,
            self.gen,
            programs,
            values,
            self.nodes,
            calls=self.calls,
            functions=self.functions,
            selection=selection,
            has_reads=self.has_reads,
        )


def seed_codes(views: Iterable[ProgramView], codes: Codes) -> None:
    """Number every enum element of the programs, in their order, as a recording's reader does.

    A reader numbers the elements of the recording's programs before it reads any tick, so that
    readers of parts of the file (``xabsl_studio.engine.query.scan``) and the recording's writer
    (``xabsl_studio.engine.record.stored``) number them alike.
    """
    for view in views:
        for enum in view.description.get("enums", ()):
            for element in enum.get("elements", ()):
                if isinstance(element, str):
                    codes.code(element)
        for table in view.tables.get("enums", {}).values():
            for element in table.values():
                if isinstance(element, str):
                    codes.code(element)


def scalar(value: Any, codes: Codes) -> float | None:
    """A recorded value as a number: bools 0/1, enum elements their code, None unknown."""
    if value is None:
        return None
    if isinstance(value, bool):
        return 1.0 if value else 0.0
    if isinstance(value, str):
        return float(codes.code(value))
    if isinstance(value, int | float):
        return float(value)
    return None


def _flatten(tree: Mapping[str, Any], into: dict[str, Any], prefix: str = "") -> None:
    """Nested message values into XABSL names (``"="`` holds a namespace's own value)."""
    for key, value in tree.items():
        name = prefix[:-1] if key == "=" else prefix + key
        if isinstance(value, dict):
            _flatten(value, into, name + ".")
        else:
            into[name] = value


def raw_number(value: Any, enum: str | None, tables: dict[str, dict[int, int]], codes: Codes) -> float | None:
    """A raw (host) value as a number: an enum's host integer becomes its element's code (``tables``)."""
    if value is None or isinstance(value, list | dict | str):
        return None
    if enum is not None:
        if isinstance(value, bool) or not isinstance(value, int | float) or value != int(value):
            return None
        code = tables.get(enum, {}).get(int(value))
        return None if code is None else float(code)
    return scalar(value, codes)


class ProgramCodes:
    """What columns need of one program generation: enum tables as codes, parameter enums, function ids."""

    def __init__(self, view: ProgramView, functions: frozenset[str] | None, codes: Codes) -> None:
        description = view.description
        self.view = view
        enums = view.tables.get("enums", {})
        read_enums = view.tables.get("read_enums") or enums
        self.host_enums = {name: {int(v): codes.code(e) for v, e in table.items()} for name, table in enums.items()}
        self.read_enums = {
            name: {int(v): codes.code(e) for v, e in table.items()} for name, table in read_enums.items()
        }
        options = description["options"]
        behaviors = description["behaviors"]
        self.option_param_enums = [[p.get("enum") for p in o["params"]] for o in options]
        declared = view.tables.get("behavior_params", {})
        self.behavior_param_enums = [
            [p[1] for p in declared.get(b["name"], [[q["name"], q.get("enum")] for q in b["params"]])]
            for b in behaviors
        ]
        # per input function id the query wants: (name, enum of each parameter, enum of the result)
        self.functions: dict[int, tuple[str, list[str | None], str | None]] = {}
        for symbol in description["inputs"]:
            if symbol.get("params") and (functions is None or symbol["name"] in functions):
                params = [p.get("enum") for p in symbol.get("params", ())]
                self.functions[int(symbol["id"])] = (symbol["name"], params, symbol.get("enum"))


@dataclass(frozen=True)
class Selection:
    """What to keep of the ticks: symbol, option, basic-behavior and input-function names (None: all)."""

    symbols: frozenset[str] | None = None
    options: frozenset[str] | None = None
    behaviors: frozenset[str] | None = None
    functions: frozenset[str] | None = None

    @classmethod
    def nothing(cls) -> Selection:
        """Keep nothing: an index that reads each name when a query first needs it."""
        return cls(frozenset(), frozenset(), frozenset(), frozenset())

    def covers(self, other: Selection) -> bool:
        """Whether everything ``other`` keeps is kept here."""
        return all(
            mine is None or (theirs is not None and theirs <= mine)
            for mine, theirs in (
                (self.symbols, other.symbols),
                (self.options, other.options),
                (self.behaviors, other.behaviors),
                (self.functions, other.functions),
            )
        )

    def union(self, other: Selection) -> Selection:
        """What either keeps."""

        def join(a: frozenset[str] | None, b: frozenset[str] | None) -> frozenset[str] | None:
            return None if a is None or b is None else a | b

        return Selection(
            join(self.symbols, other.symbols),
            join(self.options, other.options),
            join(self.behaviors, other.behaviors),
            join(self.functions, other.functions),
        )


_MISSING = object()


def _lookup(tree: dict[str, Any], keys: tuple[str, ...]) -> Any:
    """The value of a nested message name (``_MISSING`` if the message does not hold it)."""
    node: Any = tree
    for key in keys:
        if not isinstance(node, dict):
            return _MISSING
        node = node.get(key, _MISSING)
        if node is _MISSING:
            return _MISSING
    if isinstance(node, dict):  # a name that is also a namespace keeps its own value under "="
        return node.get("=", _MISSING)
    return node


class ColumnsBuilder:
    """Collects one robot's ticks, in order, into :class:`RobotColumns` (see the module docstring).

    ``program`` gives the program generation of a ``gen`` (``Recording.program(robot, gen)``);
    ``selection`` says what to keep (the names a query needs; everything by default).
    """

    def __init__(
        self,
        robot: str,
        program: Callable[[str, int], ProgramView],
        codes: Codes,
        selection: Selection | None = None,
    ) -> None:
        self.robot = robot
        self._program_of = program
        self.codes = codes
        self.selection = selection or Selection()
        self.functions = self.selection.functions
        self._keys = (
            None
            if self.selection.symbols is None
            else [(name, tuple(name.split("."))) for name in sorted(self.selection.symbols)]
        )
        self._programs: dict[int, ProgramCodes] = {}
        self._node_ids: dict[int, tuple[frozenset[int] | None, frozenset[int] | None]] = {}
        self.seq: list[int] = []
        self.t: list[int] = []
        self.gen: list[int] = []
        self._events: dict[str, tuple[list[int], list[Any]]] = {}
        self._present: set[str] = set()
        self._nodes: list[list[Any]] = []
        self._node_rows: list[int] = []
        self._calls: Calls = {}
        self._has_reads = True
        self._last_gen = -1
        self._last_ids: tuple[frozenset[int] | None, frozenset[int] | None] = (None, None)

    def _program(self, gen: int) -> ProgramCodes:
        found = self._programs.get(gen)
        if found is None:
            found = self._programs[gen] = ProgramCodes(self._program_of(self.robot, gen), self.functions, self.codes)
        return found

    def _ids(self, gen: int) -> tuple[frozenset[int] | None, frozenset[int] | None]:
        """The option and behavior ids of generation ``gen`` to keep (None: all)."""
        found = self._node_ids.get(gen)
        if found is None:
            description = self._program(gen).view.description
            options, behaviors = self.selection.options, self.selection.behaviors
            found = self._node_ids[gen] = (
                None if options is None else frozenset(o["id"] for o in description["options"] if o["name"] in options),
                None
                if behaviors is None
                else frozenset(b["id"] for b in description["behaviors"] if b["name"] in behaviors),
            )
        return found

    def _set(self, row: int, name: str, value: Any) -> None:
        events = self._events.get(name)
        if events is None:
            events = self._events[name] = ([], [])
        events[0].append(row)
        events[1].append(value)

    def _tick(self, seq: int, t: int, gen: int, path: list[list[Any]], reads: list[Any] | None) -> int:
        row = len(self.seq)
        self.seq.append(seq)
        self.t.append(t)
        self.gen.append(gen)
        if gen != self._last_gen:
            self._last_gen = gen
            self._last_ids = self._ids(gen)
        options, behaviors = self._last_ids
        if options is None and behaviors is None:
            self._nodes.extend(path)
            self._node_rows.extend([row] * len(path))
        elif options or behaviors:
            for node in path:
                wanted = options if node[0] == 0 else behaviors
                if wanted is None or node[2] in wanted:
                    self._nodes.append(node)
                    self._node_rows.append(row)
        if reads is None:
            self._has_reads = False
        elif self.functions is None or self.functions:
            collect_calls(row, self._program(gen), reads, self.codes, self._calls)
        return row

    def _values(self, data: dict[str, Any]) -> dict[str, Any]:
        """The message's values of the selected names (all when there is no selection)."""
        values: dict[str, Any] = {}
        inputs, outputs = data["inputs"], data["outputs"]
        if self._keys is None:
            _flatten(inputs, values)
            _flatten(outputs, values)
        else:
            for name, keys in self._keys:
                value = _lookup(inputs, keys)
                if value is _MISSING:
                    value = _lookup(outputs, keys)
                if value is not _MISSING:
                    values[name] = value
        return values

    def message(self, data: dict[str, Any]) -> None:
        """Add the tick of one recorded ``xabsl.AgentTick`` message (the first must be a key frame)."""
        row = self._tick(data["seq"], data["t"], data["gen"], data["path"], data.get("reads"))
        keys = self._keys
        if keys is None:
            values = self._values(data)
        else:  # _values inlined: this runs for every tick of every robot a query reads
            values = {}
            inputs, outputs = data["inputs"], data["outputs"]
            for name, path in keys:
                value = _lookup(inputs, path)
                if value is _MISSING:
                    value = _lookup(outputs, path)
                if value is not _MISSING:
                    values[name] = value
        unread_names = data.get("unread")
        if unread_names:
            symbols = self.selection.symbols
            for unread in unread_names:
                if symbols is None or unread in symbols:
                    values[unread] = None
        if data["key"]:
            # a key frame holds every value: what it lacks is not in this generation
            for name in self._present.difference(values):
                self._set(row, name, None)
            self._present = set(values)
        else:
            self._present.update(values)
        events = self._events
        for name, value in values.items():
            found = events.get(name)
            if found is None:
                found = events[name] = ([], [])
            found[0].append(row)
            found[1].append(value)

    def view(self, seq: int, t: int, agent: AgentTick) -> None:
        """Add one decoded tick of the robot (every value of the tick is in the view)."""
        row = self._tick(seq, t, agent.gen, agent.path, agent.reads)
        symbols = self.selection.symbols
        values = {
            name: value
            for name, value in (*agent.inputs.items(), *agent.outputs.items())
            if symbols is None or name in symbols
        }
        for name in self._present.difference(values):
            self._set(row, name, None)
        self._present = set(values)
        for name, value in values.items():
            self._set(row, name, value)

    def _raw(self, value: Any, enum: str | None, tables: dict[str, dict[int, int]]) -> float | None:
        return raw_number(value, enum, tables, self.codes)

    def finish(self) -> RobotColumns:
        """The columns of every tick added so far."""
        events = self.events()
        return events.columns({gen: program.view for gen, program in self._programs.items()}, self.selection)

    def events(self) -> RobotEvents:
        """The ticks added so far with each value as its changes (what a recording stores of them)."""
        nodes = self._node_table()  # first: it reads the programs of every generation seen
        enums = self._enum_tables()
        events: dict[str, tuple[Ints, Floats, Mask]] = {}
        for name, (rows, recorded) in self._events.items():
            raw = self._numbers(recorded, enums.get(name))
            known = np.fromiter((v is not None for v in raw), dtype=np.bool_, count=len(raw))
            values = np.fromiter((np.nan if v is None else v for v in raw), dtype=np.float64, count=len(raw))
            events[name] = (np.asarray(rows, dtype=np.int64), values, known)
        return RobotEvents(
            self.robot,
            np.asarray(self.seq, dtype=np.int64),
            np.asarray(self.t, dtype=np.int64),
            np.asarray(self.gen, dtype=np.int64),
            events,
            nodes,
            {name: call_table(*table) for name, table in self._calls.items()},
            self._collected(),
            self._has_reads,
        )

    def _enum_tables(self) -> dict[str, dict[int, str]]:
        """Per enum symbol: host value -> element, for recordings that hold enum values as numbers.

        A live studio recording writes an enum symbol's value as its element's index (its header's
        ``tables.enums`` names them); a headless one writes the element's name.
        """
        tables: dict[str, dict[int, str]] = {}
        for program in self._programs.values():
            description, enums = program.view.description, program.view.tables.get("enums", {})
            for symbol in (*description["inputs"], *description["outputs"]):
                enum = symbol.get("enum")
                if enum and enum in enums and not symbol.get("params"):
                    tables[symbol["name"]] = {int(v): e for v, e in enums[enum].items()}
        return tables

    def _numbers(self, recorded: list[Any], enum: dict[int, str] | None) -> list[float | None]:
        """Recorded values as numbers (see :func:`_scalar`); plain decimals pass as they are."""
        if all(type(v) is float for v in recorded):
            return recorded
        codes = self.codes
        if enum is None:
            return [scalar(v, codes) for v in recorded]
        out: list[float | None] = []
        for value in recorded:
            if isinstance(value, str):  # an element's name (headless recordings)
                out.append(float(codes.code(value)))
            elif type(value) is int and value in enum:  # an element's index (studio recordings, frames)
                out.append(float(codes.code(enum[value])))
            else:  # anything else is no element: unknown
                out.append(None)
        return out

    def _collected(self) -> frozenset[str]:
        if self.functions is not None:
            return self.functions
        return frozenset(name for p in self._programs.values() for name, _e, _r in p.functions.values())

    def _node_table(self) -> NodeTable:
        nodes = self._nodes
        rows = np.asarray(self._node_rows, dtype=np.int64)
        kind = np.fromiter((node[0] for node in nodes), dtype=np.int64, count=len(nodes))
        ident = np.fromiter((node[2] for node in nodes), dtype=np.int64, count=len(nodes))

        def option_field(index: int, missing: int) -> Ints:
            return np.fromiter(
                (node[index] if node[0] == 0 else missing for node in nodes), dtype=np.int64, count=len(nodes)
            )

        state = option_field(3, -1)
        decided = option_field(6, -1)
        leaf = option_field(7, -1)
        option_time = np.fromiter(
            (node[4] if node[0] == 0 else node[3] for node in nodes), dtype=np.float64, count=len(nodes)
        )
        state_time = np.fromiter(
            (node[5] if node[0] == 0 else np.nan for node in nodes), dtype=np.float64, count=len(nodes)
        )
        gens = np.asarray(self.gen, dtype=np.int64)
        node_gens = gens[rows] if len(rows) else rows
        flat: list[float | None] = []
        counts: list[int] = []
        for node, gen in zip(nodes, node_gens.tolist(), strict=True):
            raw = node[8] if node[0] == 0 else node[4]
            program = self._program(gen)
            if node[0] == 0:
                enums = program.option_param_enums[node[2]]
            else:
                enums = program.behavior_param_enums[node[2]]
            counts.append(len(raw))
            for value, enum in zip(raw, enums, strict=False):
                flat.append(self._raw(value, enum, program.host_enums))
            flat.extend([None] * (len(raw) - len(enums)))
        count = np.asarray(counts, dtype=np.int64)
        start = np.concatenate(([0], np.cumsum(count)[:-1])).astype(np.int64) if len(count) else count
        params_known = np.fromiter((v is not None for v in flat), dtype=np.bool_, count=len(flat))
        params = np.fromiter((np.nan if v is None else v for v in flat), dtype=np.float64, count=len(flat))
        return NodeTable(
            rows, kind, ident, state, decided, leaf, option_time, state_time, start, count, params, params_known
        )


#: Per input function name: the tick rows, arguments and results of its calls, in order.
Calls = dict[str, tuple[list[int], list[tuple[float | None, ...]], list[float | None]]]


def collect_calls(row: int, program: ProgramCodes, reads: list[Any], codes: Codes, calls: Calls) -> None:
    """Add the calls of ``program``'s input functions in one tick's ``reads`` (as JSON reads them) to ``calls``."""
    functions = program.functions
    if not functions:
        return
    tables = program.read_enums
    for entry in reads:
        if not isinstance(entry, list) or not entry or not isinstance(entry[0], int):
            continue
        wanted = functions.get(entry[0])
        if wanted is None:
            continue
        name, param_enums, result_enum = wanted
        if len(entry) != len(param_enums) + 2:
            continue
        args = tuple(raw_number(v, e, tables, codes) for v, e in zip(entry[1:-1], param_enums, strict=True))
        table = calls.get(name)
        if table is None:
            table = calls[name] = ([], [], [])
        table[0].append(row)
        table[1].append(args)
        table[2].append(raw_number(entry[-1], result_enum, tables, codes))


def call_table(rows: list[int], args: list[tuple[float | None, ...]], result: list[float | None]) -> CallTable:
    """The calls of one input function as a :class:`CallTable`."""
    known = np.fromiter((v is not None for v in result), dtype=np.bool_, count=len(result))
    values = np.fromiter((np.nan if v is None else v for v in result), dtype=np.float64, count=len(result))
    return CallTable(np.asarray(rows, dtype=np.int64), args, values, known)
