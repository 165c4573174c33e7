"""Fuzz the Dual Dynamics model loader: a mutated errands model loads or is a ModelError, nothing else."""

from __future__ import annotations

import json
import random
import tempfile
from pathlib import Path

from hypothesis import given
from hypothesis import strategies as st

from tests.fuzz.probes import fuzz_settings, mutate_many, splice_odd_value, time_bound
from xabsl_studio.engine.dynamics.model import ModelError, load_model

MODEL = Path(__file__).resolve().parents[2] / "examples" / "errands" / "model" / "errands_dd.json"
RAW = MODEL.read_bytes()
DOCUMENT = json.loads(RAW)


@fuzz_settings(150)
@given(st.randoms(use_true_random=False))
def test_mutated_models_load_or_raise_model_error(rnd: random.Random) -> None:
    if rnd.random() < 0.6:
        data = splice_odd_value(DOCUMENT, rnd).encode("utf-8", "surrogatepass")
    else:
        data = mutate_many(RAW, rnd)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "model.json"
        path.write_bytes(data)
        try:
            with time_bound():
                load_model(path)
        except ModelError as error:
            message = str(error)
            assert str(path) in message, message
            assert len(message) < 2000, f"message of {len(message)} characters"


@fuzz_settings(80)
@given(st.randoms(use_true_random=False))
def test_mutated_model_texts_in_the_studio_give_diagnostics(rnd: random.Random) -> None:
    from types import SimpleNamespace

    from xabsl_studio.examples.errands import model_edit

    if rnd.random() < 0.6:
        text = splice_odd_value(DOCUMENT, rnd)
    else:
        text = mutate_many(RAW, rnd).decode("utf-8", "replace")
    world = SimpleNamespace(model_name="model/errands_dd.json", dt=0.02)
    with time_bound():
        diagnostics, model = model_edit.check(world, text)  # type: ignore[arg-type]
    assert (model is None) == bool(diagnostics)
    for diagnostic in diagnostics:
        assert diagnostic["span"]["line"] >= 1 and len(diagnostic["message"]) < 2000
