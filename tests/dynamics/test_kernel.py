"""The generated tick kernel of DDSystem agrees with the vectorised right-hand side (flow)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from xabsl_studio.engine.dynamics.model import load_model
from xabsl_studio.engine.dynamics.system import DDSystem

MODEL_PATH = Path(__file__).resolve().parents[2] / "examples" / "errands" / "model" / "errands_dd.json"


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_step_is_one_clipped_euler_step_of_flow(seed):
    model = load_model(MODEL_PATH)
    dd = DDSystem(model, seed=seed, noise=0.0)
    # Two operators at once exercise the summed OCT increments.
    dd.pin_switch("goto a c", 0.7)
    dd.pin_switch("load mug c", 0.3)
    rng = np.random.default_rng(seed)
    lo = np.concatenate([np.zeros(model.n), model.slow_lo, model.act_lo])
    hi = np.concatenate([np.ones(model.n), model.slow_hi, model.act_hi])
    h = dd.dt
    for _ in range(200):
        sensors = {}
        for name in model.sensors:
            a, b = model.sensor_ranges[name]
            sensors[name] = float(rng.uniform(a, b))
        y = dd.state_vector()
        expected = np.clip(y + h * dd.flow(sensors, dict(dd.s))(0.0, y), lo, hi)
        rec = dd.step(sensors)
        np.testing.assert_allclose(dd.state_vector(), expected, rtol=0, atol=1e-12)
        np.testing.assert_allclose(rec.alpha, dd.alpha, rtol=0, atol=0)


def test_kernel_source_is_kept_and_names_every_behavior():
    dd = DDSystem(load_model(MODEL_PATH))
    assert dd.kernel_source.startswith("def _kernel(")
    assert all(f"a{i} = " in dd.kernel_source for i in range(dd.model.n))


def test_records_hand_out_fresh_arrays():
    dd = DDSystem(load_model(MODEL_PATH), seed=1)
    rec = dd.step({name: 0.0 for name in dd.model.sensors})
    a = rec.alpha
    a[:] = 5.0
    assert rec.alpha.max() <= 1.0
    dd.step({name: 0.0 for name in dd.model.sensors})
    assert rec.dominant(dd.model.behaviors) == dd.model.behaviors[int(np.argmax(rec.alpha))]
