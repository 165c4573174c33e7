"""The temporal assertions of a behavior test, evaluated tick by tick on an engine's public views.

Each :class:`~xabsl_studio.engine.testing.spec.Expect` becomes a :class:`Monitor`: after every tick the
runner hands it a :class:`TickView` (the tick's index and test time, the activation tree from
``Engine.activation()``, the engine for symbol values); the monitor decides as early as it can
(``always`` fails at the first tick the predicate is false, ``eventually`` passes at the first
tick it held long enough) and :meth:`Monitor.finish` decides the rest when the test ends. A
failure is a :class:`Failure` naming the assertion, the tick, the test time and the values seen.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

from xabsl_studio.engine.errors import BehaviorTestError
from xabsl_studio.engine.runtime import Engine
from xabsl_studio.engine.runtime.activation import BehaviorNode, Node, OptionNode
from xabsl_studio.engine.testing.spec import Expect

__all__ = ["Failure", "Monitor", "TickView", "path_text", "read_symbol"]

#: Numbers compare equal within this (decimal symbols go through float arithmetic).
TOLERANCE = 1e-9


@dataclass(frozen=True, slots=True)
class TickView:
    """What the assertions see of one tick: its index from the test's start, time, tree, engine."""

    tick: int
    t_ms: int
    tree: Sequence[Node]
    engine: Engine


@dataclass(frozen=True, slots=True)
class Failure:
    """A failed assertion: which one, at which tick (index from the test's start) and time, the values."""

    expect: Expect
    tick: int
    t_ms: int
    values: str

    def message(self) -> str:
        """One line: ``tick 113 (t = 2.825 s): <assertion> failed: <values>``."""
        return f"tick {self.tick} (t = {self.t_ms / 1000:g} s): {self.expect.text} failed: {self.values}"


def walk(tree: Sequence[Node]) -> Iterator[Node]:
    """Every node of an activation tree, pre-order."""
    for node in tree:
        yield node
        if isinstance(node, OptionNode):
            yield from walk(node.sub)


def path_text(tree: Sequence[Node], engine: Engine) -> str:
    """The activation path in one line: ``play_soccer:playing > goalie:guard > walk_to(x=-4200, ...)``."""
    parts: list[str] = []
    for node in walk(tree):
        if isinstance(node, OptionNode):
            parts.append(f"{node.option}:{node.state}")
        elif isinstance(node, BehaviorNode):
            params = ", ".join(
                f"{k.rsplit('.', 1)[-1]}={_fmt(engine.enum_element(node.enums.get(k), v))}"
                for k, v in node.params.items()
            )
            parts.append(f"{node.behavior}({params})")
    return " > ".join(parts) if parts else "(nothing active)"


def read_symbol(engine: Engine, name: str) -> Any:
    """The value of an output, internal or plain input symbol, enums as element names.

    Raises:
        KeyError: the program has no such symbol (or it is an input with parameters).
    """
    program = engine.program
    if name in program.outputs:
        return engine.enum_element(program.outputs[name].enum, engine.output(name))
    symbol = program.inputs.get(name)
    if symbol is None or symbol.params or name not in engine.input_reads:
        raise KeyError(name)
    return engine.enum_element(symbol.enum, engine.input_reads[name]())


def matches(actual: Any, wanted: Any) -> bool:
    """``wanted`` (a number, bool, enum element, or ``[low, high]``) accepts ``actual``."""
    if isinstance(wanted, list):
        if isinstance(actual, bool) or not isinstance(actual, int | float):
            return False
        return bool(wanted[0] - TOLERANCE <= actual <= wanted[1] + TOLERANCE)
    if isinstance(wanted, bool) or isinstance(actual, bool):
        return isinstance(wanted, bool) and isinstance(actual, bool) and actual is wanted
    if isinstance(wanted, str):
        # An enum element, qualified (role.striker) or without its enumeration's prefix (striker;
        # an element's own dots stay: kick.left of play.kind).
        return isinstance(actual, str) and (actual == wanted or actual.endswith("." + wanted))
    if isinstance(actual, str):
        return False
    return math.isclose(float(actual), float(wanted), rel_tol=TOLERANCE, abs_tol=TOLERANCE)


class Monitor:
    """Evaluates one expectation over the ticks of a test (see the module docstring)."""

    def __init__(self, expect: Expect) -> None:
        self.expect = expect
        self.failure: Failure | None = None
        self.passed = False
        self._since: int | None = None  # eventually ... for: when the predicate began to hold
        self._last: tuple[int, int, str] | None = None  # the last tick seen in the window
        self._previous: Any = None
        self._changes = 0
        self._seen = False

    @property
    def decided(self) -> bool:
        """True once the result can no longer change."""
        return self.passed or self.failure is not None

    def _in_window(self, t_ms: int) -> bool:
        e = self.expect
        return e.start * 1000 - 0.5 <= t_ms and (e.stop is None or t_ms <= e.stop * 1000 + 0.5)

    def observe(self, view: TickView, engine: Engine) -> None:
        """Take one tick into account (``engine``: the engine this expectation reads)."""
        if self.decided:
            return
        e = self.expect
        t = view.t_ms
        if e.quantifier == "at":
            if t + 0.5 >= (e.at or 0.0) * 1000:
                ok, values = self.holds(view.tree, engine)
                self._decide(ok, view, values)
            return
        late = e.stop is not None and t > e.stop * 1000 + 0.5
        # eventually ... for: it must begin to hold in the window, the holding may go on past it.
        if late and not (e.quantifier == "eventually" and self._since is not None):
            self.finish()
            return
        if not late and not self._in_window(t):
            return
        if e.quantifier == "changes":
            self._count(view, engine)
            return
        ok, values = self.holds(view.tree, engine)
        self._last = (view.tick, t, values)
        if (e.quantifier == "always" and not ok) or (e.quantifier == "never" and ok):
            self.failure = Failure(e, view.tick, t, values)
        elif e.quantifier == "eventually":
            if not ok:
                self._since = None
                if late:
                    self.finish()
            else:
                if self._since is None:
                    self._since = t
                if t - self._since + 0.5 >= e.hold * 1000:
                    self.passed = True

    def _decide(self, ok: bool, view: TickView, values: str) -> None:
        if ok:
            self.passed = True
        else:
            self.failure = Failure(self.expect, view.tick, view.t_ms, values)

    def _count(self, view: TickView, engine: Engine) -> None:
        e = self.expect
        assert e.symbol is not None and e.max_changes is not None
        value = _symbol(engine, e.symbol)
        if self._seen and value != self._previous:
            self._changes += 1
            if self._changes > e.max_changes:
                self.failure = Failure(
                    e,
                    view.tick,
                    view.t_ms,
                    f"{e.symbol} changed {_fmt(self._previous)} -> {_fmt(value)}, change {self._changes}",
                )
        self._seen = True
        self._previous = value
        self._last = (view.tick, view.t_ms, f"{e.symbol} = {_fmt(value)}")

    def finish(self) -> None:
        """The test ended (or the window closed): decide what is still open."""
        if self.decided:
            return
        e = self.expect
        if e.quantifier in ("always", "never", "changes"):
            if self._last is None and e.quantifier != "changes":
                self.failure = Failure(e, 0, 0, "the test ended before the window started")
            else:
                self.passed = True
        elif e.quantifier == "at":
            self.failure = Failure(e, 0, 0, f"the test ended before t = {e.at:g} s")
        elif self._last is None:
            self.failure = Failure(e, 0, 0, "the test ended before the window started")
        else:
            tick, t, values = self._last
            held = f" for {e.hold:g} s" if e.hold else ""
            self.failure = Failure(e, tick, t, f"never held{held}; last seen: {values}")

    # -- predicates ---------------------------------------------------------------------------------

    def holds(self, tree: Sequence[Node], engine: Engine) -> tuple[bool, str]:
        """Whether the predicate holds in this tick, and the values that show it."""
        e = self.expect
        if e.symbol is not None:
            value = _symbol(engine, e.symbol)
            return _compare(e.comparator or "equals", value, e.value), f"{e.symbol} = {_fmt(value)}"
        if e.option is not None:
            found = [n for n in walk(tree) if isinstance(n, OptionNode) and n.option == e.option]
            for node in found:
                if (e.state is None or node.state == e.state) and self._params(node.params, node.enums, engine):
                    return True, f"{node.option} in state {node.state}{_params_text(node.params, node.enums, engine)}"
            if found:
                node = found[0]
                return False, f"{node.option} in state {node.state}{_params_text(node.params, node.enums, engine)}"
            return False, f"{e.option} not active; active: {path_text(tree, engine)}"
        found_b = [n for n in walk(tree) if isinstance(n, BehaviorNode) and n.behavior == e.behavior]
        for b in found_b:
            if self._params(b.params, b.enums, engine):
                return True, f"{b.behavior}{_params_text(b.params, b.enums, engine)}"
        if found_b:
            b = found_b[0]
            return False, f"{b.behavior}{_params_text(b.params, b.enums, engine)}"
        return False, f"{e.behavior} not called; active: {path_text(tree, engine)}"

    def _params(self, params: dict[str, Any], enums: dict[str, str], engine: Engine) -> bool:
        for key, wanted in self.expect.params.items():
            name = next((k for k in params if k == key or k.rsplit(".", 1)[-1] == key), None)
            if name is None:
                return False
            if not matches(engine.enum_element(enums.get(name), params[name]), wanted):
                return False
        return True


def _symbol(engine: Engine, name: str) -> Any:
    try:
        return read_symbol(engine, name)
    except KeyError:
        raise AssertionSpecError(f"the behavior has no output or plain input symbol {name}") from None


class AssertionSpecError(BehaviorTestError, ValueError):
    """An assertion names something the behavior does not have (a symbol, an option)."""


def _compare(comparator: str, actual: Any, wanted: Any) -> bool:
    if comparator == "equals":
        return matches(actual, wanted)
    if comparator == "not_equals":
        return not matches(actual, wanted)
    if comparator == "one_of":
        return any(matches(actual, w) for w in wanted)
    if isinstance(actual, bool) or not isinstance(actual, int | float):
        return False
    if comparator == "below":
        return bool(actual < wanted)
    if comparator == "above":
        return bool(actual > wanted)
    return matches(actual, wanted)  # between: a [low, high] range


def _params_text(params: dict[str, Any], enums: dict[str, str], engine: Engine) -> str:
    if not params:
        return ""
    shown = ", ".join(f"{k.rsplit('.', 1)[-1]}={_fmt(engine.enum_element(enums.get(k), v))}" for k, v in params.items())
    return f" ({shown})"


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value).lower() if isinstance(value, bool) else str(value)
