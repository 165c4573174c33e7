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

from engine.lang.diagnostics import Diagnostics
from engine.types import Span


class TokenType(enum.Enum):
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
        return self.type is TokenType.OPERATOR and self.text == text

    def is_kw(self, text: str) -> bool:
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


class _Positions:
    """Offsets -> (line, column), for offsets visited in increasing order.

    Tokens come in source order, so the line is tracked incrementally: the newlines between the
    last offset and the next one are counted with ``str.count`` (C speed) instead of searching a
    line table per token; this was the tokenizer's largest cost on 200 KB behavior sets.
    """

    __slots__ = ("line", "line_start", "offset", "text")

    def __init__(self, text: str) -> None:
        self.text = text
        self.line = 1
        self.line_start = 0
        self.offset = 0

    def position(self, offset: int) -> tuple[int, int]:
        if offset < self.offset:  # rare: restart (only an error span could look back)
            self.line, self.line_start, self.offset = 1, 0, 0
        newlines = self.text.count("\n", self.offset, offset)
        if newlines:
            self.line += newlines
            self.line_start = self.text.rfind("\n", self.offset, offset) + 1
        self.offset = offset
        return self.line, offset - self.line_start + 1


#: One pattern for every token start; ``lastgroup`` names the rule that matched. The order is
#: the tokenizer's priority: a ``//`` comment only counts with its newline (else ``/`` is an
#: operator), ``/*`` opens a comment before ``/`` is an operator, two-character operators win.
_TOKEN = re.compile(
    r"""(?P<space>[ \t\r\n\f\v]+)
      | (?P<line_comment>//[^\n]*\n)
      | (?P<block_comment>/\*)
      | (?P<word>[A-Za-z_][A-Za-z0-9_.\-]*)
      | (?P<parameter>@[A-Za-z_][A-Za-z0-9_.]*)
      | (?P<number>[0-9]+(?:\.[0-9]*)?)
      | (?P<string>"[^"]*")
      | (?P<range>\[[^\]]*\])
      | (?P<operator><=|>=|==|!=|&&|\|\||[%!<>\[\]{}();|+\-*/=,?:])""",
    re.VERBOSE,
)
_KIND = {
    "parameter": TokenType.IDENTIFIER,
    "number": TokenType.NUMBER,
    "string": TokenType.STRING,
    "range": TokenType.RANGE,
    "operator": TokenType.OPERATOR,
}


def tokenize(text: str, file: str, diagnostics: Diagnostics) -> list[Token]:
    """Split ``text`` into tokens; lexical errors go to ``diagnostics``.

    An illegal character is reported and skipped; an unterminated comment is reported at its
    start and ends the token stream. The list always ends with an EOF token.
    """
    positions = _Positions(text)
    tokens: list[Token] = []
    append = tokens.append
    match_token = _TOKEN.match
    pos = 0
    length = len(text)

    def span(start: int, end: int) -> Span:
        line, col = positions.position(start)
        if text.find("\n", start, end) < 0:  # most tokens: the end is on the same line
            return Span(file, line, col, line, col + end - start, start, end)
        end_line = line + text.count("\n", start, end)
        end_col = end - text.rfind("\n", start, end)
        return Span(file, line, col, end_line, end_col, start, end)

    while pos < length:
        match = match_token(text, pos)
        if match is None:
            end = pos + 1
            diagnostics.add("illegal-character", f"illegal character {text[pos]!r} encountered", span(pos, end))
            pos = end
            continue
        rule = match.lastgroup
        end = match.end()
        if rule == "space" or rule == "line_comment":
            pos = end
            continue
        if rule == "word":
            word = match.group()
            if word in KEYWORDS:
                append(Token(TokenType.KEYWORD, word, span(pos, end)))
            else:
                # keyword-run rule: a run that is no keyword lexes as the identifier before any '-'
                dash = word.find("-")
                if dash >= 0:
                    word, end = word[:dash], pos + dash
                append(Token(TokenType.IDENTIFIER, word, span(pos, end)))
            pos = end
            continue
        if rule == "block_comment":
            if text.startswith("/***", pos):
                kind, body = TokenType.INITIAL_COMMENT, pos + 4
            elif text.startswith("/**", pos):
                kind, body = TokenType.DOC_COMMENT, pos + 3
            else:
                kind, body = None, pos + 2
            close = text.find("*/", body)
            if close < 0:
                diagnostics.add("unterminated-comment", "end-of-comment missing: '*/' never comes", span(pos, pos + 2))
                pos = length
                break
            if kind is not None:
                append(Token(kind, text[pos : close + 2], span(pos, close + 2)))
            pos = close + 2
            continue
        assert rule is not None
        append(Token(_KIND[rule], match.group(), span(pos, end)))
        pos = end
    tokens.append(Token(TokenType.EOF, "", span(min(pos, length), min(pos, length))))
    return tokens


def doc_text(token: Token) -> str:
    """The text of a ``/** */`` or ``/*** */`` comment without the markers, tidied per line."""
    inner = token.text[4:-2] if token.type is TokenType.INITIAL_COMMENT else token.text[3:-2]
    lines = [line.strip().lstrip("*").strip() for line in inner.replace("\r\n", "\n").split("\n")]
    return "\n".join(line for line in lines if line).strip()
