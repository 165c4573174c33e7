"""Small shared vocabulary: source spans, value kinds and type aliases used across the engine.

Kept apart from both ``xabsl_studio.engine.lang`` and ``xabsl_studio.engine.ir`` so that the IR can carry spans without
depending on the parser, and the parser can produce IR without a cycle.
"""

from __future__ import annotations

import enum
from typing import NamedTuple, TypeAlias

from typing_extensions import TypedDict

#: Milliseconds of the engine clock (the original engine uses an unsigned 32-bit counter).
Ms: TypeAlias = int
#: A symbol or parameter value at run time: decimals are floats, enum values are host integers.
Value: TypeAlias = float | bool | int


class Kind(enum.Enum):
    """The three value types of XABSL 2 (§1.4): decimal (C++ double), boolean, enumerated."""

    DECIMAL = "decimal"
    BOOLEAN = "boolean"
    ENUM = "enum"

    @property
    def ic_code(self) -> str:
        """The type letter of the intermediate code (§3.2): ``d``, ``b`` or ``e``."""
        return self.value[0]


class SpanJson(TypedDict):
    """A :class:`Span` as JSON (``Span.as_dict``): the studio's and the command line's one shape."""

    file: str
    line: int
    col: int
    end_line: int
    end_col: int
    start: int
    end: int


class Span(NamedTuple):
    """A region of a source file.

    A NamedTuple rather than a frozen dataclass because the tokenizer builds one per token:
    on a 200 KB behavior set the frozen dataclass's ``__init__`` alone cost a third of parsing.

    ``line`` and ``col`` are 1-based and point at the first character; ``end_line``/``end_col``
    point just past the last one. ``start``/``end`` are 0-based character offsets into the
    decoded file text (what an editor such as CodeMirror needs for ``from``/``to``).
    """

    file: str
    line: int
    col: int
    end_line: int
    end_col: int
    start: int
    end: int

    def to(self, other: Span) -> Span:
        """The span from the start of ``self`` to the end of ``other`` (same file)."""
        return Span(self.file, self.line, self.col, other.end_line, other.end_col, self.start, other.end)

    def as_dict(self) -> SpanJson:
        """The span as a JSON-ready dict (the field names as keys)."""
        return {
            "file": self.file,
            "line": self.line,
            "col": self.col,
            "end_line": self.end_line,
            "end_col": self.end_col,
            "start": self.start,
            "end": self.end,
        }
