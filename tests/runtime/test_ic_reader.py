"""The IC reader: kit files round into programs; malformed IC names the token position."""

from __future__ import annotations

import pytest

from tests.kit import KIT, SETS
from xabsl_studio.engine.ir.ic_reader import ICError, read_ic, read_ic_file
from xabsl_studio.engine.ir.model import If, Transition, leaves
from xabsl_studio.engine.types import Kind


@pytest.mark.parametrize("name", SETS)
def test_every_kit_ic_reads(name: str) -> None:
    program = read_ic_file(KIT / name / "expected.ic")
    assert [o.index for o in program.options.values()] == list(range(len(program.options)))
    for option in program.options.values():
        for state in option.states:
            assert [leaf.leaf for leaf in leaves(state.decision)] == list(range(len(list(leaves(state.decision)))))


def test_inference_of_external_declarations() -> None:
    program = read_ic_file(KIT / "demo-approach" / "expected.ic")
    assert program.title == "Demo"
    assert program.inputs["clamp"].params[0].name == "clamp.value"
    assert program.outputs["motion.mode"].enum == "mode"
    assert program.outputs["last_distance"].internal
    assert program.behaviors["stand_up"].params[0].kind is Kind.DECIMAL
    go = program.options["approach"].state("go")
    assert isinstance(go.decision, If)
    stay = list(leaves(go.decision))[-1]
    assert isinstance(stay, Transition) and stay.stay and stay.target == "go"


def test_crlf_lf_and_comments_are_equivalent() -> None:
    text = "0 0 1 main 0 1 s n s 0 0 t s 1 solo main"
    lf = read_ic(text.replace(" ", "\n"))
    crlf = read_ic("// comment\r\n" + text.replace(" ", "\r\n") + " // trailing\r\n")
    assert lf.options["main"].states == crlf.options["main"].states


@pytest.mark.parametrize(
    ("text", "where", "what"),
    [
        ("0 0 1 main 0 1 s n s 0 0 t nowhere 1 solo main", "column 28", "unknown state nowhere"),
        ("0 0 1 main 0\n1 s n s\n0 1 d o ? t s 1 solo main", "line 3, column 9", "expected a decimal expression"),
        ("0 0 1 main 0 1 s n s 0 0 t s", "end of input", "unexpected end"),
        ("0 0 x", "column 5", "number of options"),
    ],
)
def test_malformed_ic_reports_the_token_position(text: str, where: str, what: str) -> None:
    with pytest.raises(ICError) as caught:
        read_ic(text)
    print(caught.value)
    assert where in str(caught.value) and what in str(caught.value)
