"""Breakpoints: what stops a simulation, compiled against one engine's storage like the behavior.

A :class:`Breakpoint` names what to wait for, by XABSL names (so it survives hot reloads and is
stored per behavior as JSON):

* ``enter_option`` / ``leave_option``: an option starts / stops being executed;
* ``enter_state`` / ``leave_state``: an option's state becomes / stops being its active state
  (also when the option itself is entered or left in that state);
* ``leaf``: the decision of ``option``'s state ``state`` takes leaf ``leaf`` (an id of the
  state's decision tree, docs/protocol.md);
* ``condition``: an XABSL boolean expression over the program's symbols becomes true (checked by
  :func:`xabsl_studio.engine.lang.condition.check_condition`); it hits at the first tick it is true, then again
  each time it turns from false to true.

``robot`` limits one to one robot (None: any robot running the behavior).

:class:`EngineBreakpoints` compiles every breakpoint of one behavior for one engine: one Python
function per breakpoint, generated like the behavior (``xabsl_studio.engine.codegen``) and bound to the same
globals as the engine's generated code, so a check reads the storage lists (``LT``, ``PV``,
``S``, ``LF``) and the host's input functions directly. It is rebuilt when the engine loads
another program. Nothing of this runs inside ``Engine.execute``: the host checks after a tick, and
only while breakpoints are set (``BreakpointSet.armed``).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import asdict, dataclass, field, replace
from typing import Any, Literal, cast, get_args

from xabsl_studio.engine.codegen.python import expression_source
from xabsl_studio.engine.errors import DebugError
from xabsl_studio.engine.ir.model import Program, leaves
from xabsl_studio.engine.lang.condition import CheckedCondition, check_condition
from xabsl_studio.engine.runtime.engine import Engine
from xabsl_studio.engine.runtime.storage import LoadedProgram

__all__ = [
    "KINDS",
    "Breakpoint",
    "BreakpointError",
    "BreakpointHit",
    "BreakpointKind",
    "BreakpointSet",
    "EngineBreakpoints",
    "breakpoint_source",
    "check_breakpoint",
]

BreakpointKind = Literal["enter_option", "leave_option", "enter_state", "leave_state", "leaf", "condition"]
#: Every kind, in the order the studio lists them.
KINDS: tuple[str, ...] = get_args(BreakpointKind)


class BreakpointError(DebugError, ValueError):
    """A breakpoint that names nothing of the program, or a condition with errors."""


@dataclass(frozen=True, slots=True)
class Breakpoint:
    """What to stop at (see the module docstring); ``id`` is unique within a behavior."""

    id: int
    kind: BreakpointKind
    option: str | None = None
    state: str | None = None
    leaf: int | None = None
    condition: str | None = None
    robot: int | None = None
    enabled: bool = True

    def describe(self) -> str:
        """A one-line description (``enter striker.kick``, ``when ball.distance < 300``)."""
        kind = self.kind
        if kind == "condition":
            return f"when {self.condition}"
        if kind == "leaf":
            return f"{self.option}.{self.state} leaf {self.leaf}"
        verb = "enter" if kind.startswith("enter") else "leave"
        target = self.option if kind.endswith("option") else f"{self.option}.{self.state}"
        return f"{verb} {target}"

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready fields (what the breakpoints file and the protocol carry)."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Breakpoint:
        """A breakpoint from :meth:`as_dict` output.

        Raises:
            BreakpointError: a field is missing or has the wrong type.
        """
        try:
            kind = data["kind"]
            if kind not in KINDS:
                raise BreakpointError(f"unknown breakpoint kind {kind!r} (kinds: {', '.join(KINDS)})")
            robot = data.get("robot")
            leaf = data.get("leaf")
            point = cls(
                id=int(data["id"]),
                kind=cast(BreakpointKind, kind),
                option=_text(data.get("option")),
                state=_text(data.get("state")),
                leaf=None if leaf is None else int(leaf),
                condition=_text(data.get("condition")),
                robot=None if robot is None else int(robot),
                enabled=bool(data.get("enabled", True)),
            )
        except (KeyError, TypeError, ValueError) as error:
            if isinstance(error, BreakpointError):
                raise
            raise BreakpointError(f"not a breakpoint: {error}") from None
        point.require_fields()
        return point

    def require_fields(self) -> None:
        """Check that the kind has the fields it needs (names are checked against a program later).

        Raises:
            BreakpointError: a field the kind needs is missing.
        """
        kind = self.kind
        if kind == "condition":
            if not self.condition:
                raise BreakpointError("a condition breakpoint needs a condition")
            return
        if not self.option:
            raise BreakpointError(f"a {kind} breakpoint needs an option")
        if kind in ("enter_state", "leave_state", "leaf") and not self.state:
            raise BreakpointError(f"a {kind} breakpoint needs a state")
        if kind == "leaf" and self.leaf is None:
            raise BreakpointError("a leaf breakpoint needs a leaf id")


def _text(value: Any) -> str | None:
    if value is None:
        return None
    if not isinstance(value, str):
        raise TypeError(f"expected a string, found {type(value).__name__}")
    return value


@dataclass(frozen=True, slots=True)
class BreakpointHit:
    """Breakpoint ``id`` hit on robot ``robot`` in the engine's tick ``tick``."""

    id: int
    robot: int
    tick: int


def check_breakpoint(program: Program, point: Breakpoint) -> CheckedCondition | None:
    """Check ``point``'s names against ``program``; a condition's check result (None for other kinds).

    Raises:
        BreakpointError: an option, state or leaf the program does not have, or a condition with
            errors (the message has ``line:col`` per error).
    """
    point.require_fields()
    if point.kind == "condition":
        checked = check_condition(program, point.condition or "")
        if not checked.ok:
            raise BreakpointError(f"condition: {checked.message()}")
        return checked
    option = program.options.get(point.option or "")
    if option is None:
        raise BreakpointError(f"the behavior has no option {point.option!r}")
    if point.kind in ("enter_option", "leave_option"):
        return None
    names = [s.name for s in option.states]
    if point.state not in names:
        raise BreakpointError(f"option {option.name} has no state {point.state!r} (states: {', '.join(names)})")
    if point.kind == "leaf":
        ids = sorted(t.leaf for t in leaves(option.state(point.state or "").decision))
        if point.leaf not in ids:
            raise BreakpointError(
                f"state {option.name}.{point.state} has no leaf {point.leaf} (leaves: {', '.join(map(str, ids))})"
            )
    return None


def breakpoint_source(loaded: LoadedProgram, point: Breakpoint, checked: CheckedCondition | None) -> str:
    """The Python expression (free names: the engine's globals and ``tick``) that is true on a hit.

    For a condition it is the condition's value; the edge (false to true) is :class:`EngineBreakpoints`'.
    """
    program, layout = loaded.program, loaded.layout
    if point.kind == "condition":
        assert checked is not None and checked.expression is not None
        # A condition reads no option's storage: any option gives the writer its context.
        first = next(iter(program.options.values()))
        return expression_source(layout, first, None, checked.expression)
    option = program.options[point.option or ""]
    i = layout.options[option.name].index
    ran = f"LT[{i}] == tick"
    was = f"PV[{i}] == tick - 1"
    if point.kind == "enter_option":
        return f"{ran} and not {was}"
    if point.kind == "leave_option":
        return f"LT[{i}] == tick - 1"
    s = option.state(point.state or "").index
    if point.kind == "enter_state":
        # active now, and either the option was just entered or its decision came from elsewhere
        return f"{ran} and S[{i}] == {s} and (not {was} or LF[{i}][2] != {s})"
    if point.kind == "leave_state":
        return f"({ran} and {was} and LF[{i}][2] == {s} and S[{i}] != {s}) or (LT[{i}] == tick - 1 and S[{i}] == {s})"
    return f"{ran} and LF[{i}][1] == {point.leaf} and LF[{i}][2] == {s}"


@dataclass(slots=True)
class EngineBreakpoints:
    """The enabled breakpoints of one behavior, compiled for one engine's loaded program.

    ``problems`` says, per breakpoint id, why it cannot be checked on this program (it names
    something a hot reload removed); such breakpoints are skipped.
    """

    loaded: LoadedProgram
    robot: int
    checks: list[tuple[int, Any, bool]] = field(default_factory=list)  # (id, function, is condition)
    problems: dict[int, str] = field(default_factory=dict)
    #: per condition breakpoint id: its value at the last check (a hit needs false -> true)
    previous: dict[int, bool] = field(default_factory=dict)

    @classmethod
    def build(
        cls, loaded: LoadedProgram, robot: int, points: Iterable[Breakpoint], previous: dict[int, bool] | None = None
    ) -> EngineBreakpoints:
        """Compile ``points`` (those enabled and for ``robot`` or any robot) for ``loaded``.

        ``previous`` (the conditions' last values, by id) is shared, so that a recompile (a hot
        reload, another breakpoint set) does not make a condition that stayed true hit again.
        """
        compiled = cls(loaded, robot, previous={} if previous is None else previous)
        for point in points:
            if not point.enabled or (point.robot is not None and point.robot != robot):
                continue
            try:
                checked = check_breakpoint(loaded.program, point)
            except BreakpointError as error:
                compiled.problems[point.id] = str(error)
                continue
            source = breakpoint_source(loaded, point, checked)
            code = compile(f"lambda tick: bool({source})", f"<xabsl-breakpoint:{point.id}>", "eval")
            # Bound to the engine's globals: the check reads the storage the generated code writes.
            function = eval(code, loaded.globals)
            compiled.checks.append((point.id, function, point.kind == "condition"))
        return compiled

    def hits(self, tick: int) -> list[int]:
        """The ids of the breakpoints that hit in the engine's tick ``tick`` (just run)."""
        found: list[int] = []
        previous = self.previous
        for ident, function, is_condition in self.checks:
            try:
                value = function(tick)
            except Exception:  # a host input that raises or a decision not recorded yet: no hit
                value = False
            if is_condition:
                was = previous.get(ident, False)
                previous[ident] = value
                if value and not was:
                    found.append(ident)
            elif value:
                found.append(ident)
        return found


class BreakpointSet:
    """The breakpoints of every behavior, checked after each tick of a set of engines.

    ``armed`` is False while no breakpoint is enabled: the host then skips :meth:`check`
    entirely (the tick path pays one attribute read).
    """

    def __init__(self) -> None:
        self.points: dict[str, dict[int, Breakpoint]] = {}  # behavior key -> id -> breakpoint
        self.armed = False
        self._compiled: dict[int, EngineBreakpoints] = {}  # robot -> compiled for its engine
        self._previous: dict[int, dict[int, bool]] = {}  # robot -> condition id -> last value

    def replace(self, key: str, points: Iterable[Breakpoint]) -> None:
        """Set the breakpoints of behavior ``key`` (all at once); a changed or new condition starts afresh."""
        old = self.points.get(key, {})
        new = {p.id: p for p in points}
        for ident, point in new.items():
            if old.get(ident) is None or old[ident].condition != point.condition or old[ident].kind != point.kind:
                for previous in self._previous.values():
                    previous.pop(ident, None)
        self.points[key] = new
        self._changed()

    def put(self, key: str, point: Breakpoint) -> None:
        """Add or replace one breakpoint of behavior ``key`` (a replaced condition starts afresh)."""
        self.points.setdefault(key, {})[point.id] = point
        for previous in self._previous.values():
            previous.pop(point.id, None)
        self._changed()

    def remove(self, key: str, ident: int) -> Breakpoint:
        """Remove breakpoint ``ident`` of behavior ``key``.

        Raises:
            BreakpointError: there is none.
        """
        try:
            point = self.points.get(key, {}).pop(ident)
        except KeyError:
            raise BreakpointError(f"no breakpoint {ident}") from None
        self._changed()
        return point

    def enable(self, key: str, ident: int, enabled: bool) -> Breakpoint:
        """Enable or disable breakpoint ``ident`` of behavior ``key``.

        Raises:
            BreakpointError: there is none.
        """
        point = self.points.get(key, {}).get(ident)
        if point is None:
            raise BreakpointError(f"no breakpoint {ident}")
        point = replace(point, enabled=enabled)
        self.points[key][ident] = point
        self._changed()
        return point

    def next_id(self, key: str) -> int:
        """An id no breakpoint of behavior ``key`` has."""
        return max(self.points.get(key, {}), default=0) + 1

    def _changed(self) -> None:
        self._compiled.clear()
        self.armed = any(p.enabled for points in self.points.values() for p in points.values())

    def problems(self, key: str) -> dict[int, str]:
        """Per breakpoint id of ``key``: why it is not checked on some robot (compiled robots only)."""
        found: dict[int, str] = {}
        for compiled in self._compiled.values():
            if any(p.id in compiled.problems for p in self.points.get(key, {}).values()):
                found.update(compiled.problems)
        return found

    def check(self, engines: Iterable[tuple[int, str | None, Engine | None]]) -> list[BreakpointHit]:
        """The hits of the tick just run; ``engines`` = (robot, behavior key, engine) per robot."""
        hits: list[BreakpointHit] = []
        compiled_by_robot = self._compiled
        for robot, key, engine in engines:
            if engine is None or key is None or engine.errored:
                continue
            points = self.points.get(key)
            if not points:
                continue
            loaded = engine.loaded
            compiled = compiled_by_robot.get(robot)
            if compiled is None or compiled.loaded is not loaded:
                previous = self._previous.setdefault(robot, {})
                compiled = EngineBreakpoints.build(loaded, robot, points.values(), previous)
                compiled_by_robot[robot] = compiled
            tick = engine.tick
            for ident in compiled.hits(tick):
                hits.append(BreakpointHit(ident, robot, tick))
        return hits
