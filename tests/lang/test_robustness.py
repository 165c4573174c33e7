"""Regression tests for inputs the property tests of test_properties.py once broke the compiler with.

``compile_file``'s contract is that user mistakes, or merely unusual sources, become diagnostics
or programs, never tracebacks; each test here once showed an exception escaping it.
"""

from __future__ import annotations

from collections.abc import Callable

from engine.lang import Compilation

SYMBOLS = 'namespace s("S") { float output x; }\n'


def option_with_decision(condition: str) -> str:
    return f"option o {{ initial state s {{ decision {{ if ({condition}) stay; else stay; }} action {{ }} }} }}\n"


def test_nul_byte_in_include_path_is_a_diagnostic(compile_sources: Callable[..., Compilation]) -> None:
    # os.path.realpath raises ValueError("embedded null byte") in loader.visit
    compilation = compile_sources({"agents.xabsl": 'include "a\x00b.xabsl";\n'})
    assert [d.code for d in compilation.errors] == ["missing-include-file"]


def test_long_else_if_chain_does_not_overflow_the_stack(compile_sources: Callable[..., Compilation]) -> None:
    # parser.parse_dtree recurses once per 'else if': ~980 levels hit the recursion limit
    chain = "if (state_time > 1) stay; else " * 1000 + "stay;"
    compilation = compile_sources(
        {
            "agents.xabsl": 'include "o.xabsl";\nagent a("A", o);\n',
            "o.xabsl": f"option o {{ initial state s {{ decision {{ {chain} }} action {{ }} }} }}\n",
        }
    )
    assert compilation.program is not None


def test_long_and_chain_does_not_overflow_the_stack(compile_sources: Callable[..., Compilation]) -> None:
    # check.expression/binary/logical recurse once per '&&': ~330 operands hit the limit
    compilation = compile_sources(
        {
            "agents.xabsl": 'include "o.xabsl";\nagent a("A", o);\n',
            "o.xabsl": option_with_decision(" && ".join(["true"] * 400)),
        }
    )
    assert compilation.program is not None


def test_long_sum_does_not_overflow_the_stack(compile_sources: Callable[..., Compilation]) -> None:
    # check.expression/binary recurse once per '+': ~500 operands hit the limit
    compilation = compile_sources(
        {
            "agents.xabsl": 'include "o.xabsl";\nagent a("A", o);\n',
            "o.xabsl": option_with_decision(" + ".join(["1"] * 600) + " > 0"),
        }
    )
    assert compilation.program is not None


def test_nested_parentheses_give_a_result_not_a_recursion_error(
    compile_sources: Callable[..., Compilation],
) -> None:
    # parser.parse_expression -> parse_binary (x5 levels) -> parse_unary per '(':
    # ~110 nested parentheses hit the recursion limit
    depth = 150
    compilation = compile_sources(
        {
            "agents.xabsl": 'include "o.xabsl";\nagent a("A", o);\n',
            "o.xabsl": option_with_decision("(" * depth + "true" + ")" * depth),
        }
    )
    assert compilation.program is not None


def test_options_differing_only_in_case_are_ordered_independently_of_include_order(
    compile_sources: Callable[..., Compilation],
) -> None:
    # __init__.compile_file sorts options by name.lower() only; the tie keeps the include order,
    # so the IC (option order, hence option indices) changes when include lines are swapped.
    # Same for internal symbols / internal enums sorted by lower-cased name in emit.ic.
    from engine.emit.ic import emit_ic

    options = {
        "Foo.xabsl": "option Foo { initial state s { action { } } }\n",
        "foo.xabsl": "option foo { initial state s { action { Foo(); } } }\n",
    }
    ics = []
    for order in (["Foo.xabsl", "foo.xabsl"], ["foo.xabsl", "Foo.xabsl"]):
        agents = "".join(f'include "{name}";\n' for name in order) + 'agent a("A", foo);\n'
        compilation = compile_sources({"agents.xabsl": agents, **options})
        assert compilation.program is not None
        ics.append(emit_ic(compilation.program))
    assert ics[0] == ics[1]


def test_nesting_beyond_any_limit_is_a_diagnostic(compile_sources: Callable[..., Compilation]) -> None:
    depth = 4000
    compilation = compile_sources({"o.xabsl": option_with_decision("(" * depth + "true" + ")" * depth)})
    (error,) = compilation.errors
    assert error.code == "nesting-too-deep" and error.file == "o.xabsl"
