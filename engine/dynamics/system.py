"""The running Dual Dynamics behavior system: one synchronous Euler(-Maruyama) tick (doc §1.3–§1.5, §4.1).

This module owns the state of a DD system built from a :class:`~xabsl_studio.engine.dynamics.model.DDModel`
(activations α, slow variables, actuators, switch variables s_OP), the tick that advances it, and
the per-tick record the debugger shows (§4.3 items 1, 2 and 5). Tick order follows §4.1 steps 4–6:

1. switches: ``s_OP += dt·λ_s·(σ_OP − s_OP)`` where σ_OP = 1 for the monitor's current operator;
2. every increment below is computed from one snapshot (PDL semantics, §1.4), then committed;
3. activation (form A of §1.3)::

       Δα = dt·[λ(T − α) + Σ_OP s_OP·c_OP·(Z_OP − α)] + σ·√dt·ξ,   T = S(k·(B@s + W@α − θ))

4. actuators: ``Δm = dt·[−decay·m + Σ_i α_i·λ_im·(m*_i − m)]`` (superposition, no arbiter);
5. slow variables: ``Δv = dt·rate(v, sensors, α) + σ_v·√dt·ξ``;
6. commit: α clipped to [0, 1], actuators and slow variables clipped to their ranges.

Every rate is in 1/s and multiplied by dt, so the same model runs at any tick (§1.4: PDL gains
were per cycle, which made dynamics depend on the cycle rate). Noise comes from one seeded
``numpy.random.Generator`` per system; a full noise vector is drawn every tick even where σ=0, so
changing one σ does not reshuffle the other behaviors' noise streams.

:meth:`DDSystem.flow` exposes the same right-hand side without noise and clipping for offline
integrators (``scipy.integrate.solve_ivp``) on frozen inputs, as §4.1 recommends for accuracy
checks and phase portraits.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any, NamedTuple

import numpy as np

from xabsl_studio.engine.dynamics.model import DDModel, ModelError


class TickLists(NamedTuple):
    """A tick's numbers as the Python lists the kernel made (shared with the record: read, never change)."""

    features: list[float]
    u: list[float]
    T: list[float]
    alpha: list[float]
    d_relax: list[float]
    d_noise: list[float]
    pair_targets: list[float]
    pair_contributions: list[float]
    decay: list[float]
    actuators: list[float]
    slow: list[float]
    d_oct: Mapping[str, list[float]]


class TickRecord:
    """Everything one tick computed, for the debugger (§4.3 items 1, 2 and 5).

    The tick keeps its numbers as Python lists and hands out a fresh numpy array on every
    attribute access, so a record is never changed by later ticks and the headless loop pays for
    arrays only when somebody looks (the errands speed target, §4.4).

    Attributes:
        t: simulation time after the tick (s).
        dt: the tick length used (s).
        features: the drive input vector s (model.features order).
        u: drives B@s + W@α + bias; ``T`` their sigmoid targets.
        alpha: activations after commit.
        d_relax: dt·λ(T − α) per behavior.
        d_oct: per operator with s > 0, dt·s·c·(Z − α) per behavior.
        d_noise: σ·√dt·ξ per behavior.
        switches: s_OP after this tick's switch update (the values the OCTs used).
        pair_targets: m*_i per (behavior, actuator) target pair of the model.
        pair_contributions: α_i·λ_im·(m*_i − m) per target pair (1/s).
        targets: behavior × actuator matrix of m*_i (NaN where a behavior has no target).
        contributions: behavior × actuator matrix of α_i·λ_im·(m*_i − m) (1/s).
        decay: per actuator, −decay·m (1/s).
        actuators: actuator values after commit.
        slow: slow variables after commit.
        model: the model, for names and the pair layout.
    """

    __slots__ = ("_T", "_act", "_alpha", "_contrib", "_d_noise", "_d_oct", "_d_relax", "_decay", "_features",
                 "_slow", "_tgt", "_u", "dt", "model", "switches", "t")  # fmt: skip

    def __init__(
        self,
        t: float,
        dt: float,
        model: DDModel,
        lists: tuple[list[float], ...],
        d_oct: Mapping[str, list[float]],
        switches: Mapping[str, float],
    ) -> None:
        self.t = t
        self.dt = dt
        self.model = model
        self.switches = switches
        self._d_oct = d_oct
        (self._features, self._u, self._T, self._alpha, self._d_relax, self._d_noise, self._tgt, self._contrib,
         self._decay, self._act, self._slow) = lists  # fmt: skip

    features = property(lambda self: np.array(self._features))
    u = property(lambda self: np.array(self._u))
    T = property(lambda self: np.array(self._T))
    alpha = property(lambda self: np.array(self._alpha))
    d_relax = property(lambda self: np.array(self._d_relax))
    d_noise = property(lambda self: np.array(self._d_noise))
    pair_targets = property(lambda self: np.array(self._tgt))
    pair_contributions = property(lambda self: np.array(self._contrib))
    decay = property(lambda self: np.array(self._decay))
    actuators = property(lambda self: np.array(self._act))
    slow = property(lambda self: np.array(self._slow))

    @property
    def d_oct(self) -> dict[str, np.ndarray]:
        """Per operator with s > 0, its OCT pull dt·s·c·(Z − α) on each behavior."""
        return {op: np.array(v) for op, v in self._d_oct.items()}

    @property
    def targets(self) -> np.ndarray:
        """Target values as a behavior x actuator matrix (NaN where a behavior has no target)."""
        m = self.model
        tmat = np.full((m.n, len(m.actuators)), np.nan)
        tmat[m.pair_behavior, m.pair_actuator] = self._tgt
        return tmat

    @property
    def contributions(self) -> np.ndarray:
        """Each behavior's contribution to each actuator's change (behavior x actuator)."""
        m = self.model
        cmat = np.zeros((m.n, len(m.actuators)))
        cmat[m.pair_behavior, m.pair_actuator] = self._contrib
        return cmat

    def lists(self) -> TickLists:
        """The tick's numbers without copies into arrays (for per-tick views such as the studio's)."""
        return TickLists(self._features, self._u, self._T, self._alpha, self._d_relax, self._d_noise, self._tgt,
                         self._contrib, self._decay, self._act, self._slow, self._d_oct)  # fmt: skip

    def dominant_index(self) -> int:
        """Index of the behavior with the largest activation (ties: first in model order)."""
        a = self._alpha
        return a.index(max(a))

    def dominant(self, behaviors: tuple[str, ...]) -> str:
        """The behavior with the largest activation (ties: first in model order)."""
        return behaviors[self.dominant_index()]


class DDSystem:
    """A DD behavior system in motion: call :meth:`step` once per control tick.

    Args:
        model: a compiled model (:func:`xabsl_studio.engine.dynamics.model.load_model`).
        seed: seed of the run's noise generator.
        dt: default tick; the model is re-checked for stability at this dt.
        noise: multiplies every σ (0 turns noise off, as in §4.4 claims 7 and 23).
    """

    def __init__(self, model: DDModel, seed: int = 0, dt: float | None = None, noise: float = 1.0) -> None:
        self.model = model
        self.dt = float(model.dt if dt is None else dt)
        if self.dt != model.dt:
            model.check_stability(self.dt)
        self.noise = float(noise)
        self._sensor_index = {s: i for i, s in enumerate(model.sensors)}
        self._alpha_names = tuple(f"alpha.{b}" for b in model.behaviors)
        self._compile()
        self.reset(seed)

    def _compile(self) -> None:
        """Generate the tick's arithmetic as one straight-line Python function of floats.

        With 8 behaviors and 6 actuators one numpy call costs more than the arithmetic it does,
        so :meth:`step` runs a function generated from the model once (like the model's own
        evaluator): every parameter is a literal, the sparse rows of B and W keep only their
        non-zero entries, and nothing loops. :meth:`flow` keeps the vectorised numpy form, and
        the tests check that the two agree.
        """
        m = self.model
        self.kernel_source = _kernel_source(m)
        namespace: dict[str, Callable[..., Any]] = {"tanh": math.tanh}
        # The source holds only numbers from the model and fixed names: nothing user-written runs.
        exec(compile(self.kernel_source, f"<dd-kernel:{m.name}>", "exec"), namespace)
        self._kernel = namespace["_kernel"]
        self._sigma = m.sigma.tolist()
        self._zeros = [0.0] * m.n
        self._cz: dict[str, tuple[list[float], list[float]]] = {}

    def _couplings(self, op: str) -> tuple[list[float], list[float]]:
        hit = self._cz.get(op)
        if hit is None:
            c, z = self.model.couplings(op)
            hit = self._cz[op] = (c.tolist(), z.tolist())
        return hit

    # -- state --

    def reset(self, seed: int = 0) -> None:
        """Back to the model's initial state with a fresh noise generator."""
        m = self.model
        self.rng = np.random.default_rng(seed)
        self.t = 0.0
        self._a: list[float] = m.alpha_init.tolist()
        self._v: list[float] = m.slow_init.tolist()
        self._m: list[float] = m.act_init.tolist()
        self.s: dict[str, float] = {}
        self.sigma_op: dict[str, float] = {}
        self.pinned: dict[str, float] = {}
        self.last: TickRecord | None = None

    def set_current_operator(self, operator: str | None) -> None:
        """Make ``operator`` (e.g. ``"goto a c"``) the one with σ_OP = 1; None: no operator.

        Raises:
            ModelError: the model has no OCT table entry for the operator's schema.
        """
        if operator is not None:
            self.model.couplings(operator)  # validate now, not in the middle of a tick
        self.sigma_op = {} if operator is None else {operator: 1.0}

    def pin_switch(self, operator: str, value: float | None) -> None:
        """Hold s_OP at ``value`` (hand-driving from the editor, tests); None releases it."""
        if value is None:
            self.pinned.pop(operator, None)
            return
        self.model.couplings(operator)
        if not 0.0 <= value <= 1.0:
            raise ValueError(f"switch value must be in [0, 1], got {value}")
        self.pinned[operator] = float(value)
        self.s[operator] = float(value)

    @property
    def alpha(self) -> np.ndarray:
        """Activations α (a fresh array; assign an array to set them)."""
        return np.array(self._a)

    @alpha.setter
    def alpha(self, value: np.ndarray) -> None:
        self._a = np.asarray(value, dtype=float).tolist()

    @property
    def act(self) -> np.ndarray:
        """Actuator values (a fresh array; assign an array to set them)."""
        return np.array(self._m)

    @act.setter
    def act(self, value: np.ndarray) -> None:
        self._m = np.asarray(value, dtype=float).tolist()

    @property
    def slow(self) -> np.ndarray:
        """Slow variables (a fresh array; assign an array to set them)."""
        return np.array(self._v)

    @slow.setter
    def slow(self, value: np.ndarray) -> None:
        self._v = np.asarray(value, dtype=float).tolist()

    @property
    def alphas(self) -> dict[str, float]:
        """Activations by behavior name."""
        return dict(zip(self.model.behaviors, self._a, strict=True))

    @property
    def actuators(self) -> dict[str, float]:
        """Actuator values by name (what the world applies, §4.1 step 7)."""
        return dict(zip(self.model.actuators, self._m, strict=True))

    def signals(self, sensors: Mapping[str, float] | None = None) -> dict[str, float]:
        """Signal snapshot for fact derivation: sensors, slow variables, ``alpha.<b>``, actuators, ``s.<op>``."""
        out: dict[str, float] = dict(sensors) if sensors is not None else {}
        out.update(zip(self.model.slow, self._v, strict=True))
        out.update(zip(self._alpha_names, self._a, strict=True))
        out.update(zip(self.model.actuators, self._m, strict=True))
        out.update({f"s.{op}": v for op, v in self.s.items()})
        return out

    def sensor_vector(self, sensors: Mapping[str, float] | np.ndarray) -> list[float]:
        """Order a sensor mapping as the model declares it; missing or unknown names are errors."""
        m = self.model
        if isinstance(sensors, np.ndarray):
            if sensors.shape != (len(m.sensors),):
                raise ValueError(f"expected {len(m.sensors)} sensor values, got shape {sensors.shape}")
            values: list[float] = sensors.astype(float).tolist()
            return values
        if len(sensors) == len(m.sensors):
            # Fast path, once per tick: same size and every model name present means no extras.
            try:
                return [float(sensors[s]) for s in m.sensors]
            except KeyError:
                pass
        missing = [s for s in m.sensors if s not in sensors]
        if missing:
            raise ModelError(f"model {m.name!r}: missing sensor value(s) {', '.join(missing)}")
        extra = [s for s in sensors if s not in self._sensor_index]
        if extra:
            raise ModelError(f"model {m.name!r}: unknown sensor(s) {', '.join(extra)}")
        return [float(sensors[s]) for s in m.sensors]

    # -- dynamics --

    def _drive(self, features: list[float], alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        m = self.model
        f = np.asarray(features, dtype=float)
        u = m.B @ f + m.W @ alpha + m.bias
        x = m.k * (u - m.theta)
        T = 0.5 * (1.0 + np.tanh(0.5 * x))  # the logistic, without exp overflow for steep k
        return f, u, T

    def _actuator_rates(
        self, targets: list[float], alpha: np.ndarray, act: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        m = self.model
        tgt = np.asarray(targets, dtype=float)
        contrib = alpha[m.pair_behavior] * m.pair_rate * (tgt - act[m.pair_actuator])
        return tgt, contrib

    def step(self, sensors: Mapping[str, float] | np.ndarray, dt: float | None = None) -> TickRecord:
        """Advance one tick with this tick's sensor snapshot; return the tick's record."""
        m = self.model
        h = self.dt if dt is None else float(dt)
        if dt is not None and h != self.dt:
            m.check_stability(h)
        sv = self.sensor_vector(sensors)

        # 1. switch variables ramp toward σ (pinned ones are held).
        for op in set(self.s) | set(self.sigma_op):
            if op in self.pinned:
                self.s[op] = self.pinned[op]
                continue
            s = self.s.get(op, 0.0)
            s += h * m.lambda_s * (self.sigma_op.get(op, 0.0) - s)
            if s < 1e-9 and op not in self.sigma_op:
                self.s.pop(op, None)  # fully released: keep the active set small
            else:
                self.s[op] = s

        # 2.–3. one snapshot for all increments (PDL semantics: every Δ reads the same α, m, v),
        # then the commit with clipping; all of it in the generated kernel except the OCTs.
        alpha, act, slow = self._a, self._m, self._v
        feats, tgts, rates = m.evaluate(sv, slow, alpha)
        d_oct: dict[str, list[float]] = {}
        oct_sum = self._zeros
        for op, s in self.s.items():
            if s > 0.0:
                c, z = self._couplings(op)
                hs = h * s
                d = d_oct[op] = [hs * ci * (zi - ai) for ci, zi, ai in zip(c, z, alpha, strict=True)]
                oct_sum = d if oct_sum is self._zeros else [a + b for a, b in zip(oct_sum, d, strict=True)]
        xi = self.rng.standard_normal(len(alpha) + len(slow)).tolist()
        sq = math.sqrt(h) * self.noise
        u, T, d_relax, d_noise, contrib, decay, new_alpha, new_act, new_slow = self._kernel(
            feats + alpha, alpha, act, slow, tgts, rates, xi, h, sq, oct_sum
        )
        self._a, self._m, self._v = new_alpha, new_act, new_slow
        self.t += h

        self.last = TickRecord(
            self.t,
            h,
            m,
            (feats, u, T, new_alpha, d_relax, d_noise, tgts, contrib, decay, new_act, new_slow),
            d_oct,
            dict(self.s),
        )
        return self.last

    # -- offline integration --

    def state_vector(self) -> np.ndarray:
        """Concatenate [α, slow variables, actuators] (the layout :meth:`flow` integrates)."""
        return np.concatenate([self.alpha, self.slow, self.act])

    def flow(
        self, sensors: Mapping[str, float] | np.ndarray, switches: Mapping[str, float] | None = None
    ) -> Callable[[float, np.ndarray], np.ndarray]:
        """The noise-free right-hand side dy/dt on frozen sensors and frozen switch values.

        ``y`` is laid out as :meth:`state_vector`. Intended for ``solve_ivp`` (accuracy checks,
        phase portraits, §4.1); the online loop uses :meth:`step`.
        """
        m = self.model
        sv = self.sensor_vector(sensors)
        sw = dict(self.s if switches is None else switches)
        couplings = [(s, *m.couplings(op)) for op, s in sw.items() if s > 0.0]
        n, nv = m.n, len(m.slow)

        def rhs(_t: float, y: np.ndarray) -> np.ndarray:
            alpha, slow, act = y[:n], y[n : n + nv], y[n + nv :]
            feats, tgts, rates = m.evaluate(sv, slow.tolist(), alpha.tolist())
            _, _, T = self._drive(feats, alpha)
            da = m.lam * (T - alpha)
            for s, c, z in couplings:
                da = da + s * c * (z - alpha)
            _, contrib = self._actuator_rates(tgts, alpha, act)
            dm = -m.act_decay * act + np.bincount(m.pair_actuator, contrib, minlength=len(m.actuators))
            return np.concatenate([da, np.asarray(rates, dtype=float), dm])

        return rhs


def _kernel_source(m: DDModel) -> str:
    """Python source of ``_kernel`` for model ``m`` (see :meth:`DDSystem._compile`).

    ``_kernel(x, A, M, V, G, R, xi, h, sq, O)`` takes the drive inputs x = [s, α], activations A,
    actuators M, slow variables V, pair targets G, slow rates R, the noise draws ξ, the tick h,
    √h·noise and the summed OCT increments O; it returns u, T, dt·λ(T − α), σ√h·ξ, the pair
    contributions, the actuator decay terms and the committed α, actuators and slow variables.
    """
    nf, n = len(m.features), m.n

    def num(v: float) -> str:
        return repr(float(v))

    def clamp(target: str, expr: str, lo: float, hi: float) -> list[str]:
        # Conditional expressions rather than min/max calls: a builtin call costs more here.
        lines = [f"{target} = {expr}"]
        if math.isfinite(lo):
            lines.append(f"if {target} < {num(lo)}: {target} = {num(lo)}")
        if math.isfinite(hi):
            lines.append(f"if {target} > {num(hi)}: {target} = {num(hi)}")
        return lines

    body = []
    for i in range(n):
        terms = [num(m.bias[i])]
        terms += [f"{num(m.B[i, j])} * x[{j}]" for j in range(nf) if m.B[i, j] != 0.0]
        terms += [f"{num(m.W[i, j])} * x[{nf + j}]" for j in range(n) if m.W[i, j] != 0.0]
        body.append(f"u{i} = {' + '.join(terms)}")
        # the logistic S(k(u − θ)) as ½(1 + tanh(k(u − θ)/2)): no exp overflow for steep k
        body.append(f"T{i} = 0.5 * (1.0 + tanh({num(0.5 * m.k[i])} * (u{i} - {num(m.theta[i])})))")
        body.append(f"r{i} = h * {num(m.lam[i])} * (T{i} - A[{i}])")
        body.append(f"n{i} = {num(m.sigma[i])} * sq * xi[{i}]")
        body.append(f"v = A[{i}] + (r{i} + n{i} + O[{i}])")
        body.append(f"a{i} = 0.0 if v < 0.0 else (1.0 if v > 1.0 else v)")
    pairs = list(zip(m.pair_behavior.tolist(), m.pair_actuator.tolist(), m.pair_rate.tolist(), strict=True))
    for p, (b, a, rate) in enumerate(pairs):
        body.append(f"c{p} = A[{b}] * {num(rate)} * (G[{p}] - M[{a}])")
    na = len(m.actuators)
    for a in range(na):
        pushed = " + ".join(f"c{p}" for p, (_, pa, _) in enumerate(pairs) if pa == a) or "0.0"
        body.append(f"k{a} = {num(-m.act_decay[a])} * M[{a}]")
        body += clamp(f"m{a}", f"M[{a}] + h * (k{a} + ({pushed}))", m.act_lo[a], m.act_hi[a])
    nv = len(m.slow)
    for v in range(nv):
        update = f"V[{v}] + (h * R[{v}] + {num(m.slow_sigma[v])} * sq * xi[{n + v}])"
        body += clamp(f"w{v}", update, m.slow_lo[v], m.slow_hi[v])

    def seq(prefix: str, count: int) -> str:
        return "[" + ", ".join(f"{prefix}{i}" for i in range(count)) + "]"

    outs = [seq("u", n), seq("T", n), seq("r", n), seq("n", n), seq("c", len(pairs)), seq("k", na),
            seq("a", n), seq("m", na), seq("w", nv)]  # fmt: skip
    lines = ["def _kernel(x, A, M, V, G, R, xi, h, sq, O):", *("    " + line for line in body)]
    lines.append("    return (" + ", ".join(outs) + ")")
    return "\n".join(lines) + "\n"
