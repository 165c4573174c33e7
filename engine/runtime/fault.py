"""The engine's error vocabulary: load-time errors (raised) and run-time faults (recorded).

Loading a program can fail with :class:`LinkError` (the program names host symbols, enum
elements or basic behaviors that were not registered, §2.10 and §3.5) or :class:`LoadError`
(option graph checks, §2.10). At run time nothing propagates out of ``Engine.execute``: a host
callable that raises, a ``%`` by zero or a double execution under the B2 policy becomes a
:class:`Fault` that halts the agent until ``reset()`` (as hosts of the original engine stop on
``errorsOccurred``, §2.9).
"""

from __future__ import annotations

from dataclasses import dataclass

from engine.types import Span


class EngineError(Exception):
    """Root of the engine's exceptions."""


class LinkError(EngineError):
    """The program names things the host did not register (or registered differently).

    ``problems`` lists every one of them, so a host fixes its bindings in one go.
    """

    def __init__(self, problems: list[str]) -> None:
        self.problems = list(problems)
        lines = "\n".join(f"  - {p}" for p in self.problems)
        super().__init__(f"cannot link the behavior: {len(self.problems)} problem(s)\n{lines}")


class LoadError(EngineError):
    """The option graph fails a load-time check (a loop, or double execution under B2, §2.10)."""


class DoubleExecutionError(EngineError):
    """An option was reached twice in one activation tree (§2.2; a fault under policy B2)."""


class DebugError(EngineError):
    """A debug request names something unknown or gives a value of the wrong kind."""


@dataclass(frozen=True, slots=True)
class Fault:
    """Why and where an agent stopped: the message, the option and state, the XABSL span."""

    message: str
    option: str | None = None
    state: str | None = None
    span: Span | None = None
    #: the class name of the exception that caused it
    error: str = ""

    def __str__(self) -> str:
        where = []
        if self.option is not None:
            where.append(f"option {self.option}")
        if self.state is not None:
            where.append(f"state {self.state}")
        if self.span is not None:
            where.append(f"{self.span.file}:{self.span.line}:{self.span.col}")
        location = f" (in {', '.join(where)})" if where else ""
        return f"{self.message}{location}"
