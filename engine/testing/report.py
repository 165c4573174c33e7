"""Reports of a behavior test run: the JUnit XML file (for CI) and the ``-k`` selection.

The JUnit file is the common dialect CI servers read: ``<testsuites>`` with one ``<testsuite>``
per test file, one ``<testcase classname=SUITE name=TEST time=S>`` per test, a ``<failure
message=...>`` (the first failed assertion; the text has all of them and the recording) or an
``<error message=...>`` for a test that could not run. Written atomically.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path

from xabsl_studio.engine.errors import BehaviorTestError
from xabsl_studio.engine.files import write_atomically
from xabsl_studio.engine.testing.runner import CaseResult

__all__ = ["KeywordError", "junit_xml", "keyword_matcher", "write_junit"]


def junit_xml(results: Sequence[CaseResult]) -> str:
    """The JUnit XML document of ``results`` (grouped by test file, in run order)."""
    root = ET.Element("testsuites", name="xabsl test")
    groups: dict[str, list[CaseResult]] = {}
    for result in results:
        groups.setdefault(result.file, []).append(result)
    for file, group in groups.items():
        suite = ET.SubElement(
            root,
            "testsuite",
            name=group[0].suite,
            file=file,
            tests=str(len(group)),
            failures=str(sum(r.status == "failed" for r in group)),
            errors=str(sum(r.status == "error" for r in group)),
            skipped="0",
            time=f"{sum(r.seconds for r in group):.3f}",
        )
        for result in group:
            case = ET.SubElement(
                suite, "testcase", classname=result.suite, name=result.name, file=file, time=f"{result.seconds:.3f}"
            )
            if result.status == "failed":
                failure = ET.SubElement(case, "failure", message=result.failures[0].message(), type="AssertionError")
                failure.text = result.report()
            elif result.status == "error":
                error = ET.SubElement(case, "error", message=result.error or "", type="TestSetupError")
                error.text = result.report()
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def write_junit(path: Path, results: Sequence[CaseResult]) -> None:
    """Write :func:`junit_xml` to ``path`` atomically."""
    write_atomically(path, junit_xml(results).encode("utf-8"))


class KeywordError(BehaviorTestError, ValueError):
    """A ``-k`` expression that does not parse."""


_TOKEN = re.compile(r"\s*(?:(\()|(\))|([^\s()]+))")


def keyword_matcher(expression: str) -> object:
    """A predicate over test ids for ``-k``: words match as substrings (case-insensitive), with and/or/not.

    ``-k "goalie and not clear"`` selects the tests whose ``suite::test`` id contains ``goalie``
    and not ``clear``, as pytest's ``-k`` does.

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
    tree, rest = _or(tokens)
    if rest:
        raise KeywordError(f"-k {expression!r}: unexpected {rest[0]!r}")
    return tree


class _Node:
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


def _or(tokens: list[str]) -> tuple[_Node, list[str]]:
    left, tokens = _and(tokens)
    while tokens and tokens[0] == "or":
        right, tokens = _and(tokens[1:])
        left = _Node("or", left, right)
    return left, tokens


def _and(tokens: list[str]) -> tuple[_Node, list[str]]:
    left, tokens = _not(tokens)
    while tokens and tokens[0] == "and":
        right, tokens = _not(tokens[1:])
        left = _Node("and", left, right)
    return left, tokens


def _not(tokens: list[str]) -> tuple[_Node, list[str]]:
    if not tokens:
        raise KeywordError("-k: the expression ends too early")
    if tokens[0] == "not":
        inner, rest = _not(tokens[1:])
        return _Node("not", inner), rest
    if tokens[0] == "(":
        inner, rest = _or(tokens[1:])
        if not rest or rest[0] != ")":
            raise KeywordError("-k: missing )")
        return inner, rest[1:]
    if tokens[0] in ("and", "or", ")"):
        raise KeywordError(f"-k: unexpected {tokens[0]!r}")
    return _Node("word", tokens[0]), tokens[1:]
