"""Run-time faults: why and where an agent stopped (recorded, never raised).

Loading a program can fail with :class:`~xabsl_studio.engine.errors.LinkError` or
:class:`~xabsl_studio.engine.errors.LoadError` (raised, see :mod:`xabsl_studio.engine.errors`). At run time nothing
propagates out of ``Engine.execute``: a host callable that raises, a ``%`` by zero or a double
execution under the B2 policy becomes a :class:`Fault` that halts the agent until ``reset()``
(as hosts of the original engine stop on ``errorsOccurred``, §2.9).
"""

from __future__ import annotations

from dataclasses import dataclass

from xabsl_studio.engine.types import Span


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
