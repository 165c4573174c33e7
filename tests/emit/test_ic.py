"""Intermediate code of hand-written behaviors, checked against the layout and rules of §3."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from xabsl_studio.engine.emit.ic import emit_ic, format_number
from xabsl_studio.engine.lang import Compilation

SYMBOLS = """namespace s("S") {
  enum mode { idle, walk };
  float input a;
  bool input b;
  enum mode input m;
  float output out;
  bool output flag;
  enum mode output mo;
  enum phase internal { one, two };
  enum phase internal ph;
  float internal memo;
  float const neg = -5 "mm";
  const pos = 0.50;
}
"""


def ic_of(compile_sources: Callable[..., Compilation], option: str, title: str = "T") -> list[str]:
    compilation = compile_sources(
        {
            "agents.xabsl": f'/*** Title: {title} */\ninclude "s.xabsl";\ninclude "o.xabsl";\nagent ag("A", o);\n',
            "s.xabsl": SYMBOLS,
            "o.xabsl": option,
        }
    )
    assert [d.format() for d in compilation.errors] == []
    assert compilation.program is not None
    text = emit_ic(compilation.program)
    assert text.endswith("\r\n") and "\n" not in text.replace("\r\n", "")
    return text.split("\r\n")


def body(lines: list[str]) -> str:
    return " | ".join(lines)


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (2.0, "2"),
        (-0.0, "0"),
        (0.5, "0.5"),
        (-2.5, "-2.5"),
        (0.0001, "0.0001"),
        (0.00001, "1.0e-05"),
        (0.0000123, "1.23e-05"),
        (-0.000001, "-1.0e-06"),
        (3.14159265358979323846, "3.141592653589793"),
        (1234567890123456.7, "1234567890123456.8"),
        (12345678901234567890.0, "12345678901234567168"),
        (1e26, "100000000000000004764729344"),
        (123456.789, "123456.789"),
    ],
)
def test_number_format_follows_ruby(value: float, text: str) -> None:
    assert format_number(value) == text


def test_header_sections_and_agents_line(compile_sources: Callable[..., Compilation]) -> None:
    lines = ic_of(compile_sources, "option o { initial state s { action { ph = two; memo = 1; } } }", "My Title")
    assert lines[:9] == [
        "// Intermediate code for the agents of My Title",
        "",
        "1",
        "phase 2 phase.one phase.two",
        "2",
        "d memo",
        "e phase ph",
        "",
        "1",
    ]
    assert lines[-3:] == ["1", "ag o", ""]


def test_stay_and_goto_self_are_both_t_self(compile_sources: Callable[..., Compilation]) -> None:
    lines = ic_of(
        compile_sources,
        "option o { initial state s { decision { if (b) goto s; else stay; } action { } } }",
    )
    assert "i | i b | 0 | t s | t s" in body(lines)
    assert body(lines).count("t s") == 2


def test_unary_minus_folds_on_literals_only(compile_sources: Callable[..., Compilation]) -> None:
    lines = ic_of(compile_sources, "option o { initial state s { action { out = -a + - -2 + -0; } } }")
    assert "d out | + | + | - | v 0 | i a | 0 | v 2 | v 0 | t s" in body(lines)


def test_and_or_chains_are_n_ary_also_through_parentheses(compile_sources: Callable[..., Compilation]) -> None:
    lines = ic_of(
        compile_sources,
        "option o { initial state s { action { flag = b && (a > 1 && (b && b)) || b || !b; } } }",
    )
    assert "| 3 | & 4 | i b" in body(lines)


def test_enum_equality_and_inequality(compile_sources: Callable[..., Compilation]) -> None:
    lines = ic_of(compile_sources, "option o { initial state s { action { flag = m != walk; mo = b ? idle : m; } } }")
    text = body(lines)
    assert "b flag | ! | c | i m | 0 | v mode.walk " in text
    assert "e mo | q | i b | 0 | v mode.idle  | i m | 0" in text


def test_constants_are_inlined_as_written_with_their_sign(compile_sources: Callable[..., Compilation]) -> None:
    lines = ic_of(compile_sources, "option o { initial state s { action { out = neg + pos; } } }")
    assert "d out | + | c -5 | c 0.50" in body(lines)


def test_common_tree_and_action_are_copied_into_every_state(compile_sources: Callable[..., Compilation]) -> None:
    lines = ic_of(
        compile_sources,
        """option o {
          common decision { if (b) goto t; else if (a > 1) stay; }
          common action { memo = 1; }
          initial state s { decision { else goto t; } action { out = 2; } }
          state t { action { } }
        }""",
    )
    text = body(lines)
    # state s: common action first, then its own; decision: the common chain, then its own tree
    assert "s | 0 | 2 | d memo | v 1 | d out | v 2 | i | i b | 0 | t t | i | > | i a | 0 | v 1 | t s | t t" in text
    # state t: the common `stay` means t itself; no decision of its own is an implicit stay
    assert "0 | 1 | d memo | v 1 | i | i b | 0 | t t | i | > | i a | 0 | v 1 | t t | t t" in text


def test_option_header_lists_parameters_in_declaration_order(compile_sources: Callable[..., Compilation]) -> None:
    compilation = compile_sources(
        {
            "agents.xabsl": 'include "s.xabsl";\ninclude "o.xabsl";\ninclude "p.xabsl";\nagent ag("A", o);\n',
            "s.xabsl": SYMBOLS,
            "o.xabsl": "option o { initial state s { action { p(y = true, x = a, z = walk); } } }",
            "p.xabsl": "option p { float @x; bool @y; enum mode @z; initial state s { action { } } }",
        }
    )
    assert compilation.program is not None
    text = emit_ic(compilation.program)
    assert "p 3 d p.x b p.y e mode p.z\r\n" in text
    # call-site arguments keep the order they were written in
    assert "o p\r\n3\r\nb p.y\r\nv true\r\nd p.x\r\ni a\r\n0\r\ne mode p.z\r\nv mode.walk \r\n" in text


def test_options_are_sorted_case_insensitively(compile_sources: Callable[..., Compilation]) -> None:
    compilation = compile_sources(
        {
            "agents.xabsl": 'include "s.xabsl";\ninclude "b.xabsl";\ninclude "A2.xabsl";\ninclude "a1.xabsl";\n'
            'agent ag("A", b);\n',
            "s.xabsl": SYMBOLS,
            "b.xabsl": "option b { initial state s { action { A2(); a1(); } } }",
            "A2.xabsl": "option A2 { initial state s { action { } } }",
            "a1.xabsl": "option a1 { initial state s { action { } } }",
        }
    )
    assert compilation.program is not None
    assert list(compilation.program.options) == ["a1", "A2", "b"]
