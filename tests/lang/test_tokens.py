"""Tokenizer rules of §1.2, one test per rule or quirk."""

from __future__ import annotations

from xabsl_studio.engine.lang.diagnostics import Diagnostics
from xabsl_studio.engine.lang.tokens import KEYWORDS, TokenType, doc_text, tokenize


def lex(text: str) -> tuple[list[tuple[str, str]], Diagnostics]:
    diagnostics = Diagnostics()
    tokens = tokenize(text, "f.xabsl", diagnostics)
    assert tokens[-1].type is TokenType.EOF
    return [(t.type.name, t.text) for t in tokens[:-1]], diagnostics


def test_keyword_table_holds_the_reserved_words() -> None:
    assert {"state_time", "option_time", "action_done", "conflict", "capacity", "synchronized"} <= KEYWORDS
    assert "function" in KEYWORDS and "decimal" not in KEYWORDS


def test_keyword_only_when_the_whole_run_is_one() -> None:
    tokens, _ = lex("state_time-500 state_time - 500")
    assert tokens == [
        ("IDENTIFIER", "state_time"),
        ("OPERATOR", "-"),
        ("NUMBER", "500"),
        ("KEYWORD", "state_time"),
        ("OPERATOR", "-"),
        ("NUMBER", "500"),
    ]


def test_dotted_and_at_identifiers() -> None:
    tokens, _ = lex("ball.distance @stop_at @a.b game.state.ready")
    assert tokens == [
        ("IDENTIFIER", "ball.distance"),
        ("IDENTIFIER", "@stop_at"),
        ("IDENTIFIER", "@a.b"),
        ("IDENTIFIER", "game.state.ready"),
    ]


def test_keyword_prefix_is_an_identifier() -> None:
    tokens, _ = lex("states initial_pose truex")
    assert [t[0] for t in tokens] == ["IDENTIFIER"] * 3


def test_numbers_have_no_leading_dot_and_no_exponent() -> None:
    tokens, _ = lex("5. 007 1.5E3 0.25")
    assert tokens == [
        ("NUMBER", "5."),
        ("NUMBER", "007"),
        ("NUMBER", "1.5"),
        ("IDENTIFIER", "E3"),
        ("NUMBER", "0.25"),
    ]


def test_title_doc_and_plain_comments() -> None:
    tokens, _ = lex("/*** Title: T */ /** doc */ /* gone */ x")
    assert [t[0] for t in tokens] == ["INITIAL_COMMENT", "DOC_COMMENT", "IDENTIFIER"]


def test_empty_comment_opens_a_doc_comment() -> None:
    # `/**/` is `/**` followed by text up to the next `*/`
    tokens, _ = lex("/**/ a /* b */ c")
    assert tokens == [("DOC_COMMENT", "/**/ a /* b */"), ("IDENTIFIER", "c")]


def test_line_comment_needs_a_newline() -> None:
    assert lex("a // note\nb")[0] == [("IDENTIFIER", "a"), ("IDENTIFIER", "b")]
    # on the last line without newline it degrades into '/' tokens
    assert lex("a // x")[0] == [("IDENTIFIER", "a"), ("OPERATOR", "/"), ("OPERATOR", "/"), ("IDENTIFIER", "x")]


def test_unterminated_comment_is_reported_where_it_starts() -> None:
    _, diagnostics = lex("a\n  /* never\nclosed")
    (d,) = diagnostics.items
    assert d.code == "unterminated-comment" and (d.span.line, d.span.col) == (2, 3)


def test_strings_and_ranges_are_single_tokens() -> None:
    tokens, _ = lex('"mm/s" [0..1000] [..] [mm]')
    assert tokens == [("STRING", '"mm/s"'), ("RANGE", "[0..1000]"), ("RANGE", "[..]"), ("RANGE", "[mm]")]


def test_two_char_operators_before_single() -> None:
    tokens, _ = lex("<= >= == != && || < > ! = % ? :")
    assert [t[1] for t in tokens] == ["<=", ">=", "==", "!=", "&&", "||", "<", ">", "!", "=", "%", "?", ":"]


def test_illegal_character_is_reported_and_skipped() -> None:
    tokens, diagnostics = lex("a # b")
    assert tokens == [("IDENTIFIER", "a"), ("IDENTIFIER", "b")]
    (d,) = diagnostics.items
    assert d.code == "illegal-character" and d.span.col == 3


def test_crlf_and_lf_give_the_same_lines_and_columns() -> None:
    lf = tokenize("a\n  b\nc", "f", Diagnostics())
    crlf = tokenize("a\r\n  b\r\nc", "f", Diagnostics())
    assert [(t.span.line, t.span.col) for t in lf] == [(t.span.line, t.span.col) for t in crlf]
    assert (crlf[1].span.line, crlf[1].span.col) == (2, 3)


def test_non_ascii_in_comments_is_harmless() -> None:
    tokens, diagnostics = lex("// Grüße\n/* ça va */ x")
    assert tokens == [("IDENTIFIER", "x")] and not diagnostics.items


def test_spans_carry_offsets_for_the_editor() -> None:
    tokens = tokenize("ab  cd", "f", Diagnostics())
    assert (tokens[1].span.start, tokens[1].span.end, tokens[1].span.end_col) == (4, 6, 7)


def test_doc_text_strips_markers_and_stars() -> None:
    tokens = tokenize("/**\n * Walks.\n * Fast.\n */", "f", Diagnostics())
    assert doc_text(tokens[0]) == "Walks.\nFast."
