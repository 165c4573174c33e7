"""The one conversion of a value given from outside the behavior into an engine value (§1.4).

Debug requests (forcing a root with parameters, overriding an input symbol, an output-symbol root
action), the studio's commands and the conformance kit's input traces all hand the engine values
that came from a user, a JSON message or a file. :func:`coerce` turns each into what the engine
stores (decimals as finite floats, booleans as bools, enum values as host integers) or refuses it
with one :class:`~xabsl_studio.engine.errors.ValueConversionError` naming the value and what was expected.

Enum values are given as a qualified element name (``"mode.walk"``), as a host value (an int the
enumeration registers), or, for clients that number elements as the program JSON does
(``xabsl_studio.engine.emit.json``, the studio protocol), as the element's index in declaration order
(``by_index=True``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

from xabsl_studio.engine.errors import ValueConversionError
from xabsl_studio.engine.types import Kind, Value

__all__ = ["EnumValues", "coerce"]


@dataclass(frozen=True, slots=True)
class EnumValues:
    """An enumeration as the engine runs it: qualified elements (declaration order) -> host values."""

    name: str
    elements: Mapping[str, int]

    def element(self, index: int) -> str | None:
        """The element at ``index`` in declaration order (None when out of range)."""
        if 0 <= index < len(self.elements):
            return list(self.elements)[index]
        return None


def coerce(kind: Kind, enum: EnumValues | None, value: object, *, name: str = "value", by_index: bool = False) -> Value:
    """``value`` as the engine stores a ``kind`` value of enumeration ``enum``.

    Args:
        kind: the declared type of the symbol or parameter.
        enum: its enumeration (for ``Kind.ENUM``; None: the enumeration is unknown to the engine).
        value: what was given: a number, a bool, an element name or an enum value.
        name: what the value is for, for the error message (``"parameter walk.speed"``).
        by_index: an int given for an enum is the element's index, not its host value.

    Raises:
        ValueConversionError: a value of the wrong type, a number that is not finite or cannot
            be a double, an unknown or unqualified element, an int that is no value (index) of
            the enumeration.
    """
    if kind is Kind.DECIMAL:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueConversionError(f"{name} is decimal, got {value!r}")
        try:
            number = float(value)
        except OverflowError:
            raise ValueConversionError(f"{name}: {value} is out of the range of a decimal") from None
        if not math.isfinite(number):
            raise ValueConversionError(f"{name}: {value!r} is not a finite number")
        return number
    if kind is Kind.BOOLEAN:
        if not isinstance(value, bool):
            raise ValueConversionError(f"{name} is boolean, got {value!r}")
        return value
    label = enum.name if enum is not None else "its enumeration"
    if isinstance(value, str):
        if enum is not None and value in enum.elements:
            return enum.elements[value]
        if enum is not None and "." not in value and f"{enum.name}.{value}" in enum.elements:
            raise ValueConversionError(f"{name}: enum element {value!r} is not qualified (write {enum.name}.{value})")
        raise ValueConversionError(f"{name}: {value!r} is not an element of enumeration {label}")
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueConversionError(f"{name} is an enum of {label}, give an element name, got {value!r}")
    if enum is None:
        raise ValueConversionError(f"{name}: enumeration unknown, give a qualified element name, got {value!r}")
    if by_index:
        element = enum.element(value)
        if element is None:
            raise ValueConversionError(f"{name}: no element {value} in enumeration {enum.name}")
        return enum.elements[element]
    if value not in enum.elements.values():
        raise ValueConversionError(f"{name}: {value} is not a value of enumeration {enum.name}")
    return value
