"""Regression tests for inputs the property tests of test_properties.py once broke the compiler with.

``compile_file``'s contract is that user mistakes, or merely unusual sources, become diagnostics
or programs, never tracebacks; each test here once showed an exception escaping it.
"""

from __future__ import annotations

from collections.abc import Callable

from xabsl_studio.engine.lang import Compilation

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
    from xabsl_studio.engine.emit.ic import emit_ic

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


def _chain_option(levels: int, common: bool = False) -> str:
    # one `if` per line, so that a diagnostic's line tells at which level the parser stopped
    chain = "if (state_time > 1) stay;\nelse " * levels + "stay;"
    if common:
        branches = "if (state_time > 1) goto s;\nelse " * (levels - 1) + "if (state_time > 1) goto s;"
        return f"option o {{\ncommon decision {{\n{branches}\n}}\ninitial state s {{ action {{ }} }} }}\n"
    return f"option o {{ initial state s {{ decision {{\n{chain}\n}} action {{ }} }} }}\n"


def test_decision_trees_nest_up_to_the_limit(compile_sources: Callable[..., Compilation]) -> None:
    from xabsl_studio.engine.lang.parser import MAX_DECISION_DEPTH

    compilation = compile_sources(
        {"agents.xabsl": 'include "o.xabsl";\nagent a("A", o);\n', "o.xabsl": _chain_option(MAX_DECISION_DEPTH)}
    )
    assert compilation.program is not None


def test_a_13000_deep_else_if_chain_fails_fast_at_the_limit(compile_sources: Callable[..., Compilation]) -> None:
    # Issue 18: the parser recursed to the recursion limit (~12,000 levels, 1.3 s of CPU) before
    # "nesting too deep"; it must stop at the limit's first level too many, and say only that.
    from xabsl_studio.engine.lang.parser import MAX_DECISION_DEPTH

    compilation = compile_sources({"o.xabsl": _chain_option(13_000)})
    (error,) = compilation.diagnostics
    assert error.code == "nesting-too-deep" and error.file == "o.xabsl"
    assert error.span is not None and error.span.line == MAX_DECISION_DEPTH + 2
    assert f"{MAX_DECISION_DEPTH}" in error.message


def test_a_deep_common_decision_chain_fails_at_the_limit(compile_sources: Callable[..., Compilation]) -> None:
    from xabsl_studio.engine.lang.parser import MAX_DECISION_DEPTH

    (error,) = compile_sources({"o.xabsl": _chain_option(5_000, common=True)}).diagnostics
    assert error.code == "nesting-too-deep"
    assert error.span is not None and error.span.line == MAX_DECISION_DEPTH + 3


def test_expressions_nest_up_to_the_limit_and_not_beyond(compile_sources: Callable[..., Compilation]) -> None:
    from xabsl_studio.engine.lang.parser import MAX_EXPRESSION_DEPTH

    agents = {"agents.xabsl": 'include "o.xabsl";\nagent a("A", o);\n'}
    # the condition itself is one level: MAX - 1 parentheses and unary operators around `true`
    inner = MAX_EXPRESSION_DEPTH - 1
    for condition in ("(" * inner + "true" + ")" * inner, "!" * (inner - 1) + "(true)"):
        compilation = compile_sources({**agents, "o.xabsl": option_with_decision(condition)})
        assert compilation.program is not None, condition[:20]
    for condition in ("(" * (inner + 1) + "true" + ")" * (inner + 1), "!" * (inner + 1) + "true"):
        (error,) = compile_sources({"o.xabsl": option_with_decision(condition)}).diagnostics
        assert error.code == "nesting-too-deep"
        assert error.span is not None and error.span.col == option_with_decision("").index("(") + 3 + inner
