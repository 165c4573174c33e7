"""The exception tree of xabsl-studio: one root, one class per stage that can refuse something.

Every exception the project raises on purpose derives from :class:`XabslError`, so a host
catches everything the toolchain refuses with one ``except XabslError``, and one stage with its
class. Classes that callers also catch as a builtin (``ValueError``, ``LookupError``...) keep that
builtin as a second base. The concrete classes of a stage live next to the code that raises
them and derive from the stage's class here::

    XabslError
    ├── CompileError          xabsl_studio.engine.lang: a behavior that does not parse or check
    ├── ReadError             xabsl_studio.engine.ir: intermediate code that cannot be read (ICError)
    ├── EmitError             xabsl_studio.engine.emit: an output that cannot be produced (GraphvizMissing)
    ├── EngineError           xabsl_studio.engine.runtime: the engine refuses a program or a request
    │   ├── LinkError         the program names host symbols/behaviors that are not registered
    │   ├── LoadError         the option graph fails a load-time check (CodegenError)
    │   ├── DoubleExecutionError  an option ran twice in one tick under policy B2 (a fault)
    │   └── DebugError        a debug request names something unknown (CommandError)
    │       └── ValueConversionError  a value of the wrong type, not finite, out of range
    ├── TraceError            xabsl_studio.engine.trace: a conformance trace (TraceInputError, TraceFaultError)
    ├── DynamicsError         xabsl_studio.engine.dynamics: a Dual Dynamics model (ModelError, ExprError)
    ├── PlanningError         xabsl_studio.engine.planning: PDDL and fact rules (UnsupportedPDDLError, FactRuleError)
    ├── HostError             a host or world: an example folder, a team (ExampleError, TeamError)
    ├── RecordError           xabsl_studio.engine.record: recordings (RecordingError, RecordingFailed)
    ├── QueryError            xabsl_studio.engine.query: a query over ticks (QueryConditionError)
    ├── BehaviorTestError     xabsl_studio.engine.testing: test files and selections (AssertionSpecError, ...)
    ├── CommandLineError      the ``xabsl`` command line (UsageError)
    └── ServerError           the studio server, defined by it (``xabsl_studio.server.protocol.errors``:
                              ProtocolError, FileError, GraphError, ChannelClosed, StudioFull, ...)

Run-time faults of a running agent are not exceptions that propagate: the engine records them as a
:class:`xabsl_studio.engine.runtime.fault.Fault` (§2.9).
"""

from __future__ import annotations

__all__ = [
    "BehaviorTestError",
    "CommandLineError",
    "CompileError",
    "DebugError",
    "DoubleExecutionError",
    "DynamicsError",
    "EmitError",
    "EngineError",
    "HostError",
    "LinkError",
    "LoadError",
    "PlanningError",
    "QueryError",
    "ReadError",
    "RecordError",
    "TraceError",
    "ValueConversionError",
    "XabslError",
]


class XabslError(Exception):
    """Root of every exception the project raises on purpose."""


class CompileError(XabslError):
    """A behavior that does not compile (the compiler reports most problems as diagnostics)."""


class ReadError(XabslError):
    """Intermediate code or another stored program that cannot be read."""


class EmitError(XabslError):
    """An output format (graph, JSON, intermediate code) that cannot be produced."""


class EngineError(XabslError):
    """The engine refuses a program (link, load) or a request (debug)."""


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
    """A debug request names something unknown (an option, a parameter, a symbol, an agent)."""


class ValueConversionError(DebugError, ValueError):
    """A value given from outside (debugger, server, trace) of the wrong type, not finite or out of range."""


class TraceError(XabslError):
    """A conformance trace that cannot be run."""


class DynamicsError(XabslError):
    """A Dual Dynamics model that cannot be read or evaluated."""


class PlanningError(XabslError):
    """A planning problem that cannot be grounded, solved or monitored."""


class HostError(XabslError):
    """A host or world that cannot run: an example folder, a team's behavior."""


class CommandLineError(XabslError):
    """A command line of ``xabsl`` that cannot be carried out."""


class RecordError(XabslError):
    """A recording that cannot be read, written or re-simulated."""


class QueryError(XabslError):
    """A query over recorded ticks that cannot be run: a bad condition, an unknown robot."""


class BehaviorTestError(XabslError):
    """A behavior test file, selection or draft that cannot be run (``xabsl test``)."""
