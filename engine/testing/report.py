"""Reports of a behavior test run: the JUnit XML file (for CI) and the ``-k`` selection.

The JUnit file is the common dialect CI servers read: ``<testsuites>`` with one ``<testsuite>``
per test file, one ``<testcase classname=SUITE name=TEST time=S>`` per test, a ``<failure
message=...>`` (the first failed assertion; the text has all of them and the recording) or an
``<error message=...>`` for a test that could not run. Written atomically; names and messages
are :func:`printable` first (control characters would make the XML unreadable, and drive the
terminal the console report goes to).
"""

from __future__ import annotations

import re
import unicodedata
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

from xabsl_studio.engine.errors import BehaviorTestError
from xabsl_studio.engine.files import write_atomically
from xabsl_studio.engine.testing.runner import CaseResult

__all__ = ["KeywordError", "junit_xml", "keyword_matcher", "printable", "write_junit"]


#: Characters shown as escapes: C0/C1 controls (escape sequences could drive a terminal), format
#: characters (bidi overrides), line and paragraph separators, surrogates, and the noncharacters
#: XML cannot hold.
_HIDDEN = frozenset({"Cc", "Cf", "Cs", "Zl", "Zp"})


def printable(text: str, lines: bool = False) -> str:
    """``text`` with every invisible or control character as an escape (``\\x1b``, ``\\u202e``).

    Names and messages of a test file go to a terminal and into XML: escaped, they can neither
    drive the terminal nor make the XML unreadable, and still say what the file holds. With
    ``lines``, line breaks and tabs stay (a multi-line report).
    """
    out = []
    for char in text:
        code = ord(char)
        if lines and char in "\n\t":
            out.append(char)
        elif unicodedata.category(char) in _HIDDEN or code in (0xFFFE, 0xFFFF):
            out.append(f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}")
        else:
            out.append(char)
    return "".join(out)


def junit_xml(results: Sequence[CaseResult]) -> str:
    """The JUnit XML document of ``results`` (grouped by test file, in run order).

    Names and messages are :func:`printable`, so the document parses whatever a test file holds.
    """
    root = ET.Element("testsuites", name="xabsl test")
    groups: dict[str, list[CaseResult]] = {}
    for result in results:
        groups.setdefault(result.file, []).append(result)
    for file, group in groups.items():
        suite = ET.SubElement(
            root,
            "testsuite",
            name=printable(group[0].suite),
            file=printable(file),
            tests=str(len(group)),
            failures=str(sum(r.status == "failed" for r in group)),
            errors=str(sum(r.status == "error" for r in group)),
            skipped="0",
            time=f"{sum(r.seconds for r in group):.3f}",
        )
        for result in group:
            case = ET.SubElement(
                suite,
                "testcase",
                classname=printable(result.suite),
                name=printable(result.name),
                file=printable(file),
                time=f"{result.seconds:.3f}",
            )
            if result.status == "failed":
                message = printable(result.failures[0].message())
                failure = ET.SubElement(case, "failure", message=message, type="AssertionError")
                failure.text = printable(result.report(), lines=True)
            elif result.status == "error":
                error = ET.SubElement(case, "error", message=printable(result.error or ""), type="TestSetupError")
                error.text = printable(result.report(), lines=True)
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def write_junit(path: Path, results: Sequence[CaseResult]) -> None:
    """Write :func:`junit_xml` to ``path`` atomically."""
    write_atomically(path, junit_xml(results).encode("utf-8"))


class KeywordError(BehaviorTestError, ValueError):
    """A ``-k`` expression that does not parse."""


#: Parentheses a ``-k`` expression may nest (pytest's own parser has a similar bound).
MAX_KEYWORD_NESTING = 100

_TOKEN = re.compile(r"\s*(?:(\()|(\))|([^\s()]+))")


def keyword_matcher(expression: str) -> object:
    """A predicate over test ids for ``-k``: words match as substrings (case-insensitive), with and/or/not.

    ``-k "goalie and not clear"`` selects the tests whose ``suite::test`` id contains ``goalie``
    and not ``clear``, as pytest's ``-k`` does. Long chains of ``and``/``or``/``not`` are fine;
    parentheses nest at most :data:`MAX_KEYWORD_NESTING` deep.

    Raises:
        KeywordError: an expression that does not parse.
    """
    tokens: list[str] = []
    position = 0
    text = expression.strip()
    while position < len(text):
        match = _TOKEN.match(text, position)
        if match is None or match.end() == position:
            raise KeywordError(f"-k {expression!r}: cannot parse at {text[position:]!r}")
        tokens.append(match.group(1) or match.group(2) or match.group(3))
        position = match.end()
        while position < len(text) and text[position].isspace():
            position += 1
    if not tokens:
        raise KeywordError("-k: empty expression")
    parser = _KeywordParser(tokens)
    tree = parser.any_of(0)
    if parser.at < len(tokens):
        raise KeywordError(f"-k {expression!r}: unexpected {tokens[parser.at]!r}")
    return tree


class _Node:
    """One node of a ``-k`` expression: a word, ``not`` of a node, ``and``/``or`` of several."""

    def __init__(self, op: str, *args: object) -> None:
        self.op, self.args = op, args

    def __call__(self, test_id: str) -> bool:
        if self.op == "word":
            return str(self.args[0]).lower() in test_id.lower()
        if self.op == "not":
            return not self.args[0](test_id)  # type: ignore[operator]
        if self.op == "and":
            return all(a(test_id) for a in self.args)  # type: ignore[operator]
        return any(a(test_id) for a in self.args)  # type: ignore[operator]


class _KeywordParser:
    """Recursive descent over the tokens; recursion only for parentheses, which are bounded."""

    def __init__(self, tokens: list[str]) -> None:
        self.tokens = tokens
        self.at = 0

    def peek(self) -> str | None:
        return self.tokens[self.at] if self.at < len(self.tokens) else None

    def any_of(self, depth: int) -> _Node:
        terms = [self.all_of(depth)]
        while self.peek() == "or":
            self.at += 1
            terms.append(self.all_of(depth))
        return terms[0] if len(terms) == 1 else _Node("or", *terms)

    def all_of(self, depth: int) -> _Node:
        terms = [self.negated(depth)]
        while self.peek() == "and":
            self.at += 1
            terms.append(self.negated(depth))
        return terms[0] if len(terms) == 1 else _Node("and", *terms)

    def negated(self, depth: int) -> _Node:
        negations = 0
        while self.peek() == "not":  # a chain of nots is one node (or none), not a deep tree
            negations += 1
            self.at += 1
        token = self.peek()
        if token is None:
            raise KeywordError("-k: the expression ends too early")
        if token == "(":
            if depth >= MAX_KEYWORD_NESTING:
                raise KeywordError(f"-k: parentheses nested more than {MAX_KEYWORD_NESTING} deep")
            self.at += 1
            node = self.any_of(depth + 1)
            if self.peek() != ")":
                raise KeywordError("-k: missing )")
            self.at += 1
        elif token in ("and", "or", ")"):
            raise KeywordError(f"-k: unexpected {token!r}")
        else:
            node = _Node("word", token)
            self.at += 1
        return _Node("not", node) if negations % 2 else node
