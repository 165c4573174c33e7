"""Dual Dynamics models as data: the JSON model file format, its validation and compilation (§1.3–§1.5, §4.1).

This module owns the declarative description of a DD behavior system and its compiled form
(:class:`DDModel`): sensors, parameters, helpers, slow (higher-level) variables, actuators,
elementary and higher-level behaviors with their activation drives and target dynamics, switch
variables and the operator-coupling (OCT) table per operator schema. The running system lives in
:mod:`xabsl_studio.engine.dynamics.system`.

A model file (``examples/errands/model/errands_dd.json`` is the reference)::

    {
      "format": "xabsl-dd-model/1",
      "name": "errands",
      "dt": 0.02,                                    # the tick the stability check uses
      "parameters": {"lambda_m": 8.0, ...},          # named constants, usable in any expression
      "sensors": {"o_l": {"range": [0, 1], "doc": "..."}, ...},
      "helpers": {"o_max": "max(o_l, o_r)", ...},    # evaluated in order, once per tick
      "slow": {"f": {"init": 0, "rate": "... - f/6", "sigma": 0, "range": [0, 1]}, ...},
      "actuators": {"m_l": {"init": 0, "range": [-1, 1], "decay": "lambda_0", "rate": "lambda_m"}},
      "activation": {"lambda": 3, "k": 8, "theta": 0.5, "sigma": 0.05},   # defaults per behavior
      "behaviors": {
        "roam": {"level": 0, "init": 0, "drive": "1 - 1.2*max(α_gather_book, ...) + 1.5*f",
                 "let": {"fwd": "...", "turn": "..."},
                 "targets": {"m_l": "fwd + turn", "m_r": "fwd - turn"},
                 "rates": {"m_l": "lambda_m"}}                           # optional
      },
      "switches": {"lambda_s": 5},
      "oct": {"goto": {"params": ["from", "to"],
                       "couplings": [{"behavior": "approach_{to}", "z": 1, "c": 10},
                                     {"behavior": "approach_*", "z": 0, "c": 10}]}}
    }

Expressions use :mod:`xabsl_studio.engine.dynamics.expr`. Activations are read as ``α_<behavior>`` (ASCII
spelling ``alpha_<behavior>``). Numeric fields accept a number or a constant expression over
parameters; numbers must be finite doubles. Every error is a :class:`ModelError` naming the
file, the key path and, for expressions, the column; a file that is not UTF-8, not JSON, nested
more than :data:`MAX_JSON_DEPTH` deep, not a regular file or over :data:`MAX_MODEL_BYTES` is one
too, naming the line and column where it can.

Drives are compiled to the vectorised form of §4.1, T = S(k·(B@s + W@α − θ)): each drive is split
by :func:`xabsl_studio.engine.dynamics.expr.linear_terms` into a bias, linear activation terms (a row of W:
self-excitation on the diagonal, inhibition off it) and *features* (any other subterm, such as
``max(α_gather_book, ...)`` or ``ν_a``), which form the drive input vector s with weights B.

OCT couplings are matched per behavior, first match wins: ``approach_{to}`` with ``{param}``
bound to the ground operator's arguments, then glob patterns such as ``approach_*``. A behavior no
coupling matches is uncoupled (roam under GOTO in §1.5).

Stability (§1.3 and §4.1, checked at load and by :meth:`DDModel.check_stability`):

* activations: (λ_i + max_OP c_OP^i)·dt < 1 for every behavior. The doc writes Σc over the
  simultaneously active OCTs; that sum is at most max c because all s_OP relax with one rate
  λ_s toward targets σ_OP that sum to at most 1, so Σ s_OP ≤ 1 is invariant. This is the doc's
  "λ_max·dt = 13·0.02" reading (λ = 3 plus one c = 10).
* switch variables: λ_s·dt < 1.
* actuators: (decay + Σ_i rate_i)·dt < 2, the explicit-Euler stability bound with every
  targeting behavior fully active (no oscillating blow-up; values are clipped to their range).

Slow-variable rates are arbitrary expressions and are not analysed.
"""

from __future__ import annotations

import fnmatch
import json
import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from xabsl_studio.engine.dynamics import expr as ex
from xabsl_studio.engine.errors import DynamicsError
from xabsl_studio.engine.files import read_regular

FORMAT = "xabsl-dd-model/1"

_TOP_KEYS = {
    "format", "name", "doc", "dt", "parameters", "sensors", "helpers", "slow",
    "actuators", "activation", "behaviors", "switches", "oct",
}  # fmt: skip
_BEHAVIOR_KEYS = {"level", "init", "drive", "lambda", "k", "theta", "sigma", "let", "targets", "rates", "doc"}
_ACTIVATION_KEYS = {"lambda", "k", "theta", "sigma"}
_PLACEHOLDER = re.compile(r"\{(\w+)\}")
#: The largest model file read (the errands model is 10 kB).
MAX_MODEL_BYTES = 16 * 1024 * 1024
#: The deepest JSON nesting read (a model nests 5 levels; the json module recurses per level).
MAX_JSON_DEPTH = 64
#: Integers with more digits are read as floats (then refused when not finite): Python's int()
#: refuses over 4,300 digits with a ValueError that would not name the key.
_MAX_INT_DIGITS = 400


class ModelError(DynamicsError, ValueError):
    """A DD model file is invalid; the message names the file, the key and the problem."""


class ModelSyntaxError(ModelError):
    """A model text that is not UTF-8 or not JSON we read; ``pos`` is the offset in the text.

    ``reason`` is the problem alone (``"not valid JSON: Expecting value"``), ``line`` and ``col``
    are 1-based; the message adds the source and the place.
    """

    def __init__(self, source: str, reason: str, pos: int, line: int, col: int) -> None:
        super().__init__(f"{source}: {reason} at line {line} column {col}")
        self.reason, self.pos, self.line, self.col = reason, pos, line, col


#: Evaluates features, targets and slow rates from (sensors, slow variables, activations).
Evaluator = Callable[[Sequence[float], Sequence[float], Sequence[float]], tuple[list[float], list[float], list[float]]]


@dataclass(frozen=True, slots=True)
class Coupling:
    """One row of an OCT schema: a behavior pattern, the value Z it is pulled to, its gain c."""

    pattern: str
    z: float
    c: float


@dataclass(frozen=True, slots=True)
class OctSchema:
    """The OCT table entry of one operator schema (``goto``, ``load``, ``unload``)."""

    params: tuple[str, ...]
    couplings: tuple[Coupling, ...]


@dataclass(eq=False)
class DDModel:
    """A validated, compiled DD model: names, parameter arrays and the compiled evaluator.

    Array attributes are indexed by behavior (n), feature (nf), actuator (na), slow variable
    (nv) or target pair (np: one per behavior/actuator target).
    """

    name: str
    dt: float
    parameters: Mapping[str, float]
    sensors: tuple[str, ...]
    sensor_ranges: Mapping[str, tuple[float, float]]
    slow: tuple[str, ...]
    slow_init: np.ndarray
    slow_sigma: np.ndarray
    slow_lo: np.ndarray
    slow_hi: np.ndarray
    actuators: tuple[str, ...]
    act_init: np.ndarray
    act_lo: np.ndarray
    act_hi: np.ndarray
    act_decay: np.ndarray
    behaviors: tuple[str, ...]
    levels: np.ndarray
    alpha_init: np.ndarray
    lam: np.ndarray
    k: np.ndarray
    theta: np.ndarray
    sigma: np.ndarray
    features: tuple[str, ...]
    B: np.ndarray
    W: np.ndarray
    bias: np.ndarray
    pair_behavior: np.ndarray
    pair_actuator: np.ndarray
    pair_rate: np.ndarray
    lambda_s: float
    oct: Mapping[str, OctSchema]
    evaluate: Evaluator
    source: str
    _coupling_cache: dict[str, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict, repr=False)

    @property
    def n(self) -> int:
        """Number of behaviors."""
        return len(self.behaviors)

    def behavior_index(self, name: str) -> int:
        """Return the index of behavior ``name``; ``KeyError`` names it when absent."""
        try:
            return self.behaviors.index(name)
        except ValueError:
            raise KeyError(f"model {self.name!r} has no behavior {name!r}") from None

    def max_coupling(self) -> np.ndarray:
        """Largest OCT gain any operator can apply to each behavior (0 if never coupled)."""
        out = np.zeros(self.n)
        for schema in self.oct.values():
            for cp in schema.couplings:
                for i, b in enumerate(self.behaviors):
                    if _could_match(cp.pattern, b):
                        out[i] = max(out[i], cp.c)
        return out

    def couplings(self, operator: str) -> tuple[np.ndarray, np.ndarray]:
        """(c, Z) vectors over behaviors for a ground operator such as ``"goto a c"``.

        Raises:
            ModelError: unknown schema, wrong arity, or a bound pattern naming no behavior.
        """
        hit = self._coupling_cache.get(operator)
        if hit is not None:
            return hit
        schema_name, *args = operator.split()
        schema = self.oct.get(schema_name.lower())
        if schema is None:
            raise ModelError(f"model {self.name!r}: no OCT table for operator schema {schema_name!r}")
        if len(args) != len(schema.params):
            raise ModelError(
                f"model {self.name!r}: operator {operator!r} has {len(args)} arguments, "
                f"OCT schema {schema_name!r} expects {len(schema.params)} ({', '.join(schema.params)})"
            )
        env = dict(zip(schema.params, args, strict=True))
        c = np.zeros(self.n)
        z = np.zeros(self.n)
        matched = np.zeros(self.n, dtype=bool)
        for cp in schema.couplings:
            pattern = _PLACEHOLDER.sub(lambda m: env[m.group(1)], cp.pattern)
            hits = [i for i, b in enumerate(self.behaviors) if fnmatch.fnmatchcase(b, pattern)]
            if not hits and "*" not in pattern and "?" not in pattern:
                raise ModelError(
                    f"model {self.name!r}: OCT {schema_name} coupling {cp.pattern!r} -> {pattern!r} "
                    f"names no behavior (operator {operator!r})"
                )
            for i in hits:
                if not matched[i]:
                    matched[i] = True
                    c[i], z[i] = cp.c, cp.z
        self._coupling_cache[operator] = (c, z)
        return c, z

    def check_stability(self, dt: float) -> None:
        """Raise :class:`ModelError` if explicit Euler at ``dt`` violates the bounds above."""
        problems = []
        cmax = self.max_coupling()
        for i, b in enumerate(self.behaviors):
            g = (self.lam[i] + cmax[i]) * dt
            if not g < 1.0:
                problems.append(
                    f"behavior {b!r}: (λ + max c)·dt = ({self.lam[i]:g} + {cmax[i]:g})·{dt:g} = {g:.3g} ≥ 1"
                )
        if not self.lambda_s * dt < 1.0:
            problems.append(f"switches: λ_s·dt = {self.lambda_s:g}·{dt:g} = {self.lambda_s * dt:.3g} ≥ 1")
        for m, name in enumerate(self.actuators):
            total = self.act_decay[m] + self.pair_rate[self.pair_actuator == m].sum()
            if not total * dt < 2.0:
                problems.append(f"actuator {name!r}: (decay + Σ rates)·dt = {total:g}·{dt:g} = {total * dt:.3g} ≥ 2")
        if problems:
            raise ModelError(f"model {self.name!r} is unstable at dt={dt:g}: " + "; ".join(problems))


def _could_match(pattern: str, behavior: str) -> bool:
    return fnmatch.fnmatchcase(behavior, _PLACEHOLDER.sub("*", pattern))


# --- loading -------------------------------------------------------------------------------------


def load_model(path: str | Path, dt: float | None = None) -> DDModel:
    """Read, validate and compile a JSON model file.

    Args:
        path: the ``.json`` file.
        dt: the tick to check stability for; defaults to the file's ``dt``.

    Raises:
        ModelError: naming the file and the offending key or expression.
    """
    p = Path(path)
    try:
        raw = read_regular(p, MAX_MODEL_BYTES)
    except OSError as e:
        raise ModelError(f"{p}: cannot read: {e.strerror or e}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        line, col = _line_col(raw, e.start)
        raise ModelSyntaxError(str(p), f"not UTF-8 text (byte 0x{raw[e.start]:02x})", e.start, line, col) from None
    data = parse_model_json(text, str(p))
    return build_model(data, source=str(p), dt=dt)


def parse_model_json(text: str, source: str = "<model>") -> Any:
    """Parse a model file's text as JSON, within the limits every model reader keeps.

    Nesting deeper than :data:`MAX_JSON_DEPTH` is refused before parsing (the json module would
    recurse into a RecursionError), and integers of more than a few hundred digits are read as
    floats (Python's int() refuses 4,300 digits; the builder then names the key of a non-finite one).

    Raises:
        ModelSyntaxError: not JSON, or nested too deeply; with the offset, line and column.
    """
    deep = _too_deep(text, MAX_JSON_DEPTH)
    if deep is not None:
        line, col = _line_col(text, deep)
        raise ModelSyntaxError(source, f"JSON nested too deeply (over {MAX_JSON_DEPTH} levels)", deep, line, col)
    try:
        return json.loads(text, parse_int=_parse_int)
    except json.JSONDecodeError as e:
        raise ModelSyntaxError(source, f"not valid JSON: {e.msg}", e.pos, e.lineno, e.colno) from None
    except RecursionError:  # _too_deep bounds the nesting; kept so no input can leak one
        raise ModelSyntaxError(source, "JSON nested too deeply", 0, 1, 1) from None


def _parse_int(digits: str) -> int | float:
    return int(digits) if len(digits) <= _MAX_INT_DIGITS else float(digits)


def _line_col(data: bytes | str, offset: int) -> tuple[int, int]:
    """1-based line and column of ``offset`` in ``data``."""
    newline = b"\n" if isinstance(data, bytes) else "\n"
    line = data.count(newline, 0, offset) + 1  # type: ignore[arg-type]
    start = data.rfind(newline, 0, offset) + 1  # type: ignore[arg-type]
    return line, offset - start + 1


def _too_deep(text: str, limit: int) -> int | None:
    """The offset where JSON ``text`` nests deeper than ``limit``, or None (strings skipped)."""
    if text.count("[") + text.count("{") <= limit:
        return None
    depth = 0
    in_string = escaped = False
    for i, ch in enumerate(text):
        if in_string:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == '"':
                in_string = False
        elif ch == '"':
            in_string = True
        elif ch in "[{":
            depth += 1
            if depth > limit:
                return i
        elif ch in "]}":
            depth -= 1
    return None


_show = ex.short_repr


def _elide(text: str, limit: int) -> str:
    """``text``, or its start and end around "..." when longer than ``limit`` characters."""
    if len(text) <= limit:
        return text
    half = (limit - 3) // 2
    return f"{text[:half]}...{text[-half:]}"


def build_model(data: Mapping[str, object], source: str = "<model>", dt: float | None = None) -> DDModel:
    """Validate and compile model data (the parsed JSON); see the module docstring for the format."""
    return _Builder(data, source).build(dt)


class _Builder:
    def __init__(self, data: Mapping[str, object], source: str) -> None:
        self.data = data
        self.source = source

    def err(self, key: str, msg: str) -> ModelError:
        # Keys and names come from the file and may be megabytes long: keep each line readable.
        lines = [_elide(line, 300) for line in msg.split("\n")]
        return ModelError(f"{self.source}: {_elide(key, 200)}: " + "\n".join(lines))

    def table(self, key: str, value: object, allowed: set[str] | None = None) -> dict[str, object]:
        if not isinstance(value, dict):
            raise self.err(key, f"expected an object, got {type(value).__name__}")
        if allowed is not None:
            unknown = sorted(set(value) - allowed)
            if unknown:
                raise self.err(key, f"unknown key(s) {', '.join(map(repr, unknown))}")
        return value

    def parse_expr(self, key: str, text: object, known: Callable[[str], bool]) -> ex.Node:
        try:
            node = ex.parse(text)  # type: ignore[arg-type]
            ex.check_names(node, str(text), lambda n: n in self.params or known(n))
        except ex.ExprError as e:
            raise self.err(key, str(e)) from None
        folded = ex.fold(ex.substitute(node, self.param_nodes))
        for const in ex.constants(folded):
            if not math.isfinite(const.value):
                where = ex.ExprError(f"a constant part is {const.value!r} (not finite)", str(text), const.col)
                raise self.err(key, str(where))
        return folded

    def number(self, key: str, value: object) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float | str):
            raise self.err(key, f"expected a number or a parameter expression, got {_show(value)}")
        if isinstance(value, int | float):
            try:
                v = float(value)
            except OverflowError:
                raise self.err(key, f"{_show(value)} is out of the double range") from None
        else:
            node = self.parse_expr(key, value, lambda n: n in self.params)
            if not isinstance(node, ex.Num):
                raise self.err(key, f"{_show(value)} is not constant")
            v = node.value
        if not math.isfinite(v):
            raise self.err(key, f"{_show(value)} is not finite")
        return v

    def range_of(self, key: str, value: object) -> tuple[float, float]:
        if value is None:
            return (-math.inf, math.inf)
        if not (isinstance(value, list) and len(value) == 2):
            raise self.err(key, f"expected [lo, hi], got {_show(value)}")
        lo, hi = (self.number(f"{key}[{i}]", v) for i, v in enumerate(value))
        if not lo <= hi:
            raise self.err(key, f"empty range [{lo:g}, {hi:g}]")
        return lo, hi

    def build(self, dt_override: float | None) -> DDModel:
        d = self.table("<top>", self.data, _TOP_KEYS)
        if d.get("format") != FORMAT:
            raise self.err("format", f"expected {FORMAT!r}, got {_show(d.get('format'))}")
        name = str(d.get("name", "dd"))
        self.params: dict[str, float] = {}
        self.param_nodes: dict[str, ex.Node] = {}
        for pname, pval in self.table("parameters", d.get("parameters", {})).items():
            self.params[pname] = self.number(f"parameters.{pname}", pval)
            self.param_nodes[pname] = ex.Num(self.params[pname])
        dt = self.number("dt", d.get("dt", 0.02)) if dt_override is None else float(dt_override)
        if not dt > 0:
            raise self.err("dt", f"must be > 0, got {dt:g}")

        declared: dict[str, str] = {p: "parameter" for p in self.params}

        def declare(n: str, kind: str, key: str) -> None:
            if not n.isidentifier():
                raise self.err(key, f"{kind} name {n!r} is not an identifier")
            if n in declared:
                raise self.err(key, f"{kind} {n!r} clashes with the {declared[n]} of that name")
            declared[n] = kind

        raw_sensors = d.get("sensors", {})
        if isinstance(raw_sensors, list):
            raw_sensors = {s: {} for s in raw_sensors}
        sensors = self.table("sensors", raw_sensors)
        sensor_ranges = {}
        for s, spec in sensors.items():
            declare(s, "sensor", f"sensors.{s}")
            spec = self.table(f"sensors.{s}", spec, {"range", "unit", "doc"})
            sensor_ranges[s] = self.range_of(f"sensors.{s}.range", spec.get("range"))

        behaviors = self.table("behaviors", d.get("behaviors"))
        if not behaviors:
            raise self.err("behaviors", "a model needs at least one behavior")
        bnames = list(behaviors)
        alpha_alias = {}
        for b in bnames:
            if not b.isidentifier():
                raise self.err(f"behaviors.{b}", f"behavior name {b!r} is not an identifier")
            for spelled in (f"α_{b}", f"alpha_{b}"):
                declare(spelled, "activation", f"behaviors.{b}")
                alpha_alias[spelled] = b

        slow = self.table("slow", d.get("slow", {}))
        for v in slow:
            declare(v, "slow variable", f"slow.{v}")
        actuators = self.table("actuators", d.get("actuators", {}))
        for m in actuators:
            declare(m, "actuator", f"actuators.{m}")

        # Local Python names for generated code; user names never become Python identifiers.
        local: dict[str, str] = {}
        for i, s in enumerate(sensors):
            local[s] = f"_s{i}"
        for i, v in enumerate(slow):
            local[v] = f"_v{i}"
        for spelled, b in alpha_alias.items():
            local[spelled] = f"_a{bnames.index(b)}"
        state_names = set(sensors) | set(slow) | set(alpha_alias)
        scope: set[str] = set(state_names)

        lines = ["def _evaluate(S, V, A):"]
        lines += [f"    _s{i} = S[{i}]" for i in range(len(sensors))]
        lines += [f"    _v{i} = V[{i}]" for i in range(len(slow))]
        lines += [f"    _a{i} = A[{i}]" for i in range(len(bnames))]

        helpers = self.table("helpers", d.get("helpers", {}))
        for i, (h, text) in enumerate(helpers.items()):
            key = f"helpers.{h}"
            declare(h, "helper", key)
            node = self.parse_expr(key, text, scope.__contains__)
            local[h] = f"_h{i}"
            lines.append(f"    _h{i} = {ex.to_python(node, local)}")
            scope.add(h)

        # Slow variables (levels >= 1 without behavior structure, e.g. novelty, frustration).
        slow_init, slow_sigma, slow_lo, slow_hi, rate_src = [], [], [], [], []
        for v, spec in slow.items():
            key = f"slow.{v}"
            spec = self.table(key, spec, {"init", "rate", "sigma", "range", "doc"})
            if "rate" not in spec:
                raise self.err(key, "missing 'rate'")
            node = self.parse_expr(f"{key}.rate", spec["rate"], scope.__contains__)
            rate_src.append(ex.to_python(node, local))
            lo, hi = self.range_of(f"{key}.range", spec.get("range"))
            init = self.number(f"{key}.init", spec.get("init", 0.0))
            slow_init.append(min(max(init, lo), hi))
            slow_sigma.append(self.number(f"{key}.sigma", spec.get("sigma", 0.0)))
            slow_lo.append(lo)
            slow_hi.append(hi)

        act_init, act_lo, act_hi, act_decay, act_rate = [], [], [], [], []
        for m, spec in actuators.items():
            key = f"actuators.{m}"
            spec = self.table(key, spec, {"init", "range", "decay", "rate", "doc"})
            lo, hi = self.range_of(f"{key}.range", spec.get("range"))
            act_init.append(min(max(self.number(f"{key}.init", spec.get("init", 0.0)), lo), hi))
            act_lo.append(lo)
            act_hi.append(hi)
            act_decay.append(self.number(f"{key}.decay", spec.get("decay", 0.0)))
            act_rate.append(self.number(f"{key}.rate", spec.get("rate", 1.0)))
        mnames = list(actuators)

        defaults = self.table("activation", d.get("activation", {}), _ACTIVATION_KEYS)
        dflt = {
            "lambda": self.number("activation.lambda", defaults.get("lambda", 3.0)),
            "k": self.number("activation.k", defaults.get("k", 8.0)),
            "theta": self.number("activation.theta", defaults.get("theta", 0.5)),
            "sigma": self.number("activation.sigma", defaults.get("sigma", 0.0)),
        }

        n = len(bnames)
        levels, ainit, lam, kk, theta, sigma = [], [], [], [], [], []
        drives: list[dict[ex.LinearKey, tuple[float, ex.Node | None]]] = []
        pairs: list[tuple[int, int, float]] = []
        target_src: list[str] = []
        let_counter = 0
        for i, b in enumerate(bnames):
            key = f"behaviors.{b}"
            spec = self.table(key, behaviors[b], _BEHAVIOR_KEYS)
            level = int(self.number(f"{key}.level", spec.get("level", 0)))
            levels.append(level)
            ainit.append(self.number(f"{key}.init", spec.get("init", 0.0)))
            if not 0.0 <= ainit[-1] <= 1.0:
                raise self.err(f"{key}.init", f"activation must be in [0, 1], got {ainit[-1]:g}")
            lam.append(self.number(f"{key}.lambda", spec.get("lambda", dflt["lambda"])))
            kk.append(self.number(f"{key}.k", spec.get("k", dflt["k"])))
            theta.append(self.number(f"{key}.theta", spec.get("theta", dflt["theta"])))
            sigma.append(self.number(f"{key}.sigma", spec.get("sigma", dflt["sigma"])))
            if lam[-1] <= 0 or sigma[-1] < 0:
                raise self.err(key, "lambda must be > 0 and sigma >= 0")
            if "drive" not in spec:
                raise self.err(key, "missing 'drive' (the u_i before the sigmoid)")
            drive = self.parse_expr(f"{key}.drive", spec["drive"], scope.__contains__)
            drives.append(ex.linear_terms(drive, alpha_alias.__contains__))

            targets = self.table(f"{key}.targets", spec.get("targets", {}))
            if targets and level > 0:
                raise self.err(f"{key}.targets", "only elementary behaviors (level 0) have target dynamics (§1.2)")
            let_scope = set(scope)
            lets = self.table(f"{key}.let", spec.get("let", {}))
            for lname, text in lets.items():
                if lname in declared or not lname.isidentifier():
                    raise self.err(f"{key}.let.{lname}", f"let name {lname!r} clashes or is not an identifier")
                node = self.parse_expr(f"{key}.let.{lname}", text, let_scope.__contains__)
                local[lname] = f"_l{let_counter}"
                let_counter += 1
                lines.append(f"    {local[lname]} = {ex.to_python(node, local)}")
                let_scope.add(lname)
            rates = self.table(f"{key}.rates", spec.get("rates", {}))
            for m in rates:
                if m not in targets:
                    raise self.err(f"{key}.rates.{m}", f"rate given for {m!r}, which has no target here")
            for m, text in targets.items():
                if m not in actuators:
                    raise self.err(f"{key}.targets.{m}", f"unknown actuator {m!r}")
                node = self.parse_expr(f"{key}.targets.{m}", text, let_scope.__contains__)
                target_src.append(ex.to_python(node, local))
                rate = self.number(f"{key}.rates.{m}", rates.get(m, act_rate[mnames.index(m)]))
                if rate <= 0:
                    raise self.err(f"{key}.rates.{m}", "must be > 0")
                pairs.append((i, mnames.index(m), rate))
            for lname in lets:
                del local[lname]

        # Features: every non-linear drive subterm, shared between behaviors by canonical text.
        feature_nodes: dict[str, ex.Node] = {}
        for row in drives:
            for key_, (_, term) in row.items():
                if key_ is not None and key_[0] == "feature" and key_[1] not in feature_nodes:
                    assert term is not None
                    feature_nodes[key_[1]] = term
        fnames = list(feature_nodes)
        Bm = np.zeros((n, len(fnames)))
        Wm = np.zeros((n, n))
        bias = np.zeros(n)
        for i, row in enumerate(drives):
            for key_, (coef, _) in row.items():
                if key_ is None:
                    bias[i] += coef
                elif key_[0] == "name":
                    Wm[i, bnames.index(alpha_alias[key_[1]])] += coef
                else:
                    Bm[i, fnames.index(key_[1])] += coef
        lines.append(f"    F = [{', '.join(ex.to_python(feature_nodes[f], local) for f in fnames)}]")
        lines.append(f"    T = [{', '.join(target_src)}]")
        lines.append(f"    R = [{', '.join(rate_src)}]")
        lines.append("    return F, T, R")
        source = "\n".join(lines) + "\n"
        namespace: dict[str, object] = dict(ex.RUNTIME)
        exec(compile(source, f"<dd-model:{name}>", "exec"), namespace)  # our own emitted source only

        sw = self.table("switches", d.get("switches", {}), {"lambda_s"})
        lambda_s = self.number("switches.lambda_s", sw.get("lambda_s", 5.0))
        oct_table = self.oct_schemas(self.table("oct", d.get("oct", {})), bnames)

        model = DDModel(
            name=name,
            dt=dt,
            parameters=dict(self.params),
            sensors=tuple(sensors),
            sensor_ranges=sensor_ranges,
            slow=tuple(slow),
            slow_init=np.array(slow_init, dtype=float),
            slow_sigma=np.array(slow_sigma, dtype=float),
            slow_lo=np.array(slow_lo, dtype=float),
            slow_hi=np.array(slow_hi, dtype=float),
            actuators=tuple(mnames),
            act_init=np.array(act_init, dtype=float),
            act_lo=np.array(act_lo, dtype=float),
            act_hi=np.array(act_hi, dtype=float),
            act_decay=np.array(act_decay, dtype=float),
            behaviors=tuple(bnames),
            levels=np.array(levels, dtype=int),
            alpha_init=np.array(ainit, dtype=float),
            lam=np.array(lam),
            k=np.array(kk),
            theta=np.array(theta),
            sigma=np.array(sigma),
            features=tuple(fnames),
            B=Bm,
            W=Wm,
            bias=bias,
            pair_behavior=np.array([p[0] for p in pairs], dtype=int),
            pair_actuator=np.array([p[1] for p in pairs], dtype=int),
            pair_rate=np.array([p[2] for p in pairs], dtype=float),
            lambda_s=lambda_s,
            oct=oct_table,
            evaluate=namespace["_evaluate"],  # type: ignore[arg-type]
            source=source,
        )
        try:
            model.check_stability(dt)
        except ModelError as e:
            raise self.err("stability", str(e)) from None
        return model

    def oct_schemas(self, table: Mapping[str, object], bnames: list[str]) -> dict[str, OctSchema]:
        out = {}
        for schema, spec in table.items():
            key = f"oct.{schema}"
            spec = self.table(key, spec, {"params", "couplings", "doc"})
            params = spec.get("params", [])
            if not (isinstance(params, list) and all(isinstance(p, str) for p in params)):
                raise self.err(f"{key}.params", "expected a list of parameter names")
            couplings = spec.get("couplings", [])
            if not isinstance(couplings, list):
                raise self.err(f"{key}.couplings", "expected a list")
            rows = []
            for j, row in enumerate(couplings):
                rk = f"{key}.couplings[{j}]"
                row = self.table(rk, row, {"behavior", "z", "c"})
                pattern = row.get("behavior")
                if not isinstance(pattern, str):
                    raise self.err(f"{rk}.behavior", "expected a behavior name or pattern")
                for ph in _PLACEHOLDER.findall(pattern):
                    if ph not in params:
                        raise self.err(f"{rk}.behavior", f"placeholder {{{ph}}} is not a parameter of {schema!r}")
                if not any(_could_match(pattern, b) for b in bnames):
                    raise self.err(f"{rk}.behavior", f"pattern {pattern!r} matches no behavior")
                z = self.number(f"{rk}.z", row.get("z"))
                c = self.number(f"{rk}.c", row.get("c"))
                if not 0.0 <= z <= 1.0:
                    raise self.err(f"{rk}.z", f"Z must be in [0, 1], got {z:g}")
                if c < 0:
                    raise self.err(f"{rk}.c", f"c must be >= 0, got {c:g}")
                rows.append(Coupling(pattern, z, c))
            out[schema.lower()] = OctSchema(tuple(params), tuple(rows))
        return out
