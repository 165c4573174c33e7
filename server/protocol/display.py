"""Display values (docs/protocol.md "Values"): how a raw symbol or parameter value is shown in frames.

Decimals to :data:`DECIMALS` fractional digits, booleans as booleans, enum values as the index of
their element in the enumeration (a host value the enumeration does not name: -1); a value that
does not convert (NaN, infinities, a stray type) is None, unknown.

The server converts every sample of a host that sends raw values (the simulation process, an
attach host): the robots' symbol tuples and the parameters in their paths
(:class:`SampleDisplay`), so that a host's tick path only reads raw values; the host converts
only the overrides it reports. A :class:`SampleDisplay` is built from what a generation announces
(the programs' descriptions, the enum host values, the symbol ids per robot) and converts, per
robot, only the symbol values that changed since the robot's last sample (:class:`Displayed`).
"""

from __future__ import annotations

import dataclasses
import operator
from collections.abc import Callable, Mapping, Sequence
from itertools import compress
from typing import Any

import orjson

from xabsl_studio.engine.runtime.activation import BEHAVIOR_NODE, OPTION_NODE
from xabsl_studio.engine.types import Kind, Value
from xabsl_studio.server.protocol.host import Sample
from xabsl_studio.server.protocol.types import BEHAVIOR_PARAMS_INDEX, ID_INDEX, KIND_INDEX, OPTION_PARAMS_INDEX

__all__ = [
    "DECIMALS",
    "Displayed",
    "ProgramDisplay",
    "SampleDisplay",
    "converter",
    "display_path",
    "display_values",
    "program_display",
    "round_decimal",
]

#: Decimal values are rounded to this many fractional digits in frames (display precision).
DECIMALS = 3

_SCALE = 10.0**DECIMALS

Converter = Callable[[Any], Value | None]


def round_decimal(value: float) -> float:
    """``value`` to DECIMALS fractional digits for display.

    ``round(v * 1000) / 1000`` rather than ``round(v, 3)``: the two-argument round does exact
    decimal rounding through a string conversion and costs 3-4x as much, and every changed decimal
    of every robot passes here on every tick. NaN and infinities raise (the caller shows None).
    """
    return round(value * _SCALE) / _SCALE


def _decimal(value: Any) -> float:
    return round_decimal(float(value))


def converter(kind: Kind, enum_index: Mapping[int, int] | None = None) -> Converter:
    """The conversion of one value of ``kind``; ``enum_index`` maps an enum's host values to element indices."""
    if kind is Kind.DECIMAL:
        return _decimal
    if kind is Kind.BOOLEAN:
        return bool
    table = enum_index if enum_index is not None else {}
    return lambda value: table.get(int(value), -1)


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

    def __init__(self, converters: tuple[Converter, ...]) -> None:
        self._converters = converters
        self._raw: tuple[Value | None, ...] | None = None
        self._shown: tuple[Value | None, ...] = ()

    def display(self, values: tuple[Value | None, ...]) -> tuple[Value | None, ...]:
        """``values`` as display values (None stays None: a getter that raised, a value unknown)."""
        raw = self._raw
        if raw is None or len(raw) != len(values):
            shown = display_values(self._converters, values)
            self._raw, self._shown = values, shown
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
                value = values[i]
                try:
                    out[i] = None if value is None else converters[i](value)
                except Exception:  # NaN, infinities, a stray type: unknown
                    out[i] = None
        shown = tuple(out)
        self._raw, self._shown = values, shown
        return shown


def display_values(converters: tuple[Converter, ...], values: tuple[Value | None, ...]) -> tuple[Value | None, ...]:
    """``values`` converted for display, in C when every value is there and converts."""
    if len(converters) == len(values):
        try:
            return tuple(map(operator.call, converters, values))
        except Exception:  # None, a value that does not convert (NaN, a stray type): one by one below
            pass
    out: list[Value | None] = []
    for convert, value in zip(converters, values, strict=False):
        try:
            out.append(None if value is None else convert(value))
        except Exception:
            out.append(None)
    out.extend([None] * (len(values) - len(out)))
    return tuple(out)


#: Per (node kind, option or basic behavior id): the conversion of each parameter, in path order.
ParamConverters = dict[tuple[int, int], tuple[Converter, ...]]


@dataclasses.dataclass(frozen=True, slots=True)
class ProgramDisplay:
    """One program's conversions: inputs and outputs by symbol id, parameters by node (:func:`program_display`)."""

    inputs: dict[int, Converter]
    outputs: dict[int, Converter]
    params: ParamConverters


def program_display(description: Mapping[str, Any], enums: Mapping[str, Mapping[int, str]]) -> ProgramDisplay:
    """The conversions of one program's description (``enums``: enum name -> host value -> element)."""
    index_of: dict[str, dict[int, int]] = {}
    for enum in description.get("enums", ()):
        position = {element: i for i, element in enumerate(enum.get("elements", ()))}
        hosts = enums.get(enum["name"], {})
        index_of[enum["name"]] = {int(v): position.get(e, -1) for v, e in hosts.items()}

    def convert(declared: Mapping[str, Any]) -> Converter:
        return converter(Kind(declared["type"]), index_of.get(declared.get("enum") or "", {}))

    def table(symbols: Sequence[Mapping[str, Any]]) -> dict[int, Converter]:
        return {int(s["id"]): convert(s) for s in symbols if not s.get("params")}

    # Parameters in a path are in declaration order, as the description lists them.
    params: ParamConverters = {}
    kinds = ((OPTION_NODE, description.get("options", ())), (BEHAVIOR_NODE, description.get("behaviors", ())))
    for kind, nodes in kinds:
        for node in nodes:
            if node.get("params"):
                params[(kind, int(node["id"]))] = tuple(convert(p) for p in node["params"])
    return ProgramDisplay(table(description.get("inputs", ())), table(description.get("outputs", ())), params)


def display_path(params: ParamConverters, path: bytes) -> bytes:
    """A path (JSON, parameters raw) with its parameters as display values (one that does not convert: null).

    A path that is not a list of nodes, or a node of an id ``params`` does not know, keeps its
    values as they came: nothing is guessed, and nothing but parameters is touched.
    """
    try:
        nodes = orjson.loads(path)
    except orjson.JSONDecodeError:
        return path
    if not isinstance(nodes, list):
        return path
    changed = False
    for node in nodes:
        if not isinstance(node, list) or len(node) <= BEHAVIOR_PARAMS_INDEX:
            continue
        kind = node[KIND_INDEX]
        at = OPTION_PARAMS_INDEX if kind == OPTION_NODE else BEHAVIOR_PARAMS_INDEX
        values = node[at] if len(node) > at else None
        converters = params.get((kind, node[ID_INDEX])) if values else None
        if converters is None or not isinstance(values, list) or len(values) != len(converters):
            continue
        shown: list[Value | None] = []
        for convert, value in zip(converters, values, strict=True):
            try:
                shown.append(None if value is None else convert(value))
            except Exception:  # a value that does not convert: unknown
                shown.append(None)
        node[at] = shown
        changed = True
    return orjson.dumps(nodes) if changed else path


class SampleDisplay:
    """A generation's samples with raw symbol values -> the same samples with display values.

    Built from what the generation announced: ``structure`` (the programs' descriptions by key and
    the robots with their program key), ``enums`` (per key: enum name -> host value -> element)
    and the symbol ids each robot's input and output tuples are aligned with. Keeps, per robot,
    the last raw and display tuples (:class:`Displayed`): build one per generation and feed it
    that generation's samples in order.
    """

    __slots__ = ("_inputs", "_outputs", "_params")

    def __init__(
        self,
        structure: Mapping[str, Any],
        enums: Mapping[str, Mapping[str, Mapping[int, str]]],
        input_ids: tuple[tuple[int, ...], ...],
        output_ids: tuple[tuple[int, ...], ...],
    ) -> None:
        tables = {key: program_display(d, enums.get(key, {})) for key, d in structure.get("programs", {}).items()}
        nothing = ProgramDisplay({}, {}, {})
        robots = structure.get("robots", ())
        self._inputs: list[Displayed] = []
        self._outputs: list[Displayed] = []
        #: per robot: its program's parameter conversions (None: no parameters to convert)
        self._params: list[ParamConverters | None] = []
        for i, (ins, outs) in enumerate(zip(input_ids, output_ids, strict=True)):
            key = robots[i].get("program") if i < len(robots) else None
            program = tables.get(key, nothing) if key is not None else nothing
            self._inputs.append(Displayed(tuple(program.inputs.get(s, _unknown) for s in ins)))
            self._outputs.append(Displayed(tuple(program.outputs.get(s, _unknown) for s in outs)))
            self._params.append(program.params or None)

    def convert(self, sample: Sample) -> Sample:
        """``sample`` with its robots' input and output values as display values."""
        inputs = tuple(map(Displayed.display, self._inputs, sample.inputs))
        outputs = tuple(map(Displayed.display, self._outputs, sample.outputs))
        paths = tuple(
            path if params is None else display_path(params, path)
            for params, path in zip(self._params, sample.paths, strict=False)
        )
        # A sample with more robots than the generation (never sent) keeps the rest as they came.
        return dataclasses.replace(
            sample,
            paths=paths + sample.paths[len(paths) :],
            inputs=inputs + sample.inputs[len(inputs) :],
            outputs=outputs + sample.outputs[len(outputs) :],
        )


def _unknown(value: Any) -> None:
    """A symbol id the description does not have: its value cannot be shown."""
    return None
