"""Tokenizer for XABSL 2 source files (§1.2), quirks of the original ``tokenizer.rb`` included.

Lexical facts are tables (:data:`KEYWORDS`, :data:`OPERATORS`) so tests and the editor can read
them. The quirks, each reproduced on purpose:

* keyword-run rule: the maximal run ``[A-Za-z_][A-Za-z0-9_.-]*`` is a keyword only if the whole
  run is one, so ``state_time-500`` lexes as the identifier ``state_time`` (then ``-``, ``500``);
* identifiers may start with ``@`` (option parameters) and contain dots (``ball.distance``);
* ``/*** */`` is the title comment, ``/** */`` a doc comment (a token the grammar places), plain
  ``/* */`` is discarded; ``/**/`` opens a doc comment; an unterminated comment is an error at
  the line where it starts;
* a ``//`` comment needs a terminating newline, else it degrades into ``/`` tokens;
* numbers are ``[0-9]+(\\.[0-9]*)?``: no leading dot, no exponent;
* ``[ ... ]`` is one RANGE token of free text; strings have no escapes;
* CRLF and LF are both line ends; bytes that are not UTF-8 are read as Latin-1.
"""

from __future__ import annotations

import enum
import re
from typing import NamedTuple

from xabsl_studio.engine.lang.diagnostics import Diagnostics
from xabsl_studio.engine.types import Span


class TokenType(enum.Enum):
    """The kinds of token (``value`` is how messages name them)."""

    IDENTIFIER = "identifier"
    KEYWORD = "keyword"
    NUMBER = "number"
    STRING = "string"
    RANGE = "range"
    OPERATOR = "operator"
    DOC_COMMENT = "doc comment"
    INITIAL_COMMENT = "title comment"
    EOF = "end of file"


#: Reserved words (§1.2). ``function`` is reserved but unused by the grammar.
KEYWORDS = frozenset(
    [
        "true",
        "false",
        "option",
        "action",
        "initial",
        "target",
        "state",
        "common",
        "decision",
        "stay",
        "goto",
        "if",
        "else",
        "state_time",
        "option_time",
        "action_done",
        "agent",
        "function",
        "enum",
        "input",
        "output",
        "bool",
        "float",
        "const",
        "namespace",
        "behavior",
        "include",
        "internal",
        "capacity",
        "synchronized",
        "conflict",
    ]
)

#: Two-character operators are tried before single characters.
TWO_CHAR_OPERATORS = ("<=", ">=", "==", "!=", "&&", "||")
SINGLE_CHAR_OPERATORS = frozenset("%!<>[]{}();|+-*/=,?:")
OPERATORS = frozenset(TWO_CHAR_OPERATORS) | SINGLE_CHAR_OPERATORS


class Token(NamedTuple):
    """One token with its exact text and position (a NamedTuple: cheap to build, see Span)."""

    type: TokenType
    text: str
    span: Span

    def is_op(self, text: str) -> bool:
        """Whether this is the operator ``text``."""
        return self.type is TokenType.OPERATOR and self.text == text

    def is_kw(self, text: str) -> bool:
        """Whether this is the keyword ``text``."""
        return self.type is TokenType.KEYWORD and self.text == text

    def describe(self) -> str:
        """How a message names this token: ``';'``, ``keyword 'state'``, ``end of file``."""
        if self.type is TokenType.EOF:
            return "end of file"
        if self.type is TokenType.OPERATOR:
            return f"'{self.text}'"
        if self.type in (TokenType.DOC_COMMENT, TokenType.INITIAL_COMMENT):
            return f"a {self.type.value}"
        shown = self.text if len(self.text) <= 40 else self.text[:37] + "..."
        return f"{self.type.value} '{shown}'"


def decode_source(data: bytes) -> str:
    """Source bytes to text: UTF-8 when valid, else Latin-1 (the original reads bytes)."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def _span_at(text: str, file: str, start: int, end: int) -> Span:
    """The span of ``text[start:end]``, lines counted from the beginning (for the rare tokens)."""
    line = text.count("\n", 0, start) + 1
    col = start - (text.rfind("\n", 0, start) + 1) + 1
    newlines = text.count("\n", start, end)
    if not newlines:
        return Span(file, line, col, line, col + end - start, start, end)
    return Span(file, line, col, line + newlines, end - text.rfind("\n", start, end), start, end)


#: One pattern for every token start; ``lastgroup`` names the rule that matched. Semantically the
#: order is the tokenizer's priority: a ``//`` comment only counts with its newline (else ``/`` is
#: an operator), ``/*`` opens a comment before ``/`` is an operator, two-character operators win;
#: rules that cannot start alike are ordered by frequency (blanks and words first).
_TOKEN = re.compile(
    r"""(?P<space>[ \t\r\n\f\v]+)
      | (?P<word>[A-Za-z_][A-Za-z0-9_.\-]*)
      | (?P<range>\[[^\]]*\])
      | (?P<operator><=|>=|==|!=|&&|\|\||[%!<>\[\]{}();|+\-*=,?:])
      | (?P<number>[0-9]+(?:\.[0-9]*)?)
      | (?P<parameter>@[A-Za-z_][A-Za-z0-9_.]*)
      | (?P<string>"[^"]*")
      | (?P<line_comment>//[^\n]*\n)
      | (?P<block_comment>/\*)
      | (?P<slash>/)""",
    re.VERBOSE,
)
_KIND = {
    "parameter": TokenType.IDENTIFIER,
    "number": TokenType.NUMBER,
    "string": TokenType.STRING,
    "range": TokenType.RANGE,
    "operator": TokenType.OPERATOR,
    "slash": TokenType.OPERATOR,
}
#: Rules whose text may span lines (the others never contain a newline).
_MULTILINE = frozenset({"string", "range"})


#: What a declared name (a namespace, an option) may be: one word that is no keyword.
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_.]*")


def is_identifier(text: str) -> bool:
    """Whether ``text`` lexes as one identifier (``basic_behaviors``; not ``basic-behaviors``, not ``option``)."""
    return _NAME.fullmatch(text) is not None and text not in KEYWORDS


def tokenize(text: str, file: str, diagnostics: Diagnostics) -> list[Token]:
    """Split ``text`` into tokens; lexical errors go to ``diagnostics``.

    An illegal character is reported and skipped; an unterminated comment is reported at its
    start and ends the token stream. The list always ends with an EOF token.

    This is the front end's hottest loop (one pass per token of a 200-file set): the current
    line and its start are tracked from the newlines of blanks, comments and multi-line tokens,
    so a one-line token's span is plain arithmetic, and tokens and spans are built with
    ``tuple.__new__`` (what their NamedTuple constructors call, without the extra call).
    """
    tokens: list[Token] = []
    append = tokens.append
    match_token = _TOKEN.match
    new = tuple.__new__
    count = text.count
    keywords = KEYWORDS
    keyword, identifier = TokenType.KEYWORD, TokenType.IDENTIFIER
    pos = 0
    length = len(text)
    line = 1
    line_start = 0  # offset of the first character of `line`

    while pos < length:
        match = match_token(text, pos)
        if match is None:
            end = pos + 1
            diagnostics.add(
                "illegal-character", f"illegal character {text[pos]!r} encountered", _span_at(text, file, pos, end)
            )
            pos = end
            continue
        rule = match.lastgroup
        end = match.end()
        if rule == "space":
            newlines = count("\n", pos, end)
            if newlines:
                line += newlines
                line_start = text.rfind("\n", pos, end) + 1
            pos = end
            continue
        if rule == "word":
            word = match.group()
            if word in keywords:
                kind = keyword
            else:
                kind = identifier
                # keyword-run rule: a run that is no keyword lexes as the identifier before any '-'
                dash = word.find("-")
                if dash >= 0:
                    word, end = word[:dash], pos + dash
            col = pos - line_start + 1
            append(new(Token, (kind, word, new(Span, (file, line, col, line, col + end - pos, pos, end)))))
            pos = end
            continue
        if rule == "line_comment":
            line += 1
            line_start = end
            pos = end
            continue
        if rule == "block_comment":
            if text.startswith("/***", pos):
                comment, body = TokenType.INITIAL_COMMENT, pos + 4
            elif text.startswith("/**", pos):
                comment, body = TokenType.DOC_COMMENT, pos + 3
            else:
                comment, body = None, pos + 2
            close = text.find("*/", body)
            if close < 0:
                diagnostics.add(
                    "unterminated-comment",
                    "end-of-comment missing: '*/' never comes",
                    _span_at(text, file, pos, pos + 2),
                )
                pos = length
                break
            end = close + 2
        elif rule not in _MULTILINE:  # a one-line token
            assert rule is not None
            col = pos - line_start + 1
            span = new(Span, (file, line, col, line, col + end - pos, pos, end))
            append(new(Token, (_KIND[rule], match.group(), span)))
            pos = end
            continue
        else:
            comment = _KIND[rule]
        # a token that may span lines: a comment, a string or a range
        col = pos - line_start + 1
        newlines = count("\n", pos, end)
        if newlines:
            end_line = line + newlines
            end_start = text.rfind("\n", pos, end) + 1
            span = Span(file, line, col, end_line, end - end_start + 1, pos, end)
            line, line_start = end_line, end_start
        else:
            span = Span(file, line, col, line, col + end - pos, pos, end)
        if comment is not None:
            append(Token(comment, text[pos:end], span))
        pos = end
    at = min(pos, length)
    tokens.append(Token(TokenType.EOF, "", _span_at(text, file, at, at)))
    return tokens


def doc_text(token: Token) -> str:
    """The text of a ``/** */`` or ``/*** */`` comment without the markers, tidied per line."""
    inner = token.text[4:-2] if token.type is TokenType.INITIAL_COMMENT else token.text[3:-2]
    lines = [line.strip().lstrip("*").strip() for line in inner.replace("\r\n", "\n").split("\n")]
    return "\n".join(line for line in lines if line).strip()
