"""The behavior test file format: one TOML file a suite (docs/tests.md is its reference).

A suite names the world (the example folder, or a behavior run in the bench world), defaults
for its tests, and a list of ``[[test]]`` tables; each test has a setup, what runs, timed input
overrides and world commands, and ``[[test.expect]]`` assertions. :func:`load_suite` parses and
checks everything before anything runs: a bad file is a :class:`SpecError` naming the file and
the TOML key path (``test[2].expect[1].within``), never a traceback in the middle of a run.

Files are read as ``xabsl_studio.engine.files.read_regular`` reads inputs: regular files only (a
FIFO or ``/dev/zero`` named as a test file or ``inputs_file`` is an error, not a hang), at most
:data:`MAX_SUITE_BYTES` and :data:`MAX_INPUTS_BYTES`. Nesting deeper than Python's parsers can
follow is an error too, and seeds are those every world takes (:data:`MAX_SEED`).
"""

from __future__ import annotations

import json
import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from xabsl_studio.engine.errors import XabslError
from xabsl_studio.engine.files import read_regular

__all__ = ["COMPARATORS", "QUANTIFIERS", "Case", "Expect", "SpecError", "Suite", "load_suite", "parse_suite"]

#: The file names the pytest plugin and ``xabsl test DIR`` collect.
SUFFIX = ".xabsl-test.toml"

#: The largest test file read (a real one is a few kilobytes).
MAX_SUITE_BYTES = 16 * 1024 * 1024
#: The largest ``inputs_file`` read (as ``xabsl trace --inputs``).
MAX_INPUTS_BYTES = 256 * 1024 * 1024
#: The largest seed: worlds seed numpy and ``random`` with it (as the studio's ``reset``, 32 bits).
MAX_SEED = 2**32 - 1

#: What an expectation says about time (exactly one per expectation, ``within`` implies eventually).
QUANTIFIERS = ("always", "never", "eventually", "at")
#: How a symbol's value is compared (exactly one per symbol expectation).
COMPARATORS = ("equals", "not_equals", "below", "above", "between", "one_of")

_SUITE_KEYS = {"name", "world", "path", "options", "seed", "duration", "robot", "agent", "setup"}
_CASE_KEYS = {
    "name",
    "seed",
    "duration",
    "robot",
    "agent",
    "setup",
    "from",
    "force",
    "inputs",
    "inputs_file",
    "commands",
    "expect",
    "doc",
}
_EXPECT_KEYS = {
    *QUANTIFIERS,
    *COMPARATORS,
    "name",
    "within",
    "from",
    "until",
    "for",
    "option",
    "state",
    "behavior",
    "params",
    "symbol",
    "max_changes",
    "robot",
}


class SpecError(XabslError, ValueError):
    """A test file that is not valid: the message names the file and the key path."""


@dataclass(frozen=True, slots=True)
class Expect:
    """One assertion: a predicate on a tick (or a count over a window) and when it must hold.

    Attributes:
        text: the assertion in words, for messages (``"eventually within 3 s: option striker in state kick"``).
        quantifier: ``always``, ``never``, ``eventually`` or ``at`` (``changes`` for ``max_changes``).
        start, stop: the window in seconds of test time (``stop`` None: to the end of the test).
        at: for ``at``: the time in seconds.
        hold: for ``eventually``: the predicate must hold this many seconds without a break.
        option, state, behavior, params: an activation predicate (params: name -> value or [lo, hi]).
        symbol, comparator, value: a symbol predicate.
        max_changes: for ``changes``: at most this many changes of ``symbol`` in the window.
        robot: read this robot's engine instead of the test's robot.
    """

    text: str
    quantifier: str
    start: float = 0.0
    stop: float | None = None
    at: float | None = None
    hold: float = 0.0
    option: str | None = None
    state: str | None = None
    behavior: str | None = None
    params: Mapping[str, Any] = field(default_factory=dict)
    symbol: str | None = None
    comparator: str | None = None
    value: Any = None
    max_changes: int | None = None
    robot: str | None = None


@dataclass(frozen=True, slots=True)
class Case:
    """One test of a suite: setup, what runs, stimuli over time, assertions.

    Attributes:
        inputs: ``(t_ms, {symbol: value})`` in time order (the ``xabsl trace`` input format).
        commands: ``(t_ms, name, args)`` world commands (``xabsl_studio.engine.host.CommandableWorld``).
        force: ``("option" | "behavior", name, params)`` forced as root, or None (the agent runs).
        fork: ``(recording path, tick, verify)``: start from that tick of a recording.
    """

    suite: Suite
    name: str
    index: int
    seed: int
    duration: float
    robot: str | None
    agent: str | None
    setup: Mapping[str, Any]
    force: tuple[str, str, Mapping[str, Any]] | None
    inputs: tuple[tuple[int, Mapping[str, Any]], ...]
    commands: tuple[tuple[int, str, Mapping[str, Any]], ...]
    expects: tuple[Expect, ...]
    fork: tuple[Path, int, bool] | None = None

    @property
    def id(self) -> str:
        """``suite::test``, what ``-k`` matches and reports show."""
        return f"{self.suite.name}::{self.name}"


@dataclass(frozen=True, slots=True)
class Suite:
    """A parsed test file."""

    file: Path
    name: str
    path: Path
    world: str | None
    options: Mapping[str, Any]
    cases: tuple[Case, ...] = ()


def load_suite(file: str | Path) -> Suite:
    """Parse and check the test file ``file``.

    Raises:
        SpecError: not TOML, or not a valid test file (the message names the file and key).
    """
    file = Path(file)
    try:
        text = read_regular(file, MAX_SUITE_BYTES).decode("utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise SpecError(f"{file}: cannot read: {error}") from None
    return parse_suite(text, file)


def parse_suite(text: str, file: Path, *, read_files: bool = True) -> Suite:
    """Parse the text of a test file (``file`` names it in messages and anchors relative paths).

    With ``read_files`` False, a test that would read a file (``inputs_file``, ``from``) is an
    error: the studio checks the drafts it writes so, reading nothing a request could name.
    """
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise SpecError(f"{file}: not valid TOML: {error}") from None
    except RecursionError:
        raise SpecError(f"{file}: not valid TOML: arrays or tables nested too deeply") from None
    p = _Parser(file, read_files)
    unknown = set(data) - {"suite", "setup", "test"}
    if unknown:
        raise p.error("", f"unknown top-level key(s) {', '.join(sorted(unknown))} (suite, setup, test)")
    head = p.table(data.get("suite", {}), "suite")
    p.keys(head, "suite", _SUITE_KEYS)
    name = p.string(head.get("name", file.name.removesuffix(SUFFIX).removesuffix(".toml")), "suite.name")
    base = file.resolve().parent
    path = (base / p.string(head.get("path", "."), "suite.path")).resolve()
    world = p.string(head["world"], "suite.world") if "world" in head else None
    options = p.table(head.get("options", {}), "suite.options")
    defaults = {
        "seed": p.seed(head.get("seed", 1), "suite.seed"),
        "duration": p.seconds(head.get("duration", 10.0), "suite.duration"),
        "robot": p.string(head["robot"], "suite.robot") if "robot" in head else None,
        "agent": p.string(head["agent"], "suite.agent") if "agent" in head else None,
    }
    setup = p.table(data.get("setup", head.get("setup", {})), "setup")
    suite = Suite(file, name, path, world, options)
    tests = data.get("test", [])
    if not isinstance(tests, list) or not tests:
        raise p.error("test", "a suite needs at least one [[test]] table")
    cases = [p.case(suite, i, p.table(t, f"test[{i + 1}]"), defaults, setup) for i, t in enumerate(tests)]
    names = [c.name for c in cases]
    duplicate = next((n for n in names if names.count(n) > 1), None)
    if duplicate is not None:
        raise p.error("test", f"two tests are named {duplicate!r}")
    # The cases refer to the suite's head (file, name, world), which holds no cases itself.
    return Suite(file, name, path, world, options, tuple(cases))


class _Parser:
    """Checks values and builds messages naming the file and the key path."""

    def __init__(self, file: Path, read_files: bool = True) -> None:
        self.file = file
        self.read_files = read_files

    def error(self, where: str, message: str) -> SpecError:
        return SpecError(f"{self.file}: {where}: {message}" if where else f"{self.file}: {message}")

    def keys(self, table: Mapping[str, Any], where: str, allowed: set[str]) -> None:
        unknown = set(table) - allowed
        if unknown:
            raise self.error(where, f"unknown key(s) {', '.join(sorted(unknown))}")

    def table(self, value: Any, where: str) -> dict[str, Any]:
        if not isinstance(value, dict):
            raise self.error(where, f"expected a table, got {value!r}")
        return value

    def string(self, value: Any, where: str) -> str:
        if not isinstance(value, str) or not value:
            raise self.error(where, f"expected a non-empty string, got {value!r}")
        return value

    def integer(self, value: Any, where: str) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(where, f"expected an integer, got {value!r}")
        return value

    def seed(self, value: Any, where: str) -> int:
        seed = self.integer(value, where)
        if not 0 <= seed <= MAX_SEED:
            raise self.error(where, f"expected a seed in 0..{MAX_SEED}, got {seed}")
        return seed

    def no_files(self, where: str) -> None:
        if not self.read_files:
            raise self.error(where, "this test file may not read other files")

    def number(self, value: Any, where: str) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(where, f"expected a finite number, got {value!r}")
        try:
            number = float(value)  # an integer of 400 digits is no float
        except OverflowError:
            number = math.inf
        if not math.isfinite(number):
            raise self.error(where, f"expected a finite number, got {_short(value)}")
        return number

    def seconds(self, value: Any, where: str) -> float:
        seconds = self.number(value, where)
        if seconds < 0 or seconds > 24 * 3600:
            raise self.error(where, f"expected seconds in 0..86400, got {value!r}")
        return seconds

    def case(
        self, suite: Suite, index: int, t: dict[str, Any], defaults: dict[str, Any], setup: dict[str, Any]
    ) -> Case:
        where = f"test[{index + 1}]"
        self.keys(t, where, _CASE_KEYS)
        name = self.string(t.get("name", f"test {index + 1}"), f"{where}.name")
        where = f"test {name!r}"
        merged = dict(setup)
        merged.update(self.table(t.get("setup", {}), f"{where}.setup"))
        force = self.force(t["force"], f"{where}.force") if "force" in t else None
        inputs = list(self.inputs(t.get("inputs", []), f"{where}.inputs"))
        if "inputs_file" in t:
            inputs += self.inputs_file(suite.file.resolve().parent, t["inputs_file"], f"{where}.inputs_file")
        inputs.sort(key=lambda line: line[0])
        commands = self.commands(t.get("commands", []), f"{where}.commands")
        fork = self.fork(suite.file.resolve().parent, t["from"], f"{where}.from") if "from" in t else None
        expects = t.get("expect", [])
        if not isinstance(expects, list) or not expects:
            raise self.error(where, "a test needs at least one [[test.expect]] table")
        duration = self.seconds(t.get("duration", defaults["duration"]), f"{where}.duration")
        if duration <= 0:
            raise self.error(f"{where}.duration", "must be positive")
        return Case(
            suite=suite,
            name=name,
            index=index,
            seed=self.seed(t.get("seed", defaults["seed"]), f"{where}.seed"),
            duration=duration,
            robot=self.string(t["robot"], f"{where}.robot") if "robot" in t else defaults["robot"],
            agent=self.string(t["agent"], f"{where}.agent") if "agent" in t else defaults["agent"],
            setup=merged,
            force=force,
            inputs=tuple(inputs),
            commands=commands,
            expects=tuple(
                self.expect(self.table(e, f"{where}.expect[{k + 1}]"), f"{where}.expect[{k + 1}]")
                for k, e in enumerate(expects)
            ),
            fork=fork,
        )

    def force(self, value: Any, where: str) -> tuple[str, str, Mapping[str, Any]]:
        f = self.table(value, where)
        self.keys(f, where, {"option", "behavior", "params"})
        kinds = [k for k in ("option", "behavior") if k in f]
        if len(kinds) != 1:
            raise self.error(where, "give exactly one of option, behavior")
        params = self.table(f.get("params", {}), f"{where}.params")
        return kinds[0], self.string(f[kinds[0]], f"{where}.{kinds[0]}"), params

    def inputs(self, value: Any, where: str) -> list[tuple[int, Mapping[str, Any]]]:
        if not isinstance(value, list):
            raise self.error(where, "expected an array of {t = ms, set = {...}} tables")
        return [self.input_line(line, f"{where}[{k + 1}]") for k, line in enumerate(value)]

    def input_line(self, line: Any, where: str) -> tuple[int, Mapping[str, Any]]:
        line = self.table(line, where)
        self.keys(line, where, {"t", "set", "agent"})
        if "agent" in line:
            raise self.error(where, "select the XABSL agent with the test's agent key, not per input line")
        t = self.integer(line.get("t", 0), f"{where}.t")
        if t < 0:
            raise self.error(f"{where}.t", "must be >= 0 (milliseconds since the test's start)")
        return t, self.table(line.get("set", {}), f"{where}.set")

    def inputs_file(self, base: Path, value: Any, where: str) -> list[tuple[int, Mapping[str, Any]]]:
        self.no_files(where)
        path = base / self.string(value, where)
        try:
            lines = read_regular(path, MAX_INPUTS_BYTES).decode("utf-8").splitlines()
        except (OSError, UnicodeDecodeError) as error:
            raise self.error(where, f"cannot read {path}: {error}") from None
        out = []
        for number, text in enumerate(lines, 1):
            if not text.strip():
                continue
            try:
                line = json.loads(text)
            except json.JSONDecodeError as error:
                raise SpecError(f"{path}:{number}:{error.colno}: not JSON: {error.msg}") from None
            except RecursionError:
                raise SpecError(f"{path}:{number}: not JSON: arrays or objects nested too deeply") from None
            out.append(self.input_line(line, f"{path}:{number}"))
        return out

    def commands(self, value: Any, where: str) -> tuple[tuple[int, str, Mapping[str, Any]], ...]:
        if not isinstance(value, list):
            raise self.error(where, "expected an array of {at = s, name = ..., args = {...}} tables")
        out = []
        for k, c in enumerate(value):
            w = f"{where}[{k + 1}]"
            c = self.table(c, w)
            self.keys(c, w, {"at", "name", "args"})
            at = round(self.seconds(c.get("at", 0.0), f"{w}.at") * 1000)
            out.append((at, self.string(c.get("name"), f"{w}.name"), self.table(c.get("args", {}), f"{w}.args")))
        return tuple(sorted(out, key=lambda c: c[0]))

    def fork(self, base: Path, value: Any, where: str) -> tuple[Path, int, bool]:
        self.no_files(where)
        f = self.table(value, where)
        self.keys(f, where, {"recording", "tick", "verify"})
        tick = self.integer(f.get("tick", 0), f"{where}.tick")
        if tick < 0:
            raise self.error(f"{where}.tick", "must be >= 0")
        verify = f.get("verify", True)
        if not isinstance(verify, bool):
            raise self.error(f"{where}.verify", "expected true or false")
        return base / self.string(f.get("recording"), f"{where}.recording"), tick, verify

    def expect(self, e: dict[str, Any], where: str) -> Expect:
        self.keys(e, where, _EXPECT_KEYS)
        quantifiers = [q for q in QUANTIFIERS if q in e]
        for q in ("always", "never", "eventually"):
            if q in e and e[q] is not True:
                raise self.error(f"{where}.{q}", "write it as `= true`")
        if "within" in e and not quantifiers:
            quantifiers = ["eventually"]
        if "max_changes" in e:
            if quantifiers:
                raise self.error(where, "max_changes counts over the window: no always/never/eventually/at")
            quantifiers = ["changes"]
        if len(quantifiers) != 1:
            raise self.error(where, "give exactly one of always, never, eventually (or within), at, max_changes")
        quantifier = quantifiers[0]
        start = self.seconds(e.get("from", 0.0), f"{where}.from")
        stop = self.seconds(e["until"], f"{where}.until") if "until" in e else None
        if "within" in e:
            if quantifier != "eventually" or stop is not None:
                raise self.error(f"{where}.within", "within is `eventually` with an until: give one of them")
            stop = start + self.seconds(e["within"], f"{where}.within")
        if stop is not None and stop < start:
            raise self.error(where, "until is before from")
        at = self.seconds(e["at"], f"{where}.at") if quantifier == "at" else None
        hold = self.seconds(e.get("for", 0.0), f"{where}.for")
        if hold and quantifier != "eventually":
            raise self.error(f"{where}.for", "`for` (hold so long) goes with eventually/within")
        kinds = [k for k in ("option", "behavior", "symbol") if k in e]
        if len(kinds) != 1:
            raise self.error(where, "give exactly one of option, behavior, symbol")
        kind = kinds[0]
        option = self.string(e["option"], f"{where}.option") if kind == "option" else None
        state = self.string(e["state"], f"{where}.state") if "state" in e else None
        if state is not None and option is None:
            raise self.error(f"{where}.state", "a state belongs to an option: add option = ...")
        behavior = self.string(e["behavior"], f"{where}.behavior") if kind == "behavior" else None
        params = self.table(e.get("params", {}), f"{where}.params")
        if params and kind == "symbol":
            raise self.error(f"{where}.params", "params go with option or behavior")
        for key, given in params.items():
            self.param_value(given, f"{where}.params.{key}")
        symbol = self.string(e["symbol"], f"{where}.symbol") if kind == "symbol" else None
        comparators = [c for c in COMPARATORS if c in e]
        comparator: str | None = None
        value: Any = None
        max_changes = None
        if quantifier == "changes":
            max_changes = self.integer(e["max_changes"], f"{where}.max_changes")
            if symbol is None or comparators or max_changes < 0:
                raise self.error(where, "max_changes = N (N >= 0) counts the changes of a symbol, without comparator")
        elif kind == "symbol":
            if len(comparators) != 1:
                raise self.error(where, f"a symbol needs exactly one of {', '.join(COMPARATORS)}")
            comparator = comparators[0]
            value = self.comparand(comparator, e[comparator], f"{where}.{comparator}")
        elif comparators:
            raise self.error(where, f"{comparators[0]} compares a symbol: add symbol = ...")
        robot = self.string(e["robot"], f"{where}.robot") if "robot" in e else None
        draft = Expect(
            "",
            quantifier,
            start,
            stop,
            at,
            hold,
            option,
            state,
            behavior,
            params,
            symbol,
            comparator,
            value,
            max_changes,
            robot,
        )
        text = e["name"] if isinstance(e.get("name"), str) else describe(draft)
        return replace(draft, text=text)

    def param_value(self, value: Any, where: str) -> None:
        if isinstance(value, list):
            if len(value) != 2:
                raise self.error(where, "a range is [low, high]")
            low, high = (self.number(v, where) for v in value)
            if low > high:
                raise self.error(where, f"empty range [{low}, {high}]")
        elif not isinstance(value, bool | str):
            self.number(value, where)

    def comparand(self, comparator: str, value: Any, where: str) -> Any:
        if comparator in ("below", "above"):
            return self.number(value, where)
        if comparator == "between":
            self.param_value(value, where)
            if not isinstance(value, list):
                raise self.error(where, "between = [low, high]")
            return [float(v) for v in value]
        if comparator == "one_of":
            if not isinstance(value, list) or not value:
                raise self.error(where, "one_of = [value, ...]")
            for v in value:
                self.param_value(v, where)
            return value
        if isinstance(value, list):
            raise self.error(where, f"{comparator} takes one value (a number, true/false or an enum element)")
        self.param_value(value, where)
        return value


def describe(e: Expect) -> str:
    """The assertion in words: ``eventually within 0..3 s: option striker in state kick``."""
    if e.option is not None:
        what = f"option {e.option}" + (f" in state {e.state}" if e.state else "") + " active"
    elif e.behavior is not None:
        what = f"basic behavior {e.behavior} called"
    else:
        what = f"symbol {e.symbol}"
    if e.params:
        what += " with " + ", ".join(f"{k} {_range_text(v)}" for k, v in e.params.items())
    if e.comparator is not None:
        what += f" {e.comparator.replace('_', ' ')} {_range_text(e.value)}"
    window = f"{_s(e.start)}..{_s(e.stop) if e.stop is not None else 'end'}"
    if e.quantifier == "at":
        return f"at {_s(e.at or 0.0)}: {what}"
    if e.quantifier == "changes":
        return f"{what} changes at most {e.max_changes} time(s) in {window}"
    hold = f" for {_s(e.hold)}" if e.hold else ""
    return f"{e.quantifier} in {window}: {what}{hold}"


def _range_text(value: Any) -> str:
    if isinstance(value, list) and len(value) == 2 and all(isinstance(v, int | float) for v in value):
        return f"in [{value[0]:g}, {value[1]:g}]"
    if isinstance(value, list):
        return "one of " + ", ".join(map(str, value))
    return f"= {value}"


def _short(value: Any) -> str:
    """``value`` for a message: at most 60 characters of its repr."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _s(seconds: float) -> str:
    return f"{seconds:g} s"
