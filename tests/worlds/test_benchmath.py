"""The bench's computed input functions against Python's math, on the edge cases, and their matching rules."""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest

from xabsl_studio.engine.ir.model import InputSymbol, Parameter
from xabsl_studio.engine.types import Kind
from xabsl_studio.engine.worlds.benchmath import Computed, match

NAN, INF = math.nan, math.inf
EDGES = (0.0, -0.0, 1.0, -1.0, 0.5, -2.5, 1e-300, 1e300, -1e300, INF, -INF, NAN)


def symbol(
    name: str, *params: str, unit: str | None = None, units: str | None = None, kind: Kind = Kind.DECIMAL
) -> InputSymbol:
    declared = tuple(Parameter(f"{name}.{p}", kind, unit=units, owner=name) for p in params)
    return InputSymbol(name, Kind.DECIMAL, params=declared, unit=unit)


def computed(name: str, *params: str, unit: str | None = None, units: str | None = None) -> Computed:
    found = match(symbol(name, *params, unit=unit, units=units))
    assert found is not None, f"{name}({', '.join(params)}) is not computed"
    return found


def same(got: float, want: float) -> bool:
    """Equal, both NaN, or the same signed zero."""
    if math.isnan(want):
        return math.isnan(got)
    return got == want and math.copysign(1.0, got) == math.copysign(1.0, want)


def expected(function: Callable[..., float], *args: float) -> float:
    """Python's math, with NaN where it raises (the bench's rule)."""
    try:
        return function(*args)
    except (ValueError, OverflowError):
        return NAN


@pytest.mark.parametrize(
    ("name", "reference"),
    [("abs", math.fabs), ("sqrt", math.sqrt), ("asin", math.asin), ("acos", math.acos), ("atan", math.atan)],
)
def test_functions_of_one_value_agree_with_math_in_radians(name: str, reference: Callable[[float], float]) -> None:
    function = computed(name, "value", unit="rad").function
    for x in EDGES:
        assert same(function(x), expected(reference, x)), f"{name}({x})"
    assert math.isnan(computed("sqrt", "value").function(-1.0)), "math raises; the bench says NaN"


@pytest.mark.parametrize(("name", "reference"), [("sin", math.sin), ("cos", math.cos), ("tan", math.tan)])
def test_trigonometry_takes_the_declared_unit(name: str, reference: Callable[[float], float]) -> None:
    radians = computed(name, "angle", units="rad").function
    degrees = computed(name, "angle", units="deg").function
    undeclared = computed(name, "angle").function
    for x in EDGES:
        assert same(radians(x), expected(reference, x)), f"{name}({x} rad)"
        assert same(degrees(x), expected(lambda v: reference(math.radians(v)), x)), f"{name}({x} deg)"
        assert same(undeclared(x), degrees(x)), "no unit: degrees, the XABSL sets' convention"
    assert abs(degrees(90.0) - reference(math.pi / 2)) < 1e-12


def test_atan2_and_vector_angle_wrap_at_plus_minus_pi() -> None:
    atan2_rad = computed("atan2", "y", "x", unit="rad").function
    atan2_deg = computed("atan2", "y", "x", unit="deg").function
    angle = computed("vector.angle", "x", "y", unit="rad").function
    for y in EDGES:
        for x in EDGES:
            assert same(atan2_rad(y, x), math.atan2(y, x)), f"atan2({y}, {x})"
            assert same(atan2_deg(y, x), math.degrees(math.atan2(y, x)))
            assert same(angle(x, y), math.atan2(y, x)), "vector.angle(x, y) is atan2(y, x)"
    assert atan2_rad(0.0, -1.0) == math.pi and atan2_rad(-0.0, -1.0) == -math.pi
    assert atan2_deg(0.0, -1.0) == 180.0


def test_normalize_is_in_the_half_open_interval_and_wraps_at_plus_minus_pi() -> None:
    degrees = computed("normalize", "angle", units="deg").function
    radians = computed("normalize", "angle", units="rad").function
    assert degrees(180.0) == 180.0 and degrees(-180.0) == 180.0, "(-180, 180]: -180 is 180"
    assert degrees(540.0) == 180.0 and degrees(-540.0) == 180.0
    assert degrees(181.0) == -179.0 and degrees(-181.0) == 179.0 and degrees(360.0) == 0.0
    assert radians(math.pi) == math.pi and radians(-math.pi) == math.pi
    assert abs(radians(3 * math.pi / 2) - (-math.pi / 2)) < 1e-12
    for x in (INF, -INF, NAN):
        assert math.isnan(degrees(x)) and math.isnan(radians(x)), f"normalize({x})"
    for x in (-1e6, -720.5, -359.0, -0.25, 0.0, 33.0, 719.0, 1e6):
        got = degrees(x)
        assert -180.0 < got <= 180.0 and abs(math.remainder(got - x, 360.0)) < 1e-9, x
        assert abs(math.sin(math.radians(got)) - math.sin(math.radians(x))) < 1e-9


def test_min_max_clip_propagate_nan_whatever_the_order() -> None:
    lo, hi = computed("min", "value0", "value1").function, computed("max", "a", "b").function
    clip = computed("clip", "value", "min", "max").function
    clamp = computed("clamp", "value", "lo", "hi").function
    for a in EDGES:
        for b in EDGES:
            if math.isnan(a) or math.isnan(b):
                assert math.isnan(lo(a, b)) and math.isnan(hi(a, b)), (a, b)
            else:
                assert lo(a, b) == min(a, b) and hi(a, b) == max(a, b)
    assert clip(5.0, 0.0, 3.0) == 3.0 and clip(-INF, 0.0, 3.0) == 0.0 and clip(1.5, 0.0, 3.0) == 1.5
    assert math.isnan(clip(NAN, 0.0, 1.0)) and math.isnan(clamp(1.0, NAN, 2.0))
    assert clamp(600.0, 50.0, 250.0) == 250.0


def test_lengths_and_distance_agree_with_hypot() -> None:
    length = computed("vector.abs", "x", "y").function
    distance = computed("distance", "x1", "y1", "x2", "y2").function
    for x in EDGES:
        for y in EDGES:
            assert same(length(x, y), math.hypot(x, y)), (x, y)
    assert length(INF, NAN) == INF, "hypot: an infinity wins over NaN"
    assert distance(1.0, 2.0, 4.0, 6.0) == 5.0 and distance(0.0, 0.0, -3.0, -4.0) == 5.0


def test_matching_is_by_name_parameters_and_types() -> None:
    assert computed("math.abs", "value").description == "abs(value)", "a namespace prefix"
    assert computed("sin", "angle", units="deg").description == "sin(angle °)"
    assert computed("atan2", "y", "x", unit="rad").description == "atan2(y, x) rad"
    assert match(symbol("atan2", "x", "y")) is None, "atan2 needs (y, x): never a guess at the order"
    assert match(symbol("abs", "value", kind=Kind.BOOLEAN)) is None, "decimal parameters only"
    assert match(symbol("abs", "value", "other")) is None, "the parameter count"
    assert match(symbol("clip", "lo", "value", "hi")) is None, "the value comes first"
    assert match(symbol("player.abs", "x", "y")) is None, "player.abs(x, y) is not vector.abs"
    assert match(symbol("speed")) is None, "a plain input is never computed"
    boolean = InputSymbol("abs", Kind.BOOLEAN, params=symbol("abs", "value").params)
    assert match(boolean) is None, "a decimal result"
