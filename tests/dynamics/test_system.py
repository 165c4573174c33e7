from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from xabsl_studio.engine.dynamics.model import ModelError, load_model
from xabsl_studio.engine.dynamics.system import DDSystem

MODEL_PATH = Path(__file__).resolve().parents[2] / "examples/errands/model/errands_dd.json"
DT = 0.02
TASK = ["approach_a", "approach_b", "approach_c", "gather_book", "gather_mug", "dump_book", "dump_mug"]


@pytest.fixture(scope="module")
def model():
    return load_model(MODEL_PATH)


def far_from_beacons(model, **over):
    """Robot in the open: no obstacle, no beacon near, no object in view."""
    s = dict.fromkeys(model.sensors, 0.0)
    s.update({"φ_a": 0.6, "φ_b": -0.4, "φ_c": 0.15, "speed": 0.2})
    s.update(over)
    return s


def random_sensors(model, rng):
    out = {}
    for name in model.sensors:
        lo, hi = model.sensor_ranges[name]
        out[name] = float(rng.uniform(lo, hi))
    for x in "abc":
        out[f"δ_{x}"] = float(rng.random() < 0.2)
    return out


def test_claim6_alpha_stays_in_unit_interval(model):
    rng = np.random.default_rng(7)
    dd = DDSystem(model, seed=3, noise=8.0)  # σ = 0.4: clipping must do its job
    ops = [None, "goto a c", "load mug c", "goto c b", "unload book a"]
    for tick in range(3000):
        if tick % 200 == 0:
            dd.set_current_operator(ops[(tick // 200) % len(ops)])
        rec = dd.step(random_sensors(model, rng))
        assert rec.alpha.min() >= 0.0 and rec.alpha.max() <= 1.0
        assert np.all(rec.actuators >= model.act_lo) and np.all(rec.actuators <= model.act_hi)


def test_claim7_bit_identical_runs(model):
    def run(seed, noise):
        dd = DDSystem(model, seed=seed, noise=noise)
        dd.set_current_operator("goto a c")
        rng = np.random.default_rng(0)
        trace = []
        for _ in range(500):
            dd.step(random_sensors(model, rng))
            trace.append(np.concatenate([dd.alpha, dd.act, dd.slow]))
        return np.array(trace)

    a, b = run(11, 0.0), run(11, 0.0)
    assert a.tobytes() == b.tobytes()
    # With noise, the same seed is also bit-identical and another seed is not.
    assert run(5, 1.0).tobytes() == run(5, 1.0).tobytes()
    assert run(5, 1.0).tobytes() != run(6, 1.0).tobytes()


@pytest.mark.parametrize("seed", range(5))
def test_claim8_roam_on_without_octs(model, seed):
    dd = DDSystem(model, seed=seed)
    sensors = far_from_beacons(model)
    reached = None
    for tick in range(1, round(2.0 / DT) + 1):
        dd.step(sensors)
        if reached is None and dd.alphas["roam"] > 0.9:
            reached = tick * DT
    print("roam > 0.9 at", reached, dd.alphas)
    assert reached is not None and reached <= 2.0


@pytest.mark.parametrize("seed", range(5))
def test_claim9_goto_switch_drives_approach(model, seed):
    dd = DDSystem(model, seed=seed)
    dd.pin_switch("goto a c", 1.0)
    sensors = far_from_beacons(model)
    reached = None
    worst_other = 0.0
    for tick in range(1, round(3.0 / DT) + 1):
        rec = dd.step(sensors)
        a = dd.alphas
        if reached is None and a["approach_c"] > 0.75:
            reached = tick * DT
        worst_other = max(worst_other, max(a[b] for b in TASK if b != "approach_c"))
        assert rec.switches == {"goto a c": 1.0}
    print("approach_c > 0.75 at", reached, "worst other", worst_other)
    assert reached is not None and reached <= 1.5
    assert worst_other < 0.25


def test_switch_ramps_and_handover_keeps_sum_at_most_one(model):
    dd = DDSystem(model, seed=0)
    sensors = far_from_beacons(model)
    dd.set_current_operator("goto a c")
    for _ in range(10):
        dd.step(sensors)
    # Euler of ṡ = 5(1 − s) for 0.2 s: 1 − 0.9^10.
    assert dd.s["goto a c"] == pytest.approx(1 - 0.9**10)
    for _ in range(200):
        dd.step(sensors)
    dd.set_current_operator("load mug c")
    high = []
    for _ in range(200):
        rec = dd.step(sensors)
        assert sum(rec.switches.values()) <= 1.0 + 1e-12
        high.append(sum(v >= 0.5 for v in rec.switches.values()))
    assert max(high) == 1
    assert "goto a c" not in dd.s  # fully released switches leave the active set


def test_load_switch_turns_gather_on_and_roam_off(model):
    dd = DDSystem(model, seed=2)
    sensors = far_from_beacons(model, **{"δ_c": 1.0, "γ_mug": 0.9, "ψ_mug": 0.05})
    for _ in range(100):
        dd.step(sensors)
    assert dd.alphas["roam"] > 0.9
    dd.set_current_operator("load mug c")
    for _ in range(100):
        dd.step(sensors)
    a = dd.alphas
    assert a["gather_mug"] > 0.75 and a["roam"] < 0.25
    assert dd.actuators["g_mug"] > 0.5  # the gripper closes


def test_debug_record_decomposes_delta_alpha(model):
    dd = DDSystem(model, seed=4)
    sensors = far_from_beacons(model)
    dd.set_current_operator("goto a c")
    for _ in range(30):
        before = dd.alpha.copy()
        rec = dd.step(sensors)
    total = rec.d_relax + rec.d_noise + sum(rec.d_oct.values())
    inside = (before + total > 0) & (before + total < 1)
    np.testing.assert_allclose(rec.alpha[inside], (before + total)[inside], atol=1e-12)
    assert set(rec.d_oct) == {"goto a c"}
    np.testing.assert_allclose(rec.T, 1 / (1 + np.exp(-model.k * (rec.u - model.theta))))
    np.testing.assert_allclose(rec.u, model.B @ rec.features + model.W @ before + model.bias)


def test_actuator_fusion_is_activation_weighted_average(model):
    dd = DDSystem(model, seed=0, noise=0.0)
    sensors = far_from_beacons(model)
    for _ in range(500):
        a_before, m_before = dd.alpha.copy(), dd.act.copy()
        rec = dd.step(sensors)
    i = model.behavior_index("roam")
    # Each behavior adds its own share α_i·λ_m·(m*_i − m), computed from the tick's snapshot.
    assert rec.contributions[i, 0] == pytest.approx(a_before[i] * 8.0 * (rec.targets[i, 0] - m_before[0]))
    np.testing.assert_allclose(
        rec.actuators[0] - m_before[0], DT * (rec.decay[0] + rec.contributions[:, 0].sum()), atol=1e-15
    )
    # Equilibrium of ṁ = −λ0·m + Σ α_i λ_m (m*_i − m): weighted average shrunk by the decay.
    mask = ~np.isnan(rec.targets[:, 0])
    w = a_before[mask] * 8.0
    expected = (w * rec.targets[mask, 0]).sum() / (0.5 + w.sum())
    assert rec.actuators[0] == pytest.approx(expected, abs=1e-3)  # ν drifts slowly: near, not at
    assert rec.targets[i, 0] == pytest.approx(0.6)  # roam fwd with η = 0 and no obstacle


def euler_vs_rk45(model, sensors, operator=None, seconds=10.0):
    dd = DDSystem(model, seed=0, noise=0.0)
    if operator:
        dd.pin_switch(operator, 1.0)
    y0 = dd.state_vector()
    rhs = dd.flow(sensors, {operator: 1.0} if operator else {})
    n = round(seconds / DT)
    ts = np.arange(1, n + 1) * DT
    sol = solve_ivp(rhs, (0.0, seconds), y0, method="RK45", t_eval=ts, rtol=1e-8, atol=1e-10)
    assert sol.success
    euler = np.array([dd.step(sensors).alpha for _ in range(n)])
    return np.abs(euler - sol.y[: model.n].T).max()


@pytest.mark.parametrize(
    "where",
    [
        {},
        {"δ_b": 1.0, "γ_book": 0.9, "ψ_book": 0.1, "o_l": 0.4, "speed": 0.0},
    ],
)
def test_claim23_euler_matches_rk45_without_octs(model, where):
    err = euler_vs_rk45(model, far_from_beacons(model, **where))
    print("max |α_euler − α_rk45| =", err)
    assert err < 0.02  # measured ≈ 0.011


def test_euler_error_with_oct_held(model):
    # With an OCT held the fastest rate is λ + c = 13/s, and first-order Euler at 20 ms is off
    # by about (13·0.02)/2·e⁻¹ ≈ 0.05 at worst during the transient: the doc's 0.02 does not
    # hold here (measured ≈ 0.041). Halving dt halves the error.
    err = euler_vs_rk45(model, far_from_beacons(model), "goto a c")
    print("with OCT: max |α_euler − α_rk45| =", err)
    assert err < 0.05


def test_signals_for_fact_derivation(model):
    dd = DDSystem(model, seed=0)
    dd.set_current_operator("load book b")
    sensors = far_from_beacons(model)
    dd.step(sensors)
    sig = dd.signals(sensors)
    for key in ("δ_a", "γ_book", "alpha.gather_book", "alpha.dump_mug", "g_book", "d_mug", "ν_a", "s.load book b"):
        assert key in sig


def test_input_errors(model):
    dd = DDSystem(model)
    with pytest.raises(ModelError, match="missing sensor value"):
        dd.step({"o_l": 0.0})
    with pytest.raises(ModelError, match="unknown sensor"):
        dd.step({**far_from_beacons(model), "lidar": 1.0})
    with pytest.raises(ModelError, match="no OCT table for operator schema 'fly'"):
        dd.set_current_operator("fly a b")
    with pytest.raises(ValueError, match=r"switch value must be in \[0, 1\]"):
        dd.pin_switch("goto a b", 2.0)
    with pytest.raises(ModelError, match=r"unstable at dt=0\.1"):
        DDSystem(model, dt=0.1)


def test_array_sensors_and_dominant(model):
    dd = DDSystem(model, seed=0)
    vec = np.array(dd.sensor_vector(far_from_beacons(model)))
    for _ in range(50):
        rec = dd.step(vec)
    assert rec.dominant(model.behaviors) == "roam"
