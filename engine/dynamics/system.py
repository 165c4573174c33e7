"""The running Dual Dynamics behavior system: one synchronous Euler(-Maruyama) tick (doc §1.3–§1.5, §4.1).

This module owns the state of a DD system built from a :class:`~engine.dynamics.model.DDModel`
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
from dataclasses import dataclass

import numpy as np

from engine.dynamics.model import DDModel, ModelError

_minimum = np.minimum
_maximum = np.maximum


@dataclass(frozen=True, slots=True)
class TickRecord:
    """Everything one tick computed, for the debugger (arrays are fresh, never mutated later).

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
        pair_targets: m*_i per (behavior, actuator) target pair of the model (``targets`` is the
            behavior × actuator matrix, NaN where a behavior has no target, built on demand).
        pair_contributions: α_i·λ_im·(m*_i − m) per target pair (1/s); ``contributions`` is the
            matrix, built on demand.
        decay: per actuator, −decay·m (1/s).
        actuators: actuator values after commit.
        slow: slow variables after commit.
        model: the model, for names and the pair layout.

    The matrices are properties rather than fields because building them costs more than the
    rest of the record, and the headless loop rarely looks at them (errands speed target, §4.4).
    """

    t: float
    dt: float
    features: np.ndarray
    u: np.ndarray
    T: np.ndarray
    alpha: np.ndarray
    d_relax: np.ndarray
    d_oct: Mapping[str, np.ndarray]
    d_noise: np.ndarray
    switches: Mapping[str, float]
    pair_targets: np.ndarray
    pair_contributions: np.ndarray
    decay: np.ndarray
    actuators: np.ndarray
    slow: np.ndarray
    model: DDModel

    @property
    def targets(self) -> np.ndarray:
        """Behavior × actuator matrix of m*_i (NaN where a behavior has no target)."""
        m = self.model
        tmat = np.full((m.n, len(m.actuators)), np.nan)
        tmat[m.pair_behavior, m.pair_actuator] = self.pair_targets
        return tmat

    @property
    def contributions(self) -> np.ndarray:
        """Behavior × actuator matrix of α_i·λ_im·(m*_i − m) (1/s)."""
        m = self.model
        cmat = np.zeros((m.n, len(m.actuators)))
        cmat[m.pair_behavior, m.pair_actuator] = self.pair_contributions
        return cmat

    def dominant(self, behaviors: tuple[str, ...]) -> str:
        """The behavior with the largest activation (ties: first in model order)."""
        return behaviors[int(np.argmax(self.alpha))]


class DDSystem:
    """A DD behavior system in motion: call :meth:`step` once per control tick.

    Args:
        model: a compiled model (:func:`engine.dynamics.model.load_model`).
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
        self.reset(seed)

    # -- state --

    def reset(self, seed: int = 0) -> None:
        """Back to the model's initial state with a fresh noise generator."""
        m = self.model
        self.rng = np.random.default_rng(seed)
        self.t = 0.0
        self.alpha = m.alpha_init.copy()
        self.slow = m.slow_init.copy()
        self.act = m.act_init.copy()
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
    def alphas(self) -> dict[str, float]:
        """Activations by behavior name."""
        return dict(zip(self.model.behaviors, self.alpha.tolist(), strict=True))

    @property
    def actuators(self) -> dict[str, float]:
        """Actuator values by name (what the world applies, §4.1 step 7)."""
        return dict(zip(self.model.actuators, self.act.tolist(), strict=True))

    def signals(self, sensors: Mapping[str, float] | None = None) -> dict[str, float]:
        """Signal snapshot for fact derivation: sensors, slow variables, ``alpha.<b>``, actuators, ``s.<op>``."""
        out: dict[str, float] = dict(sensors) if sensors is not None else {}
        out.update(zip(self.model.slow, self.slow.tolist(), strict=True))
        out.update(zip(self._alpha_names, self.alpha.tolist(), strict=True))
        out.update(zip(self.model.actuators, self.act.tolist(), strict=True))
        out.update({f"s.{op}": v for op, v in self.s.items()})
        return out

    def sensor_vector(self, sensors: Mapping[str, float] | np.ndarray) -> list[float]:
        """Order a sensor mapping as the model declares it; missing or unknown names are errors."""
        m = self.model
        if isinstance(sensors, np.ndarray):
            if sensors.shape != (len(m.sensors),):
                raise ValueError(f"expected {len(m.sensors)} sensor values, got shape {sensors.shape}")
            return sensors.astype(float).tolist()
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

        # 2. one snapshot for all increments.
        alpha, act, slow = self.alpha, self.act, self.slow
        feats, tgts, rates = m.evaluate(sv, slow.tolist(), alpha.tolist())
        f, u, T = self._drive(feats, alpha)
        d_relax = h * m.lam * (T - alpha)
        d_oct: dict[str, np.ndarray] = {}
        for op, s in self.s.items():
            if s > 0.0:
                c, z = m.couplings(op)
                d_oct[op] = h * s * c * (z - alpha)
        xi = self.rng.standard_normal(m.n + len(m.slow))
        sq = math.sqrt(h) * self.noise
        d_noise = m.sigma * sq * xi[: m.n]
        tgt, contrib = self._actuator_rates(tgts, alpha, act)
        decay = -m.act_decay * act
        d_act = h * (decay + np.bincount(m.pair_actuator, contrib, minlength=len(m.actuators)))
        d_slow = h * np.asarray(rates, dtype=float) + m.slow_sigma * sq * xi[m.n :]

        # 3. commit.
        d_alpha = d_relax + d_noise
        for d in d_oct.values():
            d_alpha = d_alpha + d
        # np.minimum(np.maximum(x, lo), hi) is np.clip's definition, without its dispatch overhead.
        self.alpha = _minimum(_maximum(alpha + d_alpha, 0.0), 1.0)
        self.act = _minimum(_maximum(act + d_act, m.act_lo), m.act_hi)
        self.slow = _minimum(_maximum(slow + d_slow, m.slow_lo), m.slow_hi)
        self.t += h

        self.last = TickRecord(
            t=self.t,
            dt=h,
            features=f,
            u=u,
            T=T,
            alpha=self.alpha,
            d_relax=d_relax,
            d_oct=d_oct,
            d_noise=d_noise,
            switches=dict(self.s),
            pair_targets=tgt,
            pair_contributions=contrib,
            decay=decay,
            actuators=self.act,
            slow=self.slow,
            model=m,
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
