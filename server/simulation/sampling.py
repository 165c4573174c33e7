"""Sampling after a tick (simulation process): one robot's activation path and symbols as display values.

The engine is read through the project's one sampler (``xabsl_studio.engine.record.sampler.AgentSampler``,
the recorder's too): the compact ``path`` of docs/protocol.md (integer ids), the input and
output symbols, and what the tick's decisions read (exact, as JSON: the server's ring keeps it
so that "why" at any past tick uses the values the decision saw). This module turns the symbols
into the values frames carry (decimals rounded, enums as element indices) and builds the id
tables of a program (:class:`ProgramCodec`); the tick's sample goes to the server process
(``xabsl_studio.server.session.frames`` keeps and encodes it).
"""

from __future__ import annotations

import operator
from collections.abc import Callable
from dataclasses import dataclass
from itertools import compress
from typing import Any

import orjson

from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.record.sampler import AgentSampler, ProgramTables, reads_json
from xabsl_studio.engine.runtime import Engine
from xabsl_studio.engine.runtime.activation import BEHAVIOR_NODE, OPTION_NODE
from xabsl_studio.engine.types import Kind, Value
from xabsl_studio.server.protocol.types import BEHAVIOR_PARAMS_INDEX, ID_INDEX, KIND_INDEX, OPTION_PARAMS_INDEX

#: Decimal values are rounded to this many fractional digits in frames (display precision).
DECIMALS = 3

_OPT = orjson.OPT_NON_STR_KEYS


@dataclass(slots=True)
class ProgramCodec:
    """Name -> id tables of one program and host value -> element index per enumeration."""

    key: str
    program: Program
    option_ids: dict[str, int]
    state_ids: dict[str, dict[str, int]]
    behavior_ids: dict[str, int]
    behavior_params: dict[str, tuple[str, ...]]
    inputs: tuple[tuple[int, str, Kind, str | None], ...]
    outputs: tuple[tuple[int, str, Kind, str | None], ...]
    enum_index: dict[str, dict[int, int]]
    #: what the shared sampler needs to read the program's engines (symbols in the order above)
    tables: ProgramTables

    @classmethod
    def build(cls, key: str, program: Program, engine: Engine) -> ProgramCodec:
        """Tables for ``program``; ``engine`` (one that runs it) gives the enums' host values."""
        enum_index: dict[str, dict[int, int]] = {}
        for name, enum in program.enums.items():
            table: dict[int, int] = {}
            for i, element in enumerate(enum.elements):
                try:
                    table.setdefault(int(engine.enum_value(element)), i)
                except KeyError:
                    continue
            enum_index[name] = table
        return cls(
            key=key,
            program=program,
            option_ids={name: o.index for name, o in program.options.items()},
            state_ids={name: {s.name: s.index for s in o.states} for name, o in program.options.items()},
            behavior_ids={name: b.index for name, b in program.behaviors.items()},
            behavior_params={name: tuple(p.name for p in b.params) for name, b in program.behaviors.items()},
            inputs=tuple((s.index, s.name, s.kind, s.enum) for s in program.inputs.values() if not s.params),
            outputs=tuple((s.index, s.name, s.kind, s.enum) for s in program.outputs.values()),
            enum_index=enum_index,
            tables=ProgramTables.of(engine),
        )

    def display(self, kind: Kind, enum: str | None, value: Any) -> Value | None:
        """A value as frames carry it (see docs/protocol.md "Values")."""
        if kind is Kind.DECIMAL:
            try:
                return round(float(value), DECIMALS)
            except (TypeError, ValueError, OverflowError):
                return None
        if kind is Kind.BOOLEAN:
            return bool(value)
        if enum is None:
            return int(value)
        return self.enum_index.get(enum, {}).get(int(value), -1)

    def element(self, enum: str | None, index: int) -> str | None:
        """The qualified element name at ``index`` of ``enum`` (for commands that take indices)."""
        if enum is None or enum not in self.program.enums:
            return None
        elements = self.program.enums[enum].elements
        return elements[index] if 0 <= index < len(elements) else None


class FrameSampler:
    """One robot's part of a frame after a tick: display path, input and output values, extras.

    The engine is read by the one sampler of the project, :class:`xabsl_studio.engine.record.sampler.AgentSampler`
    (the recorder's too); this class only turns its raw values into the display values of frames
    (docs/protocol.md "Values": decimals rounded, booleans, enum element indices).
    """

    __slots__ = (
        "_behavior_params",
        "_inputs",
        "_option_params",
        "_outputs",
        "_shown_params",
        "codec",
        "engine",
        "index",
        "reader",
    )

    def __init__(self, index: int, engine: Engine, codec: ProgramCodec) -> None:
        self.index = index
        self.engine = engine
        self.codec = codec
        #: the shared sampler (assignment values are not part of frames)
        self.reader = AgentSampler(engine, codec.tables, assignments=False)
        # Per symbol (in the sampler's order, which is the codec's): the conversion to a display value.
        self._inputs = Displayed(tuple(self._converter(kind, enum) for _, _, kind, enum in codec.inputs))
        self._outputs = Displayed(tuple(self._converter(kind, enum) for _, _, kind, enum in codec.outputs))
        #: per (node kind, id): the raw parameters of its last path node and their display values
        self._shown_params: dict[tuple[int, int], tuple[list[Any], list[Any]]] = {}
        # Per option / basic behavior id: the conversion of each parameter, in declaration order.
        program = codec.program
        self._option_params = {
            o.index: tuple(self._converter(p.kind, p.enum) for p in o.params) for o in program.options.values()
        }
        self._behavior_params = {
            b.index: tuple(self._converter(p.kind, p.enum) for p in b.params) for b in program.behaviors.values()
        }

    def path(self) -> list[list[Any]]:
        """The robot's activation path in the frame format (docs/protocol.md "path").

        The engine's compact path already has the frame's node layout and the JSON ids; only the
        parameter values are turned into display values (rounded decimals, enum element indices).
        """
        nodes = self.reader.path()
        shown = self._shown_params
        for node in nodes:
            kind = node[KIND_INDEX]
            at = OPTION_PARAMS_INDEX if kind == OPTION_NODE else BEHAVIOR_PARAMS_INDEX
            raw = node[at]
            if not raw:
                continue
            # Most ticks call an option or behavior with the parameters of the tick before: those
            # are converted once (the lists are equal, compared in C), not on every tick.
            key = (kind, node[ID_INDEX])
            last = shown.get(key)
            if last is not None and last[0] == raw:
                node[at] = last[1]
                continue
            converters = self._option_params if kind == OPTION_NODE else self._behavior_params
            values = [convert(v) for convert, v in zip(converters[node[ID_INDEX]], raw, strict=True)]
            shown[key] = (raw, values)
            node[at] = values
        return nodes

    def _converter(self, kind: Kind, enum: str | None) -> Callable[[Any], Value | None]:
        if kind is Kind.DECIMAL:
            return _round
        if kind is Kind.BOOLEAN:
            return bool
        table = self.codec.enum_index.get(enum or "", {})
        return lambda value: table.get(int(value), -1)

    def inputs(self) -> tuple[Value | None, ...]:
        """The display values of the plain input symbols (None: the host getter failed)."""
        values, unread = self.reader.inputs()
        return self._inputs.display(values, unread)

    def outputs(self) -> tuple[Value | None, ...]:
        """The display values of the output and internal symbols."""
        values, unread = self.reader.outputs()
        return self._outputs.display(values, unread)

    def reads(self) -> bytes:
        """What the robot's decisions read in the tick, exact, as JSON (docs/recordings.md ``reads``).

        b'' (unknown) when the engine does not record reads (an attach host with no studio until
        this tick).
        """
        return reads_json(self.reader.reads()) if self.engine.record_reads else b""

    def extras(self) -> bytes:
        """``,"fault":...,"forced":...,"overrides":...`` for the robot's object, or b''."""
        engine = self.engine
        parts: dict[str, Any] = {}
        fault = engine.fault
        if fault is not None:
            parts["fault"] = {"message": fault.message, "option": fault.option, "state": fault.state}
        forced = engine.root_actions.forced
        if forced:
            root = forced[0]
            if root.kind == "option":
                parts["forced"] = [OPTION_NODE, self.codec.option_ids.get(root.name, -1)]
            else:
                parts["forced"] = [BEHAVIOR_NODE, self.codec.behavior_ids.get(root.name, -1)]
        overrides = engine.root_actions.overrides
        if overrides:
            program = self.codec.program
            parts["overrides"] = {
                program.inputs[name].index: self.codec.display(program.inputs[name].kind, program.inputs[name].enum, v)
                for name, v in overrides.items()
                if name in program.inputs
            }
        if not parts:
            return b""
        return b"," + orjson.dumps(parts, option=_OPT)[1:-1]


#: Symbols compared as one slice before value by value (:class:`Displayed`).
_BLOCK = 16


class Displayed:
    """The display values of one robot's symbols, converting only what changed since the last tick.

    Most symbols keep their value from one tick to the next (of a team-sized set's hundreds of
    inputs, a few change): the raw tuple is compared with the last one in C, and only the values
    that differ are converted again. Equal raw values convert to equal display values, so this
    gives exactly what converting everything gives (0.0 and -0.0 are equal: a zero keeps the
    sign it was first shown with).
    """

    __slots__ = ("_converters", "_raw", "_shown")

    def __init__(self, converters: tuple[Callable[[Any], Value | None], ...]) -> None:
        self._converters = converters
        self._raw: tuple[Value | None, ...] | None = None
        self._shown: tuple[Value | None, ...] = ()

    def display(self, values: tuple[Value | None, ...], unread: tuple[str, ...]) -> tuple[Value | None, ...]:
        """``values`` as display values (None where a getter raised, ``unread`` names them)."""
        raw = self._raw
        if unread or raw is None or len(raw) != len(values):
            shown = _display(self._converters, values, unread)
            # After a failed read the next tick converts everything again (None is no raw value).
            self._raw, self._shown = (None if unread else values), shown
            return shown
        if values == raw:
            return self._shown
        out = list(self._shown)
        converters = self._converters
        n = len(values)
        # Blocks first: a tuple comparison skips identical objects (a value the host did not touch),
        # so unchanged blocks cost a slice each and only changed ones are compared value by value.
        for start in range(0, n, _BLOCK):
            end = start + _BLOCK
            if values[start:end] == raw[start:end]:
                continue
            for i in compress(range(start, min(end, n)), map(operator.ne, values[start:end], raw[start:end])):
                try:
                    out[i] = converters[i](values[i])
                except Exception:  # NaN, infinities, a stray type: unknown
                    out[i] = None
        shown = tuple(out)
        self._raw, self._shown = values, shown
        return shown


def _display(
    converters: tuple[Callable[[Any], Value | None], ...], values: tuple[Value | None, ...], unread: tuple[str, ...]
) -> tuple[Value | None, ...]:
    """``values`` converted for display, in C when every value was read and converts."""
    if not unread:
        try:
            return tuple(map(operator.call, converters, values))
        except Exception:  # a value that does not convert (NaN, a stray type): one by one below
            pass
    out: list[Value | None] = []
    for convert, value in zip(converters, values, strict=True):
        try:
            out.append(None if value is None else convert(value))
        except Exception:
            out.append(None)
    return tuple(out)


_SCALE = 10.0**DECIMALS


def _round(value: float) -> float:
    """``value`` to DECIMALS fractional digits for display.

    ``round(v * 1000) / 1000`` rather than ``round(v, 3)``: the two-argument round does exact
    decimal rounding through a string conversion and costs 3-4x as much, and every decimal input
    and output of every robot passes here on every tick. NaN and infinities raise (the sampler
    then records None for the value).
    """
    return round(value * _SCALE) / _SCALE
