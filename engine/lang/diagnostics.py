"""Diagnostics: every user mistake in a behavior becomes one :class:`Diagnostic`, never a traceback.

A diagnostic has a severity, a stable code (``no-matching-symbol``), a message, a source span
and, where the original Ruby compiler had one, its error number (``X5552``) so that users of
the original toolchain recognise it. :class:`Diagnostics` collects them for a whole compile run.

The codes are a table (:data:`CODES`) so documentation and tests can enumerate them.
"""

from __future__ import annotations

import enum
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Literal

from typing_extensions import TypedDict

from xabsl_studio.engine.types import Span, SpanJson


class Severity(enum.Enum):
    """How bad a diagnostic is: an error prevents output, a warning does not."""

    ERROR = "error"
    WARNING = "warning"


#: code -> (severity, original compiler error number or "", one-line description)
CODES: dict[str, tuple[Severity, str, str]] = {
    # lexical and syntax (§1.2, §1.3)
    "illegal-character": (Severity.ERROR, "X2573", "a character that starts no token"),
    "unterminated-comment": (Severity.ERROR, "X3275", "a /* comment without */"),
    "syntax-error": (Severity.ERROR, "X2537", "a token the grammar does not accept here"),
    "unexpected-end-of-file": (Severity.ERROR, "X2555", "the file ends inside a declaration"),
    "nesting-too-deep": (Severity.ERROR, "", "nesting deeper than the compiler can follow"),
    # files and includes (§1.1)
    "missing-include-file": (Severity.ERROR, "X2375", "an included file does not exist"),
    "include-twice": (Severity.ERROR, "", "the same file included twice from one file"),
    "unreadable-file": (Severity.ERROR, "X2375", "a file that cannot be read"),
    "naming": (Severity.WARNING, "", "namespace or option named differently from its file"),
    "empty-namespace": (Severity.WARNING, "", "a namespace without declarations"),
    "namespace-separation": (Severity.ERROR, "", "symbols and basic behaviors in one namespace"),
    # names and declarations (§1.4)
    "no-matching-symbol": (Severity.ERROR, "X5552", "an identifier that names nothing usable here"),
    "multiple-matching-symbols": (Severity.ERROR, "X5723", "an identifier that names several things"),
    "duplicate-definition": (Severity.ERROR, "X5372", "a name defined more than once"),
    "parameter-set-twice": (Severity.ERROR, "X3725", "a call that sets one parameter twice"),
    "parameter-missing": (Severity.WARNING, "", "a call that leaves a parameter out (it gets 0)"),
    "unknown-parameter": (Severity.ERROR, "X5552", "a call that sets a parameter the callee lacks"),
    "unknown-state": (Severity.ERROR, "X5552", "a transition to a state the option lacks"),
    "unknown-option": (Severity.ERROR, "X5552", "an agent or call naming an unknown option"),
    "unknown-enum": (Severity.ERROR, "X5552", "a type naming an unknown enumeration"),
    "missing-initial-state": (Severity.ERROR, "X5273", "an option without an initial state"),
    "multiple-initial-states": (Severity.ERROR, "X5327", "an option with several initial states"),
    "range-on-non-decimal": (Severity.WARNING, "X2537", "a range or unit on a bool or enum"),
    "parameters-on-non-input": (Severity.ERROR, "", "parameters on an output or internal symbol"),
    "enum-io": (Severity.ERROR, "", "an enumeration declared input or output"),
    "not-assignable": (Severity.ERROR, "", "an assignment to something other than an output"),
    "not-callable": (Severity.ERROR, "", "a call of something that is no option or behavior"),
    # types (§1.4)
    "type-mismatch": (Severity.ERROR, "X5525", "an operand or value of the wrong type"),
    "mismatching-domain": (Severity.ERROR, "X5255", "enum values of different enumerations"),
    "boolean-conditional": (Severity.ERROR, "", "?: with boolean branches (the engine has none)"),
    # decision trees (§1.3 notes c, d)
    "else-without-common-decision": (
        Severity.ERROR,
        "X7352",
        "a decision starting with else in an option without a common decision tree",
    ),
    "decision-must-start-with-else": (
        Severity.WARNING,
        "",
        "a decision not starting with else in an option with a common decision tree",
    ),
    # lint the original compiler never had
    "option-graph-cycle": (Severity.ERROR, "", "an option that can reach itself through calls"),
    "unreachable-option": (Severity.WARNING, "", "an option no agent can reach"),
    "unreachable-state": (Severity.WARNING, "", "a state no transition leads to"),
    "unused-symbol": (Severity.WARNING, "", "a symbol, constant or enumeration never used"),
    "unused-behavior": (Severity.WARNING, "", "a basic behavior never called"),
}


#: Warnings the original compiler never prints: ``naming`` and ``parameter-missing`` it defines
#: but suppresses, the rest are whole-program lint of our own. ``xabsl compile --no-lint`` and
#: the studio's "as the original compiler" leave out exactly these, so what remains is what the
#: original prints (errors, and the warnings it shows).
LINT_CODES = frozenset(
    {"naming", "parameter-missing", "unreachable-option", "unreachable-state", "unused-symbol", "unused-behavior"}
)
if not all(CODES[code][0] is Severity.WARNING for code in LINT_CODES):  # pragma: no cover - a table edit
    raise AssertionError("lint is warnings only: an error can never be hidden")


class RelatedJson(TypedDict):
    """A place a diagnostic points to besides its own (``related``)."""

    message: str
    span: SpanJson


class DiagnosticJson(TypedDict):
    """A :class:`Diagnostic` as JSON (``--format json``, the studio's saves, compiles and status).

    ``file`` is the path the compiler read; ``span`` is None for a diagnostic about no place in
    a file (a missing agents file). ``original_code`` is the original compiler's error number or "".
    """

    severity: Literal["error", "warning"]
    code: str
    original_code: str
    lint: bool
    message: str
    file: str
    span: SpanJson | None
    related: list[RelatedJson]


@dataclass(frozen=True, slots=True)
class Diagnostic:
    """One finding about a behavior: where, how bad, which rule, what to do."""

    severity: Severity
    code: str
    message: str
    span: Span | None
    file: str
    related: tuple[tuple[str, Span], ...] = ()

    @property
    def is_error(self) -> bool:
        """Whether this is an error."""
        return self.severity is Severity.ERROR

    @property
    def is_lint(self) -> bool:
        """Whether the original compiler would not print this (see :data:`LINT_CODES`)."""
        return self.code in LINT_CODES

    @property
    def original_code(self) -> str:
        """The original Ruby compiler's error number, or ``""``."""
        return CODES[self.code][1]

    def format(self, path: str | None = None) -> str:
        """``path:line:col: error|warning: message [code]`` (line 0 when there is no span)."""
        where = path if path is not None else self.file
        line, col = (self.span.line, self.span.col) if self.span else (0, 0)
        return f"{where}:{line}:{col}: {self.severity.value}: {self.message} [{self.code}]"

    def as_dict(self) -> DiagnosticJson:
        """The diagnostic as plain JSON data (``--format json``, the studio)."""
        return {
            "severity": "error" if self.is_error else "warning",
            "code": self.code,
            "original_code": self.original_code,
            "lint": self.is_lint,
            "message": self.message,
            "file": self.file,
            "span": self.span.as_dict() if self.span else None,
            "related": [{"message": m, "span": s.as_dict()} for m, s in self.related],
        }


@dataclass
class Diagnostics:
    """The diagnostics of one compile run, in the order they were found."""

    items: list[Diagnostic] = field(default_factory=list)

    def add(
        self,
        code: str,
        message: str,
        span: Span | None,
        file: str | None = None,
        related: tuple[tuple[str, Span], ...] = (),
    ) -> Diagnostic:
        """Report a diagnostic; its severity follows from ``code``."""
        assert code in CODES, f"unknown diagnostic code {code!r}"
        severity = CODES[code][0]
        where = file if file is not None else (span.file if span else "")
        diagnostic = Diagnostic(severity, code, message, span, where, related)
        self.items.append(diagnostic)
        return diagnostic

    def __iter__(self) -> Iterator[Diagnostic]:
        return iter(self.items)

    def __len__(self) -> int:
        return len(self.items)

    @property
    def errors(self) -> list[Diagnostic]:
        """The errors reported so far."""
        return [d for d in self.items if d.is_error]

    @property
    def warnings(self) -> list[Diagnostic]:
        """The warnings reported so far."""
        return [d for d in self.items if not d.is_error]

    def sorted(self) -> list[Diagnostic]:
        """By file, then position; stable for diagnostics at one place."""
        return sorted(
            self.items,
            key=lambda d: (d.file, d.span.start if d.span else -1),
        )
