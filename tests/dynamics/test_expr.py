import math

import pytest

from xabsl_studio.engine.dynamics.expr import (
    RUNTIME,
    Binary,
    ExprError,
    Name,
    Num,
    evaluate,
    fold,
    linear_terms,
    parse,
    substitute,
    to_python,
    unparse,
)

ENV = {"x": 0.5, "y": -2.0, "φ_a": 0.25, "γ_book": 0.9, "α_roam": 0.3}


def compiled(text, env=ENV):
    node = parse(text)
    local = {k: f"_n{i}" for i, k in enumerate(env)}
    src = "def _f(" + ", ".join(local.values()) + "):\n    return " + to_python(node, local) + "\n"
    ns = dict(RUNTIME)
    exec(compile(src, "<test>", "exec"), ns)
    return ns["_f"](*env.values())


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("1 + 2*3", 7.0),
        ("(1 + 2)*3", 9.0),
        ("-x**2", -0.25),  # power binds tighter than unary minus, as in Python
        ("2**-1", 0.5),
        ("10 - 4 - 3", 3.0),
        ("8 / 4 / 2", 1.0),
        ("x > 0.4", 1.0),
        ("y >= 0", 0.0),
        ("max(x, y, 0.1)", 0.5),
        ("min(x, y)", -2.0),
        ("abs(y) + sign(y)", 1.0),
        ("clip(3*x, 0, 1)", 1.0),
        ("where(γ_book > 0, 0.3, 0)", 0.3),
        ("0.8*(1 - abs(φ_a))**2", 0.8 * 0.75**2),
        ("sigmoid(0)", 0.5),
        ("sqrt(-1e-17)", 0.0),
        ("1.5e1 + .5", 15.5),
        ("+x", 0.5),
    ],
)
def test_evaluation_and_compiled_code_agree(text, value):
    assert evaluate(parse(text), ENV) == pytest.approx(value)
    assert compiled(text) == pytest.approx(value)


def test_division_by_zero_is_not_a_crash():
    assert math.isinf(evaluate(parse("1 / (x - x)"), ENV))
    assert math.isinf(compiled("1 / (x - x)"))


@pytest.mark.parametrize(
    ("text", "message", "col"),
    [
        ("0.3 * * γ", "syntax error: expected a number, a name or '(', found '*'", 6),
        ("1 +", "syntax error: expected a number, a name or '(', found end of expression", 3),
        ("(1 + 2", "syntax error: expected ')', found end of expression", 6),
        ("foo(1)", "unknown function 'foo'", 0),
        ("clip(1, 2)", "clip() takes 3 argument(s), got 2", 0),
        ("x.real", "unexpected character '.'", 1),
        ("x @ y", "unexpected character '@'", 2),
        ("1 < x < 2", "expected no second comparison", 6),
        ("   ", "empty expression", 0),
        ("x y", "syntax error: expected an operator or the end, found 'y'", 2),
    ],
)
def test_errors_name_the_problem_and_column(text, message, col):
    with pytest.raises(ExprError) as info:
        parse(text)
    assert message in str(info.value)
    assert info.value.col == col
    assert text in str(info.value)


def test_python_builtins_unreachable():
    with pytest.raises(ExprError, match="unknown function '__import__'"):
        parse("__import__(x)")
    with pytest.raises(ExprError, match="unknown function 'eval'"):
        parse("eval(1)")
    assert RUNTIME["__builtins__"] == {}


def test_non_string_rejected():
    with pytest.raises(ExprError, match="expected an expression string, got int"):
        parse(3)


def test_substitute_and_fold_parameters():
    node = fold(substitute(parse("k*(x - theta) + 2*3"), {"k": Num(8.0), "theta": Num(0.5)}))
    assert unparse(node) == "((8.0 * (x - 0.5)) + 6.0)"


def test_linear_terms_split_drive_into_bias_activations_and_features():
    node = parse("1 - 1.2*max(α_a, α_b) + 1.5*f - 1.2*(α_b + α_c)/2 + 0.3*α_a + 0*γ")
    terms = {k: v[0] for k, v in linear_terms(node, lambda n: n.startswith("α_")).items()}
    assert terms == {
        None: 1.0,
        ("feature", "max(α_a, α_b)"): -1.2,
        ("feature", "f"): 1.5,
        ("name", "α_b"): pytest.approx(-0.6),
        ("name", "α_c"): pytest.approx(-0.6),
        ("name", "α_a"): 0.3,
    }


def test_linear_terms_products_of_names_are_features():
    terms = linear_terms(parse("0.5*α_a*γ"), lambda n: n.startswith("α_"))
    assert {k: v[0] for k, v in terms.items()} == {("feature", "(α_a * γ)"): 0.5}


def test_tree_positions():
    node = parse("x + max(y, 1)")
    assert isinstance(node, Binary) and node.col == 2
    assert isinstance(node.left, Name) and node.left.col == 0
