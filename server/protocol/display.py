"""Display values (docs/protocol.md "Values"): how a raw symbol or parameter value is shown in frames.

Decimals to :data:`DECIMALS` fractional digits, booleans as booleans, enum values as the index of
their element in the enumeration (a host value the enumeration does not name: -1); a value that
does not convert (NaN, infinities, a stray type) is None, unknown.

Two sides convert: the simulation process (and an attach host) converts the parameters in paths
and the overrides it reports, and the server converts the robots' symbol tuples of every sample
(:class:`SampleDisplay`), so that a host's tick path only reads raw values. A
:class:`SampleDisplay` is built from what a generation announces (the programs' descriptions, the
enum host values, the symbol ids per robot) and converts, per robot, only the values that changed
since the robot's last sample (:class:`Displayed`).
"""

from __future__ import annotations

import dataclasses
import operator
from collections.abc import Callable, Mapping, Sequence
from itertools import compress
from typing import Any

from xabsl_studio.engine.types import Kind, Value
from xabsl_studio.server.protocol.host import Sample

__all__ = ["DECIMALS", "Displayed", "SampleDisplay", "converter", "display_values", "round_decimal"]

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


def _symbol_converters(
    description: Mapping[str, Any], enums: Mapping[str, Mapping[int, str]]
) -> tuple[dict[int, Converter], dict[int, Converter]]:
    """Per symbol id of one program's description: the conversion of its inputs and of its outputs."""
    index_of: dict[str, dict[int, int]] = {}
    for enum in description.get("enums", ()):
        position = {element: i for i, element in enumerate(enum.get("elements", ()))}
        hosts = enums.get(enum["name"], {})
        index_of[enum["name"]] = {int(v): position.get(e, -1) for v, e in hosts.items()}

    def table(symbols: Sequence[Mapping[str, Any]]) -> dict[int, Converter]:
        return {
            int(s["id"]): converter(Kind(s["type"]), index_of.get(s.get("enum") or "", {}))
            for s in symbols
            if not s.get("params")
        }

    return table(description.get("inputs", ())), table(description.get("outputs", ()))


class SampleDisplay:
    """A generation's samples with raw symbol values -> the same samples with display values.

    Built from what the generation announced: ``structure`` (the programs' descriptions by key and
    the robots with their program key), ``enums`` (per key: enum name -> host value -> element)
    and the symbol ids each robot's input and output tuples are aligned with. Keeps, per robot,
    the last raw and display tuples (:class:`Displayed`): build one per generation and feed it
    that generation's samples in order.
    """

    __slots__ = ("_inputs", "_outputs")

    def __init__(
        self,
        structure: Mapping[str, Any],
        enums: Mapping[str, Mapping[str, Mapping[int, str]]],
        input_ids: tuple[tuple[int, ...], ...],
        output_ids: tuple[tuple[int, ...], ...],
    ) -> None:
        tables: dict[str, tuple[dict[int, Converter], dict[int, Converter]]] = {}
        for key, description in structure.get("programs", {}).items():
            tables[key] = _symbol_converters(description, enums.get(key, {}))
        robots = structure.get("robots", ())
        self._inputs: list[Displayed] = []
        self._outputs: list[Displayed] = []
        for i, (ins, outs) in enumerate(zip(input_ids, output_ids, strict=True)):
            key = robots[i].get("program") if i < len(robots) else None
            by_input, by_output = tables.get(key, ({}, {})) if key is not None else ({}, {})
            self._inputs.append(Displayed(tuple(by_input.get(s, _unknown) for s in ins)))
            self._outputs.append(Displayed(tuple(by_output.get(s, _unknown) for s in outs)))

    def convert(self, sample: Sample) -> Sample:
        """``sample`` with its robots' input and output values as display values."""
        inputs = tuple(map(Displayed.display, self._inputs, sample.inputs))
        outputs = tuple(map(Displayed.display, self._outputs, sample.outputs))
        # A sample with more robots than the generation (never sent) keeps the rest as they came.
        return dataclasses.replace(
            sample, inputs=inputs + sample.inputs[len(inputs) :], outputs=outputs + sample.outputs[len(outputs) :]
        )


def _unknown(value: Any) -> None:
    """A symbol id the description does not have: its value cannot be shown."""
    return None
