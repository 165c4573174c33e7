"""Runs one behavior test: build the world, set it up, run the agent or the forced root, assert tick by tick.

The world comes from the suite's world plug-in (``xabsl_studio.engine.worlds.loader.load_example``: the example
folder's ``studio.py``, a world named with ``world =``, else the bench world); its programs are
compiled once per process. A test's world-specific ``setup`` goes to the plug-in's
``arrange(world, setup)`` (:class:`ArrangeableExample`; the soccer world places robots and the
ball and sets the game state), timed ``inputs`` become input overrides of the tested robot's
engine (``engine.root_actions``), timed ``commands`` go to ``CommandableWorld.command``.

A test ends at its duration, or as soon as every assertion is decided. When one fails and a
recording folder is given, the test runs again, identically (the world is a pure function of its
seed and the stimuli), under an ``xabsl_studio.engine.record.Recorder``: the failing tick of the result is
the recording's tick ``seq`` (its tick 0 is the test's first tick).
"""

from __future__ import annotations

import hashlib
import re
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

from xabsl_studio.engine.errors import XabslError
from xabsl_studio.engine.files import check_regular
from xabsl_studio.engine.host import BehaviorLoop, CommandableWorld, World, WorldCommandError
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.record import Recorder, Recording, RecordingError
from xabsl_studio.engine.record.fork import resimulate
from xabsl_studio.engine.record.writer import engines_of
from xabsl_studio.engine.runtime import Engine
from xabsl_studio.engine.testing.coverage import Coverage
from xabsl_studio.engine.testing.expect import AssertionSpecError, Failure, Monitor, TickView
from xabsl_studio.engine.testing.spec import Case, Expect, Suite

__all__ = ["ArrangeableExample", "CaseResult", "TestSetupError", "run_case"]


@runtime_checkable
class ArrangeableExample(Protocol):
    """Optional part of a world plug-in: put a freshly built world into a test's situation."""

    def arrange(self, world: World, setup: Mapping[str, Any]) -> None:
        """Apply ``setup`` (the world's documented keys) to ``world`` before its first tick.

        Raises:
            ValueError: an unknown key or a bad value (the message names it).
        """
        ...


class TestSetupError(XabslError, ValueError):
    """A test that cannot run as written: unknown robot, option, symbol, setup key, a broken behavior."""

    __test__ = False  # not a pytest class


@dataclass(slots=True)
class CaseResult:
    """What one test did: passed, failed (failures) or error (it could not run); picklable."""

    id: str
    suite: str
    name: str
    file: str
    status: str = "passed"
    failures: list[Failure] = field(default_factory=list)
    error: str | None = None
    ticks: int = 0
    seconds: float = 0.0
    coverage: Coverage | None = None
    recording: str | None = None
    recording_tick: int | None = None

    @property
    def ok(self) -> bool:
        """True when the test passed."""
        return self.status == "passed"

    def report(self) -> str:
        """The failure or error, several lines; empty when it passed."""
        if self.status == "error":
            return f"{self.id}: error: {self.error}"
        lines = [f"{self.id}: FAILED"]
        lines += [f"  {f.message()}" for f in self.failures]
        if self.recording is not None:
            lines.append(f"  recording: {self.recording} (tick {self.recording_tick})")
        return "\n".join(lines)


# -- compiled programs and plug-ins, once per process --------------------------------------------------

_PLUGINS: dict[tuple[str, str | None, str], Any] = {}
_PROGRAMS: dict[tuple[str, float], Program] = {}


def _plugin(suite: Suite) -> Any:
    from xabsl_studio.engine.worlds.loader import load_example  # the plug-in loader (imports no world itself)

    key = (str(suite.path), suite.world, repr(sorted(suite.options.items())))
    plugin = _PLUGINS.get(key)
    if plugin is None:
        plugin = _PLUGINS[key] = load_example(suite.path, suite.world, **dict(suite.options))
    return plugin


def _program(agents_file: Path) -> Program:
    from xabsl_studio.engine.lang import compile_file

    # Keyed by the newest modification time of the behavior's files, so an edited behavior is recompiled.
    stamp = max((p.stat().st_mtime for p in agents_file.parent.rglob("*.xabsl")), default=0.0)
    key = (str(agents_file), stamp)
    program = _PROGRAMS.get(key)
    if program is None:
        compilation = compile_file(str(agents_file), str(agents_file.parent))
        if compilation.program is None:
            errors = "; ".join(d.format() for d in compilation.diagnostics[:5])
            raise TestSetupError(f"{agents_file}: the behavior does not compile: {errors}")
        program = _PROGRAMS[key] = compilation.program
    return program


# -- one run ---------------------------------------------------------------------------------------------


class _Run:
    """One run of a case: the world, the loop, the tested engine, the monitors."""

    def __init__(self, case: Case) -> None:
        self.case = case
        self.plugin = _plugin(case.suite)
        self.programs = {source.key: _program(source.agents_file) for source in self.plugin.sources}
        if case.fork is not None:
            self.loop = self._fork(*case.fork)
        else:
            world = self._build(case.seed)
            self._arrange(world)
            self.loop = BehaviorLoop(world, self.plugin.physics_hz, self.plugin.behavior_hz)
        self.world = self.loop.world
        names = [a.name for a in self.world.agents]
        self.engines: dict[str, Engine] = {
            a.name: e for a, e in zip(self.world.agents, engines_of(self.world), strict=True) if e is not None
        }
        if case.robot is None:
            if not self.engines:
                raise TestSetupError("the world has no robot running an XABSL engine")
            self.robot = next(iter(self.engines))
        elif case.robot not in self.engines:
            raise TestSetupError(f"no robot {case.robot!r} runs an XABSL engine (robots: {', '.join(names)})")
        else:
            self.robot = case.robot
        self.engine = self.engines[self.robot]
        for e in case.expects:
            if e.robot is not None and e.robot not in self.engines:
                raise TestSetupError(f"{e.text}: no robot {e.robot!r} runs an XABSL engine")
        self._check_names(case.expects)
        try:
            if case.agent is not None:
                self.engine.root_actions.select_agent(case.agent)
            if case.force is not None:
                kind, name, params = case.force
                force = (
                    self.engine.root_actions.force_option
                    if kind == "option"
                    else self.engine.root_actions.force_behavior
                )
                force(name, params)
        except (XabslError, ValueError) as error:
            raise TestSetupError(str(error)) from None
        self.start_ms = self.loop.now_ms

    def _build(self, seed: int) -> World:
        try:
            world: World = self.plugin.build_world(seed)
        except (ValueError, TypeError) as error:  # the world refused its seed or options
            raise TestSetupError(f"the {self.plugin.name} world cannot be built: {error}") from None
        for agent in world.agents:
            key = self.plugin.program_key(agent)
            if key is None:
                continue
            controller, _engine = self.plugin.make_controller(agent, self.programs[key])
            agent.controller = controller
        return world

    def _arrange(self, world: World) -> None:
        setup = self.case.setup
        if not setup:
            return
        example = getattr(self.plugin, "example", self.plugin)
        if not isinstance(example, ArrangeableExample):
            raise TestSetupError(f"the {self.plugin.name} world offers no setup (keys given: {', '.join(setup)})")
        try:
            example.arrange(world, setup)
        except (ValueError, TypeError) as error:
            raise TestSetupError(f"setup: {error}") from None

    def _fork(self, recording: Path, tick: int, verify: bool) -> BehaviorLoop:
        if self.case.setup:
            raise TestSetupError("a test from a recording takes the recording's situation: no setup")
        try:
            check_regular(recording)  # a FIFO or device would block the MCAP reader, or never end
            with Recording(recording) as opened:
                return resimulate(opened, self._build, tick, verify=verify)
        except (RecordingError, XabslError, OSError, ValueError) as error:
            raise TestSetupError(f"from tick {tick} of {recording}: {error}") from None

    def _check_names(self, expects: tuple[Expect, ...]) -> None:
        for e in expects:
            engine = self.engines[e.robot or self.robot]
            program = engine.program
            if e.option is not None:
                option = program.options.get(e.option)
                if option is None:
                    raise TestSetupError(f"{e.text}: the behavior has no option {e.option}")
                if e.state is not None and e.state not in {s.name for s in option.states}:
                    raise TestSetupError(f"{e.text}: option {e.option} has no state {e.state}")
            if e.behavior is not None and e.behavior not in program.behaviors:
                raise TestSetupError(f"{e.text}: the behavior has no basic behavior {e.behavior}")
            if e.symbol is not None and e.symbol not in program.outputs and e.symbol not in program.inputs:
                raise TestSetupError(f"{e.text}: the behavior has no symbol {e.symbol}")

    def run(
        self, recorder: Recorder | None = None, stop_after: int | None = None
    ) -> tuple[list[Monitor], Coverage, int, Failure | None]:
        case, loop, engine = self.case, self.loop, self.engine
        monitors = [Monitor(e) for e in case.expects]
        coverage = Coverage()
        # Keyed by world and program: two examples may both call their program "behavior".
        program_key = self.plugin.program_key(next(a for a in self.world.agents if a.name == self.robot))
        key = f"{self.plugin.name}/{program_key}"
        coverage.add_program(key, engine.program)
        period = 1000.0 / self.plugin.behavior_hz
        ticks = max(1, round(case.duration * 1000 / period))
        inputs, commands = list(case.inputs), list(case.commands)
        fault: Failure | None = None
        tick = 0
        for tick in range(ticks):
            now = loop.now_ms
            t = now - self.start_ms
            while inputs and inputs[0][0] <= t:
                values = inputs.pop(0)[1]
                if recorder is not None:
                    for symbol, value in values.items():
                        recorder.event("override", now, self.robot, symbol=symbol, value=value)
                self._apply_inputs(values, now)
            while commands and commands[0][0] <= t:
                _at, name, args = commands.pop(0)
                if recorder is not None:
                    recorder.event("note", now, None, text=f"world command {name} {dict(args)}")
                self._command(name, args)
            loop.tick()
            if recorder is not None:
                recorder.on_tick(now)
            tree = engine.activation()
            coverage.add(key, tree)
            view = TickView(tick, t, tree, engine)
            for monitor in monitors:
                other = monitor.expect.robot
                if other is None or other == self.robot:
                    monitor.observe(view, engine)
                else:
                    e = self.engines[other]
                    monitor.observe(TickView(tick, t, e.activation(), e), e)
            if engine.fault is not None:
                fault = Failure(Expect("the behavior runs without a fault", "always"), tick, t, str(engine.fault))
                break
            # A recording run goes on past the decisions: a second after the failing tick.
            if stop_after is not None:
                if tick >= stop_after:
                    break
            elif all(m.decided for m in monitors):
                break
            if self.world.finished:
                break
        for monitor in monitors:
            monitor.finish()
        return monitors, coverage, tick + 1, fault

    def _apply_inputs(self, values: Mapping[str, Any], now: int) -> None:
        try:
            for name, value in values.items():
                self.engine.root_actions.override_input(name, value)
        except (XabslError, ValueError) as error:
            raise TestSetupError(f"inputs at t = {now - self.start_ms} ms: {error}") from None

    def _command(self, name: str, args: Mapping[str, Any]) -> None:
        if not isinstance(self.world, CommandableWorld):
            raise TestSetupError(f"the {self.plugin.name} world has no commands (command {name!r})")
        try:
            self.world.command(name, dict(args))
        except WorldCommandError as error:
            raise TestSetupError(f"command {name}: {error}") from None


def run_case(case: Case, recordings: Path | None = None, record_all: bool = False) -> CaseResult:
    """Run ``case``; on a failure with ``recordings`` set, leave a recording of the run in that folder.

    With ``record_all`` (and ``recordings``) every run is recorded, passed or failed, in the one run
    the test makes; otherwise a failing test is run again under a recorder (a passing one costs no
    recording).
    """
    result = CaseResult(case.id, case.suite.name, case.name, str(case.suite.file))
    started = time.perf_counter()
    try:
        if record_all and recordings is not None:
            path, (monitors, coverage, ticks, fault) = _recorded_run(case, recordings)
            result.recording = str(path.resolve())
        else:
            monitors, coverage, ticks, fault = _Run(case).run()
    except (TestSetupError, AssertionSpecError) as error:
        result.status, result.error = "error", str(error)
        result.seconds = time.perf_counter() - started
        return result
    except XabslError as error:  # the world plug-in or the behavior refused
        result.status, result.error = "error", f"{type(error).__name__}: {error}"
        result.seconds = time.perf_counter() - started
        return result
    result.ticks, result.coverage = ticks, coverage
    result.failures = [m.failure for m in monitors if m.failure is not None]
    if fault is not None:
        result.failures.append(fault)
    if result.failures:
        result.status = "failed"
        if recordings is not None:
            first = min(f.tick for f in result.failures)
            if result.recording is None:
                result.recording = str(_record(case, recordings, first).resolve())
            result.recording_tick = first
    result.seconds = time.perf_counter() - started
    return result


#: The longest recording name before ``.mcap`` (file systems take 255 bytes; ASCII here).
MAX_RECORDING_STEM = 200


def recording_name(case: Case) -> str:
    """The file name of a failing test's recording: ``suite--test.mcap`` with safe characters.

    A name longer than :data:`MAX_RECORDING_STEM` is cut and ends in a digest of the whole id, so
    two long names that share their start still leave two recordings.
    """
    stem = re.sub(r"[^A-Za-z0-9_.-]+", "_", f"{case.suite.name}--{case.name}")
    if len(stem) > MAX_RECORDING_STEM:
        digest = hashlib.sha256(case.id.encode("utf-8", "surrogatepass")).hexdigest()[:12]
        stem = f"{stem[: MAX_RECORDING_STEM - 13]}-{digest}"
    return stem + ".mcap"


def _record(case: Case, folder: Path, failing_tick: int) -> Path:
    """Run ``case`` again under a recorder, up to a second past the failing tick."""
    return _recorded_run(case, folder, failing_tick + _plugin(case.suite).behavior_hz)[0]


def _recorded_run(
    case: Case, folder: Path, stop_after: int | None = None
) -> tuple[Path, tuple[list[Monitor], Coverage, int, Failure | None]]:
    """Run ``case`` under a recorder into ``folder`` (up to tick ``stop_after``): the file and what the run gave."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / recording_name(case)
    run = _Run(case)
    plugin = run.plugin
    recorder = Recorder.for_world(
        path,
        run.world,
        plugin.program_key,
        example=plugin.name,
        behavior_hz=plugin.behavior_hz,
        physics_hz=plugin.physics_hz,
        # Forced roots and overrides are session events: such a recording is not a plain seeded run.
        deterministic=case.fork is None and case.force is None and not case.inputs and not case.commands,
    )
    try:
        recorder.event("note", run.start_ms, None, text=f"behavior test {case.id}")
        if case.force is not None:
            kind, name, params = case.force
            recorder.event("force", run.start_ms, run.robot, **{kind: name, "params": dict(params)})
        outcome = run.run(recorder, stop_after=stop_after)
    except BaseException:
        recorder.abort()
        raise
    recorder.close()
    return path, outcome
