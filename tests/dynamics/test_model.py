import copy
import json
from pathlib import Path

import numpy as np
import pytest

from xabsl_studio.engine.dynamics.model import ModelError, build_model, load_model

MODEL_PATH = Path(__file__).resolve().parents[2] / "examples/errands/model/errands_dd.json"
RAW = json.loads(MODEL_PATH.read_text(encoding="utf-8"))
BEHAVIORS = ["roam", "approach_a", "approach_b", "approach_c", "gather_book", "gather_mug", "dump_book", "dump_mug"]


@pytest.fixture(scope="module")
def model():
    return load_model(MODEL_PATH)


def variant(edit):
    data = copy.deepcopy(RAW)
    edit(data)
    return data


def test_errands_model_loads_with_section_1_5_names(model):
    assert list(model.behaviors) == BEHAVIORS
    for s in ("o_l", "o_r", "φ_a", "φ_b", "φ_c", "δ_a", "δ_b", "δ_c", "γ_book", "γ_mug", "ψ_book", "ψ_mug"):
        assert s in model.sensors
    assert set(model.slow) == {"ν_a", "ν_b", "ν_c", "f", "η"}
    assert list(model.actuators) == ["m_l", "m_r", "g_book", "g_mug", "d_book", "d_mug"]
    assert model.lam.tolist() == [3.0] * 8 and model.k.tolist() == [8.0] * 8
    assert model.sigma.tolist() == [0.05] * 8
    assert model.lambda_s == 5.0


def test_drives_compile_to_B_W_bias(model):
    i = model.behavior_index
    # Self-excitation on the diagonal, mutual inhibition among the approaches (§1.5 table).
    assert model.W[i("approach_a"), i("approach_a")] == pytest.approx(0.3)
    assert model.W[i("approach_a"), i("approach_b")] == pytest.approx(-1.2)
    assert model.W[i("gather_book"), i("gather_book")] == pytest.approx(0.3)
    assert model.bias[i("roam")] == 1.0
    f = model.features.index("f")
    assert model.B[i("roam"), f] == 1.5 and model.B[i("approach_b"), f] == -1.5
    nu = model.features.index("ν_c")
    assert model.B[i("approach_c"), nu] == pytest.approx(0.9)
    # opportunistic = 0 folds the γ term of gather away entirely.
    assert not any("γ" in feat for feat in model.features)


def test_oct_table_goto_load_unload(model):
    i = model.behavior_index
    c, z = model.couplings("goto a c")
    assert c[i("roam")] == 0.0  # uncoupled: the escape route
    assert (c[i("approach_c")], z[i("approach_c")]) == (10.0, 1.0)
    for b in ("approach_a", "approach_b", "gather_book", "gather_mug", "dump_book", "dump_mug"):
        assert (c[i(b)], z[i(b)]) == (10.0, 0.0)
    c, z = model.couplings("load mug c")
    assert z.tolist() == [0, 0, 0, 0, 0, 1, 0, 0] and (c == 10.0).all()
    c, z = model.couplings("unload book a")
    assert z.tolist() == [0, 0, 0, 0, 0, 0, 1, 0] and (c == 10.0).all()
    assert model.couplings("GOTO a c")[1].tolist() == model.couplings("goto a c")[1].tolist()


def test_oct_errors(model):
    with pytest.raises(ModelError, match="no OCT table for operator schema 'fly'"):
        model.couplings("fly a b")
    with pytest.raises(ModelError, match="has 1 arguments, OCT schema 'goto' expects 2"):
        model.couplings("goto a")
    with pytest.raises(ModelError, match=r"'approach_\{to\}' -> 'approach_z' names no behavior"):
        model.couplings("goto a z")


def test_stability_of_errands_model(model):
    model.check_stability(0.02)
    # Activations would allow 50 ms ((3 + 10)·0.05 = 0.65), but eight behaviors pulling the
    # wheels at λ_m = 8/s exceed the explicit-Euler bound when all are fully active.
    with pytest.raises(ModelError, match=r"actuator 'm_l': \(decay \+ Σ rates\)·dt = 64.5·0.05 = 3.23 ≥ 2"):
        model.check_stability(0.05)


def test_bad_expression_named():
    data = variant(lambda d: d["behaviors"]["roam"].__setitem__("drive", "1 - 1.2* * f"))
    with pytest.raises(ModelError) as info:
        build_model(data, source="errands_dd.json")
    msg = str(info.value)
    assert msg.startswith("errands_dd.json: behaviors.roam.drive: syntax error")
    assert "at column 10" in msg and "1 - 1.2* * f" in msg


def test_unknown_sensor_named():
    data = variant(lambda d: d["behaviors"]["approach_a"]["let"].__setitem__("turn", "-2*φ_d + av"))
    with pytest.raises(ModelError, match=r"behaviors\.approach_a\.let\.turn: unknown name 'φ_d' at column 4"):
        build_model(data, source="errands_dd.json")


def test_unstable_rates_named():
    data = variant(lambda d: d["behaviors"]["roam"].__setitem__("lambda", 50))
    with pytest.raises(ModelError) as info:
        build_model(data, source="errands_dd.json")
    assert str(info.value) == (
        "errands_dd.json: stability: model 'errands' is unstable at dt=0.02: "
        "behavior 'roam': (λ + max c)·dt = (50 + 10)·0.02 = 1.2 ≥ 1"
    )


def test_unstable_coupling_named():
    data = variant(lambda d: d["parameters"].__setitem__("c_oct", 60))
    with pytest.raises(ModelError, match=r"behavior 'roam': \(λ \+ max c\)·dt = \(3 \+ 60\)·0.02 = 1.26 ≥ 1"):
        build_model(data)


def test_unstable_at_larger_dt():
    with pytest.raises(
        ModelError, match=r"unstable at dt=0.1: behavior 'roam': \(λ \+ max c\)·dt = \(3 \+ 10\)·0.1 = 1.3 ≥ 1"
    ):
        load_model(MODEL_PATH, dt=0.1)


def test_unstable_switch_rate_named():
    data = variant(lambda d: d["switches"].__setitem__("lambda_s", 80))
    with pytest.raises(ModelError, match=r"switches: λ_s·dt = 80·0.02 = 1.6 ≥ 1"):
        build_model(data)


def test_unknown_actuator_named():
    data = variant(lambda d: d["behaviors"]["dump_book"]["targets"].__setitem__("d_cup", "1"))
    with pytest.raises(ModelError, match=r"behaviors\.dump_book\.targets\.d_cup: unknown actuator 'd_cup'"):
        build_model(data)


def test_unknown_key_named():
    data = variant(lambda d: d["behaviors"]["roam"].__setitem__("lamda", 3))
    with pytest.raises(ModelError, match=r"behaviors\.roam: unknown key\(s\) 'lamda'"):
        build_model(data)


def test_wrong_format_named():
    with pytest.raises(ModelError, match="format: expected 'xabsl-dd-model/1'"):
        build_model({"format": "dd/0", "behaviors": {}})


def test_higher_level_behavior_has_no_targets():
    data = variant(lambda d: d["behaviors"]["roam"].__setitem__("level", 1))
    with pytest.raises(ModelError, match=r"behaviors\.roam\.targets: only elementary behaviors \(level 0\)"):
        build_model(data)


def test_oct_placeholder_must_be_parameter():
    data = variant(lambda d: d["oct"]["goto"]["couplings"][0].__setitem__("behavior", "approach_{dest}"))
    with pytest.raises(
        ModelError, match=r"oct\.goto\.couplings\[0\]\.behavior: placeholder \{dest\} is not a parameter"
    ):
        build_model(data)


def test_oct_pattern_must_match_a_behavior():
    data = variant(lambda d: d["oct"]["load"]["couplings"][0].__setitem__("behavior", "grab_{o}"))
    with pytest.raises(
        ModelError, match=r"oct\.load\.couplings\[0\]\.behavior: pattern 'grab_\{o\}' matches no behavior"
    ):
        build_model(data)


def test_name_clash_named():
    data = variant(lambda d: d["parameters"].__setitem__("o_l", 1.0))
    with pytest.raises(ModelError, match=r"sensors\.o_l: sensor 'o_l' clashes with the parameter of that name"):
        build_model(data)


def test_numeric_field_must_be_constant():
    data = variant(lambda d: d["behaviors"]["roam"].__setitem__("lambda", "o_l*3"))
    with pytest.raises(ModelError, match=r"behaviors\.roam\.lambda: unknown name 'o_l'"):
        build_model(data)


def test_invalid_json_named(tmp_path):
    p = tmp_path / "m.json"
    p.write_text("{", encoding="utf-8")
    with pytest.raises(ModelError, match=r"m\.json: not valid JSON"):
        load_model(p)


def test_minimal_model_and_sensor_list_form():
    m = build_model(
        {
            "format": "xabsl-dd-model/1",
            "sensors": ["x"],
            "actuators": {"v": {"rate": 2}},
            "behaviors": {"go": {"drive": "x", "targets": {"v": "1"}}},
        }
    )
    assert m.sensors == ("x",) and m.features == ("x",)
    assert m.pair_rate.tolist() == [2.0]
    assert np.isinf(m.sensor_ranges["x"][1])


# -- issue 18: every broken model file is a ModelError naming the file, the key and the column -------


def _write(tmp_path, data):
    path = tmp_path / "m.json"
    path.write_bytes(data if isinstance(data, bytes) else json.dumps(data, ensure_ascii=False).encode())
    return path


def _edit_drive(text):
    return variant(lambda d: d["behaviors"]["roam"].__setitem__("drive", text))


@pytest.mark.parametrize(
    ("text", "column"),
    [
        ("(" * 163 + "1" + ")" * 163, None),  # RecursionError in the parser before
        ("-" * 2000 + "1", None),
        ("1" + "+1" * 5000, None),  # a left-deep chain: RecursionError in fold/to_python
        ("2" + "**2" * 400, None),
        ("max(" * 300 + "1" + ")" * 300, None),
    ],
)
def test_deep_expressions_are_a_model_error_with_a_column(tmp_path, text, column):
    with pytest.raises(ModelError) as refused:
        load_model(_write(tmp_path, _edit_drive(text)))
    message = str(refused.value)
    assert str(tmp_path / "m.json") in message and "behaviors.roam.drive" in message
    assert "nested too deeply" in message and "at column" in message


@pytest.mark.parametrize(
    ("value", "key"),
    [
        (10**400, "parameters.lambda_m"),  # OverflowError in float() before
        ("1e999", "parameters.lambda_m"),
        ("10 ** 400", "parameters.lambda_m"),  # OverflowError while constant-folding
        ("(-8) ** 0.5", "parameters.lambda_m"),  # a complex number while folding
        ("0 ** -1", "parameters.lambda_m"),
    ],
)
def test_out_of_range_numbers_are_a_model_error_naming_the_key(tmp_path, value, key):
    data = variant(lambda d: d["parameters"].__setitem__("lambda_m", value))
    with pytest.raises(ModelError) as refused:
        load_model(_write(tmp_path, data))
    message = str(refused.value)
    assert str(tmp_path / "m.json") in message and key in message, message
    assert len(message) < 1000


def test_an_integer_of_over_4300_digits_is_a_model_error(tmp_path):
    text = json.dumps(RAW).replace('"lambda_m": 8.0', '"lambda_m": ' + "9" * 5000)
    assert "9" * 5000 in text
    with pytest.raises(ModelError) as refused:
        load_model(_write(tmp_path, text.encode()))
    message = str(refused.value)
    assert "parameters.lambda_m" in message and len(message) < 1000


def test_non_utf8_bytes_are_a_model_error_with_line_and_column(tmp_path):
    data = json.dumps(RAW, indent=1).encode().replace(b'"roam"', b'"ro\xe9m"', 1)
    with pytest.raises(ModelError) as refused:
        load_model(_write(tmp_path, data))
    message = str(refused.value)
    assert str(tmp_path / "m.json") in message and "UTF-8" in message and "column" in message


@pytest.mark.parametrize("depth", [2000, 100_000])
def test_deeply_nested_json_is_a_model_error_with_a_column(tmp_path, depth):
    data = b'{"format": "xabsl-dd-model/1", "doc": ' + b"[" * depth + b"]" * depth + b"}"
    with pytest.raises(ModelError) as refused:
        load_model(_write(tmp_path, data))
    message = str(refused.value)
    assert str(tmp_path / "m.json") in message and "nested" in message and "column" in message


def test_nested_values_in_messages_are_shortened(tmp_path):
    deep = []
    for _ in range(40):  # within the nesting limit; its repr would be 4 kB
        deep = [deep, "x" * 100]
    data = variant(lambda d: d["parameters"].__setitem__("lambda_m", deep))
    with pytest.raises(ModelError) as refused:
        load_model(_write(tmp_path, data))
    assert "parameters.lambda_m" in str(refused.value) and len(str(refused.value)) < 1000


def test_a_model_path_that_is_not_a_regular_file_is_a_model_error(tmp_path):
    import os

    os.mkfifo(tmp_path / "fifo.json")
    for path in (tmp_path / "fifo.json", tmp_path / "missing.json", "/dev/zero"):
        with pytest.raises(ModelError) as refused:
            load_model(path)
        assert str(path) in str(refused.value)


def test_xabsl_run_errands_reports_a_broken_model_without_a_traceback(tmp_path, monkeypatch, capsys):
    import xabsl_studio.examples.errands.world as world
    from xabsl_studio.engine.cli import main

    broken = _write(tmp_path, _edit_drive("(" * 163 + "1" + ")" * 163))
    monkeypatch.setattr(world, "_model", lambda path, dt: load_model(broken, dt=dt))
    assert main(["run", "examples/errands", "--duration", "1"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and str(broken) in err and "behaviors.roam.drive" in err
