"""The bench world's computed input functions: the ones with a common mathematical meaning.

A behavior set declares its host functions itself (``float input abs (value);``); the bench does
not know their C++ and, until this module, answered 0 for all of them. A function whose name
and parameters match a row of :data:`TABLE` is instead *computed* by its common meaning, so a
team set's ``vector.abs(x = …, y = …) > 800`` is true when the distance is. Anything else stays
settable by hand, and a computed one is still overridable (by hand or by a bindings module).

Matching (:func:`match`) is by name and parameters, never by guessing:

* the name is the row's name, or the row's name after a namespace prefix ending in ``.``
  (``math.abs`` matches ``abs``; ``vector.abs`` is a row of its own);
* every parameter is decimal and the result is decimal;
* the parameters' declared names, in declaration order, are one of the row's accepted lists
  (``atan2`` needs ``y, x`` to know which is which; ``min`` takes any two names).

Angles: a parameter or result whose unit is ``rad`` is in radians, ``deg``, ``°`` or no unit in
degrees (the convention of XABSL sets: NaoTH declares ``sin (angle "deg")`` and ``atan2 "deg"``).
The description the studio shows says which (``sin(angle °)``).

Values are the engine's floats. Where Python's ``math`` raises (``sqrt(-1)``, ``asin(2)``,
``normalize(inf)``) the result is NaN, and NaN in is NaN out (also for ``min``, ``max`` and
``clip``, where Python's ``min`` would depend on the order).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from xabsl_studio.engine.ir.model import InputSymbol
from xabsl_studio.engine.types import Kind

#: Units read as radians; every other unit (and none) is degrees.
RADIANS = frozenset({"rad", "radian", "radians"})

Function = Callable[..., float]


def _nan_guard(function: Callable[..., float]) -> Callable[..., float]:
    def guarded(*args: float) -> float:
        try:
            return function(*args)
        except (ValueError, OverflowError):
            return math.nan

    return guarded


def normalize_degrees(angle: float) -> float:
    """``angle`` in (-180, 180] (NaN for NaN and the infinities)."""
    if not math.isfinite(angle):
        return math.nan
    result = math.fmod(angle, 360.0)
    if result > 180.0:
        result -= 360.0
    elif result <= -180.0:
        result += 360.0
    return result


def normalize_radians(angle: float) -> float:
    """``angle`` in (-pi, pi] (NaN for NaN and the infinities)."""
    if not math.isfinite(angle):
        return math.nan
    result = math.fmod(angle, math.tau)
    if result > math.pi:
        result -= math.tau
    elif result <= -math.pi:
        result += math.tau
    return result


def _minimum(a: float, b: float) -> float:
    return math.nan if math.isnan(a) or math.isnan(b) else min(a, b)


def _maximum(a: float, b: float) -> float:
    return math.nan if math.isnan(a) or math.isnan(b) else max(a, b)


def _distance(x1: float, y1: float, x2: float, y2: float) -> float:
    return math.hypot(x2 - x1, y2 - y1)


def _clip(value: float, lo: float, hi: float) -> float:
    if math.isnan(value) or math.isnan(lo) or math.isnan(hi):
        return math.nan
    return lo if value < lo else hi if value > hi else value


@dataclass(frozen=True, slots=True)
class Row:
    """One computed function: its names, accepted parameter lists, and what it computes.

    ``make(param_degrees, result_degrees)`` returns the function for the declared units: whether
    the angle parameter and the angle result are in degrees (ignored by functions without angles).
    """

    name: str
    params: tuple[tuple[str, ...], ...]
    make: Callable[[bool, bool], Function]
    #: "param": the parameter is an angle; "result": the result is; "": no angles
    angle: str = ""
    #: any parameter names of the right number
    any_names: bool = False


def _trig(forward: Callable[[float], float]) -> Callable[[bool, bool], Function]:
    def make(param_degrees: bool, result_degrees: bool) -> Function:
        if param_degrees:
            return _nan_guard(lambda angle: forward(math.radians(angle)))
        return _nan_guard(forward)

    return make


def _inverse(backward: Callable[..., float]) -> Callable[[bool, bool], Function]:
    def make(param_degrees: bool, result_degrees: bool) -> Function:
        if result_degrees:
            return _nan_guard(lambda *args: math.degrees(backward(*args)))
        return _nan_guard(backward)

    return make


def _plain(function: Function) -> Callable[[bool, bool], Function]:
    guarded = _nan_guard(function)
    return lambda param_degrees, result_degrees: guarded


def _normalize(param_degrees: bool, result_degrees: bool) -> Function:
    return normalize_degrees if param_degrees else normalize_radians


_ONE = (("value",), ("x",), ("a",))
_ANGLE = (("angle",), ("alpha",), ("value",), ("x",), ("a",))
_XY = (("x", "y"),)

#: Every computed function (docs/bench.md prints this table).
TABLE: tuple[Row, ...] = (
    Row("abs", _ONE, _plain(abs)),
    Row("min", (("value0", "value1"),), _plain(_minimum), any_names=True),
    Row("max", (("value0", "value1"),), _plain(_maximum), any_names=True),
    Row("sqrt", _ONE, _plain(math.sqrt)),
    Row("sin", _ANGLE, _trig(math.sin), angle="param"),
    Row("cos", _ANGLE, _trig(math.cos), angle="param"),
    Row("tan", _ANGLE, _trig(math.tan), angle="param"),
    Row("asin", _ONE, _inverse(math.asin), angle="result"),
    Row("acos", _ONE, _inverse(math.acos), angle="result"),
    Row("atan", _ONE, _inverse(math.atan), angle="result"),
    Row("atan2", (("y", "x"),), _inverse(math.atan2), angle="result"),
    Row("clip", (("value", "min", "max"), ("value", "lo", "hi"), ("value", "low", "high")), _plain(_clip)),
    Row("clamp", (("value", "min", "max"), ("value", "lo", "hi"), ("value", "low", "high")), _plain(_clip)),
    Row("normalize", (("angle",), ("value",), ("a",)), _normalize, angle="param"),
    Row("normalize_angle", (("angle",), ("value",), ("a",)), _normalize, angle="param"),
    Row("vector.abs", _XY, _plain(math.hypot)),
    Row("vector.length", _XY, _plain(math.hypot)),
    Row("vector.angle", _XY, _inverse(lambda x, y: math.atan2(y, x)), angle="result"),
    Row("hypot", _XY, _plain(math.hypot)),
    Row("distance", (("x1", "y1", "x2", "y2"), ("ax", "ay", "bx", "by")), _plain(_distance)),
)

_BY_NAME = {row.name: row for row in TABLE}


@dataclass(frozen=True, slots=True)
class Computed:
    """A matched input function: what the bench calls and what the studio shows."""

    name: str
    function: Function
    #: ``abs(value)``, ``sin(angle °)``: the studio's "computed: …"
    description: str


def _row_for(name: str) -> Row | None:
    if name in _BY_NAME:
        return _BY_NAME[name]
    # a namespace prefix: math.abs, math_symbols.abs (never vector.abs for abs's sake: exact rows first)
    tail = name.rsplit(".", 1)[-1]
    row = _BY_NAME.get(tail)
    return row if row is not None and "." not in row.name else None


def _is_degrees(unit: str | None) -> bool:
    return (unit or "").strip().strip('"').lower() not in RADIANS


def match(symbol: InputSymbol) -> Computed | None:
    """The computed function for ``symbol`` (an input function), or None when no row fits."""
    if not symbol.params or symbol.kind is not Kind.DECIMAL:
        return None
    row = _row_for(symbol.name)
    if row is None or any(p.kind is not Kind.DECIMAL for p in symbol.params):
        return None
    names = tuple(p.short_name for p in symbol.params)
    if names not in row.params and not (row.any_names and len(names) == len(row.params[0])):
        return None
    param_degrees = _is_degrees(symbol.params[0].unit)
    result_degrees = _is_degrees(symbol.unit)
    shown = list(names)
    if row.angle == "param":
        shown[0] += " °" if param_degrees else " rad"
    text = f"{row.name}({', '.join(shown)})"
    if row.angle == "result" or (row.name.startswith("normalize") and row.angle == "param"):
        text += " °" if (result_degrees if row.angle == "result" else param_degrees) else " rad"
    return Computed(symbol.name, row.make(param_degrees, result_degrees), text)


def table_rows() -> Sequence[tuple[str, str, str]]:
    """``(name, accepted parameter lists, angles)`` per row, for the documentation."""
    rows = []
    for row in TABLE:
        params = " or ".join(f"({', '.join(p)})" for p in row.params)
        if row.any_names:
            params = f"any {len(row.params[0])} names"
        angles = {"param": "parameter is an angle", "result": "result is an angle"}.get(row.angle, "")
        rows.append((row.name, params, angles))
    return rows
