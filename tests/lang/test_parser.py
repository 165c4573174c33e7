"""Grammar of §1.3: one test per production, plus the syntax errors and recovery of the parser."""

from __future__ import annotations

import pytest

from xabsl_studio.engine.lang import ast
from xabsl_studio.engine.lang.diagnostics import Diagnostics
from xabsl_studio.engine.lang.parser import parse_file


def parse(text: str) -> tuple[ast.SourceFile, Diagnostics]:
    diagnostics = Diagnostics()
    return parse_file("f.xabsl", text, diagnostics), diagnostics


def parse_ok(text: str) -> ast.SourceFile:
    source, diagnostics = parse(text)
    assert [d.format() for d in diagnostics] == []
    return source


def first_error(text: str) -> tuple[int, int, str]:
    _, diagnostics = parse(text)
    assert diagnostics.items, "expected a syntax error"
    d = diagnostics.items[0]
    return d.span.line, d.span.col, d.code


def option(body: str, params: str = "") -> ast.OptionDecl:
    source = parse_ok(f"option o {{ {params} {body} }}")
    assert source.option is not None
    return source.option


def expr(text: str) -> ast.Expr:
    decl = option(f"initial state s {{ action {{ out = {text}; }} }}")
    action = decl.states[0].actions[0]
    assert isinstance(action, ast.Assign)
    return action.value


def shape(e: ast.Expr) -> str:
    """A parenthesised rendering that shows how the parser grouped an expression."""
    match e:
        case ast.BinaryOp(op=op, left=l, right=r):
            return f"({shape(l)} {op} {shape(r)})"
        case ast.UnaryOp(op=op, operand=o):
            return f"({op}{shape(o)})"
        case ast.CondOp(condition=c, then=t, otherwise=o):
            return f"({shape(c)} ? {shape(t)} : {shape(o)})"
        case ast.Paren(inner=i):
            return shape(i)
        case ast.NumberLit(text=t):
            return t
        case ast.Ident(name=n):
            return n
        case ast.BoolLit(value=v):
            return str(v).lower()
        case ast.Builtin(name=n):
            return n
        case ast.Call(name=n, args=args):
            return f"{n.text}({', '.join(a.name.text + '=' + shape(a.value) for a in args)})"
    raise AssertionError(e)


# ------------------------------------------------------------------ file, include, agent


def test_file_title_comment_includes_then_one_declaration() -> None:
    source = parse_ok('/*** Title: T */ include "a.xabsl"; include "b/c.xabsl"; agent x("X", o);')
    assert source.title_comment == " Title: T "
    assert [i.path for i in source.includes] == ["a.xabsl", "b/c.xabsl"]
    assert [a.name.text for a in source.agents] == ["x"]


def test_empty_file_is_legal() -> None:
    assert parse_ok("// nothing here\n").option is None


def test_agent_list_with_doc_comments() -> None:
    source = parse_ok('/** first */ agent a("A", o1); agent b("B", o2);')
    assert [(a.name.text, a.title, a.root.text, a.doc) for a in source.agents] == [
        ("a", "A", "o1", "first"),
        ("b", "B", "o2", None),
    ]


def test_include_after_a_declaration_is_an_error() -> None:
    assert first_error('agent a("A", o);\ninclude "x.xabsl";')[:2] == (2, 1)


def test_nothing_may_follow_an_option() -> None:
    line, _, code = first_error('option o { initial state s { action { } } }\nagent a("A", o);')
    assert (line, code) == (2, "syntax-error")


# ------------------------------------------------------------------ namespaces


def test_namespace_with_every_item_kind() -> None:
    source = parse_ok(
        """/** doc */ namespace n("Title") {
          const a = 1;
          float const b = -2.5 "mm";
          enum e { x, y };
          enum f internal { z };
          float input i [0..1] "mm";
          input untyped;
          bool output o;
          enum e internal s;
          float input fn "mm" ( float p; bool q; enum e r; );
        }"""
    )
    namespace = source.namespace
    assert namespace is not None and namespace.title == "Title" and namespace.doc == "doc"
    kinds = [type(i).__name__ for i in namespace.items]
    assert kinds == [
        "ConstDecl",
        "ConstDecl",
        "EnumDecl",
        "EnumDecl",
        "SymbolDecl",
        "SymbolDecl",
        "SymbolDecl",
        "SymbolDecl",
        "SymbolDecl",
    ]
    const_b = namespace.items[1]
    assert isinstance(const_b, ast.ConstDecl) and (const_b.negative, const_b.text, const_b.unit) == (True, "2.5", "mm")
    internal_enum = namespace.items[3]
    assert isinstance(internal_enum, ast.EnumDecl) and internal_enum.internal
    untyped = namespace.items[5]
    assert isinstance(untyped, ast.SymbolDecl) and untyped.type.kind == "decimal"
    internal_symbol = namespace.items[7]
    assert isinstance(internal_symbol, ast.SymbolDecl) and internal_symbol.io == "internal"
    function = namespace.items[8]
    assert isinstance(function, ast.SymbolDecl) and [p.name.text for p in function.params or []] == ["p", "q", "r"]


def test_behavior_prototypes_have_braces_and_no_semicolon() -> None:
    source = parse_ok('namespace b("B") { behavior stand { } /** w */ behavior walk { float speed "mm/s"; } }')
    assert source.namespace is not None
    walk = source.namespace.items[1]
    assert isinstance(walk, ast.BehaviorDecl) and walk.doc == "w" and walk.params[0].unit == "mm/s"


def test_symbol_needs_input_output_or_internal() -> None:
    assert first_error('namespace n("N") {\n  float speed;\n}')[:2] == (2, 9)


def test_enum_cannot_be_input() -> None:
    line, col, code = first_error('namespace n("N") {\n  enum e input { a };\n}')
    assert (line, col, code) == (2, 10, "enum-io")


def test_keyword_as_enum_element_is_a_syntax_error() -> None:
    assert first_error('namespace n("N") { enum e { a, initial }; }')[1] == 32


# ------------------------------------------------------------------ options and states


def test_option_parameters_common_decision_common_action_states() -> None:
    decl = option(
        """common decision { if (a) goto s; else if (b) stay; }
        common action { out = 1; }
        initial target state s capacity 2 { decision { else stay; } action { } }
        state t synchronized { action { } }
        state u synchronized 3 { action { } }""",
        params='float @p [0..1] "mm"; bool @q; enum e @r;',
    )
    assert [p.name.text for p in decl.params] == ["@p", "@q", "@r"]
    assert decl.common_decision is not None and len(decl.common_decision.branches) == 2
    assert decl.common_action is not None and len(decl.common_action) == 1
    s, t, u = decl.states
    assert (s.initial, s.target, s.coop, s.coop_count, s.leading_else) == (True, True, "c", 2, True)
    assert (t.coop, t.coop_count, u.coop, u.coop_count) == ("s", 0, "s", 3)


def test_common_action_without_common_decision() -> None:
    decl = option("common action { out = 2; } initial state s { action { } }")
    assert decl.common_decision is None and decl.common_action is not None


def test_state_without_decision() -> None:
    assert option("initial state s { action { } }").states[0].decision is None


def test_action_block_is_mandatory() -> None:
    assert first_error("option o {\n initial state s {\n }\n}")[:2] == (3, 2)


def test_decision_trees_with_braces_goto_stay_and_docs() -> None:
    decl = option(
        """initial state s { decision { { /** why */ if (a) { goto t; } /** otherwise */ else stay; } }
        action { } } state t { action { } }"""
    )
    tree = decls_tree = decl.states[0].decision
    assert isinstance(tree, ast.IfElse) and tree.doc == "why" and tree.else_doc == "otherwise"
    assert isinstance(decls_tree.then, ast.Goto) and isinstance(decls_tree.otherwise, ast.Stay)


def test_if_needs_else_in_a_state_decision() -> None:
    assert first_error("option o { initial state s { decision {\n if (a) goto s;\n } action { } } }")[:2] == (3, 2)


def test_common_decision_chain_has_no_final_else_but_nested_trees_do() -> None:
    decl = option(
        """common decision { if (a) if (b) goto s; else stay; else if (c) goto s; }
        initial state s { decision { else stay; } action { } }"""
    )
    assert decl.common_decision is not None
    first, second = decl.common_decision.branches
    assert isinstance(first.then, ast.IfElse) and isinstance(second.then, ast.Goto)


def test_doc_comment_before_state_is_a_syntax_error_at_the_state() -> None:
    line, col, code = first_error("option o {\n  /** no */\n  initial state s { action { } }\n}")
    assert (line, col, code) == (3, 3, "syntax-error")


def test_doc_comment_before_an_action_is_a_syntax_error_at_the_comment() -> None:
    assert first_error("option o { initial state s { action {\n /** no */ out = 1; } } }")[:2] == (2, 2)


def test_actions_assignments_and_calls() -> None:
    decl = option("initial state s { action { out = 1; walk(speed = 2, turn = x); t option(); u behavior(a = 1); } }")
    assign, walk, t, u = decl.states[0].actions
    assert isinstance(assign, ast.Assign)
    assert isinstance(walk, ast.CallAction) and [a.name.text for a in walk.args] == ["speed", "turn"]
    assert isinstance(t, ast.CallAction) and t.explicit == "option"
    assert isinstance(u, ast.CallAction) and u.explicit == "behavior"


# ------------------------------------------------------------------ expressions


@pytest.mark.parametrize(
    ("text", "grouping"),
    [
        ("a + b * c - d", "((a + (b * c)) - d)"),
        ("a - b - c", "((a - b) - c)"),
        ("a / b % c", "((a / b) % c)"),
        ("-a * b", "((-a) * b)"),
        ("- -2", "(-(-2))"),
        ("!a && b || c && d", "(((!a) && b) || (c && d))"),
        ("a < b + 1 && c >= d", "((a < (b + 1)) && (c >= d))"),
        ("!x == y", "((!x) == y)"),
        ("c ? a + 1 : b", "(c ? (a + 1) : b)"),
        ("c ? (d ? 1 : 2) : 3", "(c ? (d ? 1 : 2) : 3)"),
        ("c ? d ? 1 : 2 : 3", "(c ? (d ? 1 : 2) : 3)"),
        ("c || d ? 1 : 2", "((c || d) ? 1 : 2)"),
        ("f(x = 1, y = g(z = 2)) + state_time", "(f(x=1, y=g(z=2)) + state_time)"),
        ("true && action_done || conflict", "((true && action_done) || conflict)"),
    ],
)
def test_operator_precedence_and_associativity(text: str, grouping: str) -> None:
    assert shape(expr(text)) == grouping


def test_comparisons_are_non_associative() -> None:
    text = "option o { initial state s { action { out = a < b < c; } } }"
    assert first_error(text)[1] == text.rindex("<") + 1


def test_conditional_else_branch_cannot_nest_without_parentheses() -> None:
    text = "option o { initial state s { action { out = c ? 1 : d ? 2 : 3; } } }"
    assert first_error(text)[1] == text.rindex("?") + 1


def test_missing_semicolon_is_reported_at_the_next_token() -> None:
    assert first_error("option o { initial state s { action {\n out = 1\n x = 2; } } }")[:2] == (3, 2)


def test_unexpected_end_of_file() -> None:
    assert first_error("option o { initial state s { action { } }")[2] == "unexpected-end-of-file"


# ------------------------------------------------------------------ recovery


def test_recovery_reports_one_error_per_broken_state() -> None:
    _, diagnostics = parse(
        """option o {
          initial state a { action { out = ; } }
          state b { action { ok = 1; } }
          state c { decision { if (x) goto a; } action { } }
          state d { action { } }
        }"""
    )
    assert [(d.span.line, d.code) for d in diagnostics] == [(2, "syntax-error"), (4, "syntax-error")]


def test_recovery_keeps_the_good_states() -> None:
    source, _ = parse("option o { initial state a { action { out = ; } } state b { action { } } }")
    assert source.option is not None and [s.name.text for s in source.option.states] == ["b"]


def test_recovery_in_namespaces_and_agents() -> None:
    _, diagnostics = parse('namespace n("N") {\n float input a\n bool input b;\n float input c c;\n}')
    assert [d.span.line for d in diagnostics] == [3, 4]
    _, diagnostics = parse('agent a("A" o);\nagent b("B", o);\nagent c(, o);')
    assert [d.span.line for d in diagnostics] == [1, 3]
