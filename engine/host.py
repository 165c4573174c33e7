"""The platform contract: what a simulated world provides, and the deterministic loop that runs it.

A *world* (the soccer match, the errands robot, a test double) owns physics, rules and the
perception of its agents. An *agent* is one robot or character whose behavior is an XABSL engine
(``xabsl_studio.engine.runtime``), plugged in as its :class:`AgentController`. This module names the hooks
between the two and fixes their order; it imports nothing above the engine (no pymunk, no web,
no example world), so every world and the server can share one loop.

One behavior tick (the engine's ``execute()``, xabsl-language.md §2.2) sits inside a frame of
three phases, always in this order and always for all agents before the next phase starts::

    for each agent: agent.sense(now_ms)                 # world -> the agent's input symbols
    for each agent: agent.controller.execute(now_ms)    # one engine tick: decisions + outputs
    for each agent: agent.act(now_ms)                   # output symbols -> actuators
    repeat physics_hz / behavior_hz times: world.step(1 / physics_hz)

Sensing all agents before any of them thinks means no agent sees the consequences of a teammate's
decision of the same tick, so agent order cannot leak into the behavior; agents are still visited
in ``world.agents`` order so that a run is reproducible bit for bit.

Time: the loop owns the behavior clock. ``now_ms`` is an integer (the engine's millisecond
clock, ``xabsl_studio.engine.types.Ms``) computed from the tick count, never from the wall clock, so a run is a
pure function of the world's seed and the controllers.

Worlds as plug-ins: an :class:`Example` is what the studio (``xabsl serve``) needs to run one
world with XABSL engines: the behavior sources to compile, a world per seed, which program each
robot runs and the controller that runs it. A folder declares its world with a module
``studio.py`` exposing ``example(path, **options) -> Example`` (or an installed distribution
registers such a factory under the entry-point group :data:`WORLDS_GROUP`); the loader is
``xabsl_studio.engine.worlds.loader.load_example``. docs/architecture.md describes the contract.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from time import perf_counter
from typing import TYPE_CHECKING, Any, Protocol, TypeAlias, runtime_checkable

from xabsl_studio.engine.errors import HostError
from xabsl_studio.engine.types import Ms

if TYPE_CHECKING:  # the loop itself needs neither the IR nor the runtime
    from xabsl_studio.engine.ir.model import Program
    from xabsl_studio.engine.runtime import Engine

#: A scene or status: JSON-able plain data (dicts, lists, str, int, float, bool, None) that
#: ``orjson.dumps`` accepts without options. Worlds document their own keys; the studio's field
#: draws these without knowing the world (lengths in the scene's ``units``, mm by default):
#:
#: * static: ``field`` ``{"x": [lo, hi], "y": [lo, hi]}`` (the rectangle shown), ``walls``
#:   ``[[x1, y1, x2, y2], ...]``, ``teams`` ``[{"name", "color"}]``, ``agents``, ``robot_radius``;
#: * dynamic: ``robots`` ``[[x, y, heading_deg], ...]`` in agent order;
#: * both: ``shapes``, a list of ``{"shape": "circle", "x", "y", "r"}``, ``{"shape": "rect",
#:   "x", "y", "w", "h"}`` (centre and size) or ``{"shape": "segment", "x1", "y1", "x2", "y2"}``,
#:   each with optional ``fill``, ``stroke`` (CSS colours), ``dash`` (bool), ``label`` (text on
#:   the shape) and ``caption`` (text below it).
Scene: TypeAlias = dict[str, Any]

#: The default physics rate. 120 Hz keeps a kicked ball (at most ~5 m/s) under one ball radius
#: per step, which is what discrete collision detection needs, and costs half of 240 Hz.
DEFAULT_PHYSICS_HZ = 120

#: The default behavior rate. 40 Hz (25 ms ticks) is close to the 30 Hz camera / 33 ms cognition
#: cycle of SPL robots, gives integer millisecond ticks (25 ms, unlike 30 Hz's 33.3 ms) and
#: divides the physics rate (3 substeps at 120 Hz, 5 at 200 Hz). Faster would cost engine time
#: without changing what a walking robot can do in one tick.
DEFAULT_BEHAVIOR_HZ = 40


@runtime_checkable
class AgentController(Protocol):
    """The brain slot of an agent: an XABSL engine, or a scripted stand-in in tests.

    Hook, called by the loop once per behavior tick, after every agent has sensed. It reads the
    agent's input symbols (its perception) and writes output symbols (its commands); it must not
    step the world or touch other agents.
    """

    def execute(self, now_ms: Ms) -> None:
        """Run one behavior tick at the engine time ``now_ms``."""
        ...


@runtime_checkable
class Agent(Protocol):
    """One acting entity of a world, identified by team and number.

    ``name`` is unique in its world (the studio selects agents by it). ``controller`` is ``None``
    for an agent that only follows its last commands (for instance, a dummy opponent).
    """

    name: str
    team: str
    number: int
    controller: AgentController | None

    def sense(self, now_ms: Ms) -> None:
        """Update this agent's perception from the world state at ``now_ms``.

        Hook, called before any controller of the tick runs. Must not change the world.
        """
        ...

    def act(self, now_ms: Ms) -> None:
        """Turn the commands the controller wrote into actuator settings.

        Hook, called after every controller of the tick ran. May change actuators (motor targets,
        impulses) but must not advance time; physics happens in ``World.step``.
        """
        ...


@runtime_checkable
class World(Protocol):
    """A simulated world that hosts agents.

    ``seed`` is the only source of randomness: building a world twice with the same seed and
    running the same controllers gives identical dynamic scenes.
    """

    seed: int

    @property
    def agents(self) -> Sequence[Agent]:
        """The agents, in the fixed order the loop visits them."""
        ...

    @property
    def finished(self) -> bool:
        """True once the world has nothing left to simulate (a match is over)."""
        ...

    def step(self, dt: float) -> None:
        """Advance physics and world rules (referee, goals) by ``dt`` seconds."""
        ...

    def static_scene(self) -> Scene:
        """Return what never moves (field lines, goals, walls, beacons); the UI gets it once."""
        ...

    def dynamic_scene(self) -> Scene:
        """Return what moves (poses, ball, objects), compact; the UI gets it every frame."""
        ...

    def status(self) -> Scene:
        """Return score, game state and time; always has ``time_ms`` (int) and ``finished`` (bool)."""
        ...


class WorldCommandError(HostError, ValueError):
    """A world command that cannot be carried out (unknown name, bad arguments); the world is unchanged."""


@runtime_checkable
class CommandableWorld(Protocol):
    """Optional part of :class:`World`: commands of the world itself (studio op ``world_command``).

    Perturbations, forcing world-side state, queries of world data: whatever the world offers,
    named and described so that a client can render them without knowing the world. The
    simulation process calls :meth:`command` between two ticks.
    """

    def commands(self) -> list[dict[str, Any]]:
        """Describe the commands, each one ``{"name", "label", "doc", "group", "args"}``.

        ``args`` lists ``{"name", "type", "choices", "default"}``, ``type`` one of ``enum``,
        ``number``, ``bool``, ``string`` (docs/protocol.md, ``world_command``).
        """
        ...

    def command(self, name: str, args: dict[str, Any]) -> Any:
        """Carry out command ``name`` with ``args``; return JSON-able plain data (or None).

        Raises:
            WorldCommandError: unknown command or bad arguments.
        """
        ...


#: The entry-point group under which installed distributions register world factories
#: (``name = "package.module:example"``); ``xabsl serve PATH --world NAME`` picks one.
WORLDS_GROUP = "xabsl.worlds"

#: The module an example folder holds to say how the studio runs it.
STUDIO_MODULE = "studio"

#: The attribute of :data:`STUDIO_MODULE` that builds the folder's :class:`Example`.
STUDIO_FACTORY = "example"


@dataclass(frozen=True, slots=True)
class BehaviorSource:
    """One behavior set of an example: the agents file compiled as one program, named ``key``.

    Attributes:
        key: the program's name in the session (``behavior``, ``chase``); robots run it by key.
        folder: the folder the agents file lies in.
        agents_file: the agents file, root of the include closure.
        folders: every folder of the include closure (the studio serves the behavior's files
            from these only); empty means just ``folder``.
    """

    key: str
    folder: Path
    agents_file: Path
    folders: tuple[Path, ...] = ()

    @property
    def file_folders(self) -> tuple[Path, ...]:
        """The folders whose files belong to this behavior set (``folders``, else ``folder``)."""
        return self.folders or (self.folder,)


class ExampleError(HostError, ValueError):
    """A path the studio cannot run: no such folder, no behavior, a broken plug-in, bad options."""


def behavior_source(agents_file: Path, key: str | None = None) -> BehaviorSource:
    """The behavior set of ``agents_file``, with the folders of its include closure.

    Args:
        agents_file: the agents file (any name, anywhere on disk).
        key: the program's name; defaults to the folder's name for ``agents.xabsl``, else the
            file's stem.

    Raises:
        ExampleError: ``agents_file`` is not a file.
    """
    from xabsl_studio.engine.lang.diagnostics import Diagnostics
    from xabsl_studio.engine.lang.loader import load

    agents_file = agents_file.resolve()
    if not agents_file.is_file():
        raise ExampleError(f"{agents_file}: no such agents file")
    folder = agents_file.parent
    if key is None:
        key = folder.name if agents_file.name == "agents.xabsl" else agents_file.stem
    # Display names are relative to the agents file's folder, or absolute outside it.
    loaded = load(str(agents_file), Diagnostics(), str(folder))
    found = {(folder / f.path).resolve().parent for f in loaded.files} | {folder}
    # A folder below another one adds nothing: the studio serves subfolders too.
    folders = tuple(sorted(f for f in found if not any(f != g and f.is_relative_to(g) for g in found)))
    return BehaviorSource(key, folder, agents_file, folders)


def common_root(sources: Sequence[BehaviorSource]) -> Path:
    """The deepest folder holding every file folder of ``sources`` (API paths are relative to it)."""
    folders = [str(f) for s in sources for f in s.file_folders]
    return Path(os.path.commonpath(folders)) if folders else Path.cwd()


@runtime_checkable
class Example(Protocol):
    """A world plug-in: what the studio needs to run one world whose robots run XABSL agents.

    Attributes:
        name: shown in the studio's title and status.
        root: the folder the studio's file paths and diagnostics are relative to.
        sources: the behavior sets to compile (one program each).
        preload: modules the simulation process imports ahead (the forkserver preloads them once,
            so starting and resetting a simulation stays cheap).
        behavior_hz, physics_hz: the rates the world is built for (see :class:`BehaviorLoop`).
    """

    # Read-only properties, so that a plain attribute or a property both implement them.
    @property
    def name(self) -> str:
        """The example's name, shown in the studio."""
        ...

    @property
    def root(self) -> Path:
        """The folder file paths and diagnostics are relative to."""
        ...

    @property
    def sources(self) -> Sequence[BehaviorSource]:
        """The behavior sets to compile, one program each."""
        ...

    @property
    def preload(self) -> Sequence[str]:
        """Modules the simulation process imports ahead."""
        ...

    @property
    def behavior_hz(self) -> int:
        """Behavior ticks per simulated second the world is built for."""
        ...

    @property
    def physics_hz(self) -> int:
        """Physics steps per simulated second the world is built for."""
        ...

    def build_world(self, seed: int) -> World:
        """Return a fresh world for ``seed``; its agents have no controllers yet."""
        ...

    def program_key(self, agent: Agent) -> str | None:
        """Return the key of the behavior set ``agent`` runs (None: no XABSL engine)."""
        ...

    def make_controller(self, agent: Agent, program: Program) -> tuple[AgentController, Engine]:
        """Return ``agent``'s controller for ``program`` and the engine inside it.

        Raises:
            xabsl_studio.engine.runtime.EngineError: the program does not link with this world's bindings.
        """
        ...


#: What ``studio.py`` and the :data:`WORLDS_GROUP` entry points provide:
#: ``example(path, **options)``, ``path`` being the folder or file the user named.
ExampleFactory: TypeAlias = Callable[..., Example]


@dataclass(slots=True)
class PhaseTimes:
    """Wall-clock seconds spent per phase of the loop, for benchmarks.

    Measured once per phase per tick (not per agent), so measuring costs a few
    ``perf_counter`` calls per tick whatever the number of agents.
    """

    perception: float = 0.0
    engine: float = 0.0
    actuation: float = 0.0
    physics: float = 0.0

    @property
    def total(self) -> float:
        """Seconds measured over all phases."""
        return self.perception + self.engine + self.actuation + self.physics

    def shares(self) -> dict[str, float]:
        """Each phase's fraction of the measured total (0..1); zeros if nothing was measured."""
        total = self.total
        if total <= 0.0:
            return {"perception": 0.0, "engine": 0.0, "actuation": 0.0, "physics": 0.0}
        return {
            "perception": self.perception / total,
            "engine": self.engine / total,
            "actuation": self.actuation / total,
            "physics": self.physics / total,
        }


@dataclass(slots=True)
class RunStats:
    """What :func:`run_headless` did: ticks, simulated and wall time, time per phase."""

    ticks: int = 0
    physics_steps: int = 0
    sim_seconds: float = 0.0
    wall_seconds: float = 0.0
    phases: PhaseTimes = field(default_factory=PhaseTimes)

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall second (``inf`` if the wall time was too small to see)."""
        return self.sim_seconds / self.wall_seconds if self.wall_seconds > 0.0 else float("inf")


class BehaviorLoop:
    """Steps a world tick by tick: sense, think, act, then fixed-rate physics substeps.

    The headless runner drives it as fast as possible; the studio's simulation thread drives the
    same object at real time times a speed factor, so both see the same sequence of states.

    Args:
        world: the world to run.
        physics_hz: physics steps per simulated second (>= 100).
        behavior_hz: behavior ticks per simulated second (30..50); must divide ``physics_hz``.
        start_ms: the engine time of the first tick.

    Raises:
        ValueError: if the rates are out of range or do not divide.
    """

    __slots__ = ("_period_ms", "_physics_dt", "_substeps", "phases", "physics_steps", "start_ms", "ticks", "world")

    def __init__(
        self,
        world: World,
        physics_hz: int = DEFAULT_PHYSICS_HZ,
        behavior_hz: int = DEFAULT_BEHAVIOR_HZ,
        start_ms: Ms = 0,
    ) -> None:
        if physics_hz < 100:
            raise ValueError(f"physics_hz must be at least 100, got {physics_hz}")
        if not 30 <= behavior_hz <= 50:
            raise ValueError(f"behavior_hz must be between 30 and 50, got {behavior_hz}")
        if physics_hz % behavior_hz:
            raise ValueError(f"behavior_hz ({behavior_hz}) must divide physics_hz ({physics_hz})")
        self.world = world
        self._substeps = physics_hz // behavior_hz
        self._physics_dt = 1.0 / physics_hz
        self._period_ms = 1000.0 / behavior_hz
        self.start_ms = start_ms
        self.ticks = 0
        self.physics_steps = 0
        self.phases = PhaseTimes()

    @property
    def now_ms(self) -> Ms:
        """The engine time of the next tick."""
        # Rounded from the tick count rather than accumulated, so 30 Hz (33.33 ms) never drifts.
        return self.start_ms + round(self.ticks * self._period_ms)

    @property
    def sim_seconds(self) -> float:
        """Simulated seconds covered by the ticks run so far."""
        return self.physics_steps * self._physics_dt

    def tick(self) -> None:
        """Run one behavior tick and the physics substeps that follow it."""
        now = self.now_ms
        agents = self.world.agents
        phases = self.phases

        t0 = perf_counter()
        for agent in agents:
            agent.sense(now)
        t1 = perf_counter()
        for agent in agents:
            controller = agent.controller
            if controller is not None:
                controller.execute(now)
        t2 = perf_counter()
        for agent in agents:
            agent.act(now)
        t3 = perf_counter()
        step = self.world.step
        dt = self._physics_dt
        for _ in range(self._substeps):
            step(dt)
        t4 = perf_counter()

        phases.perception += t1 - t0
        phases.engine += t2 - t1
        phases.actuation += t3 - t2
        phases.physics += t4 - t3
        self.ticks += 1
        self.physics_steps += self._substeps


def run_headless(
    world: World,
    duration_s: float,
    physics_hz: int = DEFAULT_PHYSICS_HZ,
    behavior_hz: int = DEFAULT_BEHAVIOR_HZ,
    on_tick: Callable[[Ms], bool | None] | None = None,
    stop_when_finished: bool = True,
) -> RunStats:
    """Run a world without a UI as fast as the machine allows, deterministically.

    The behavior rate defaults to 40 Hz (see :data:`DEFAULT_BEHAVIOR_HZ`: close to an SPL
    robot's 30 Hz cognition cycle, integer 25 ms ticks, divides the physics rate) and physics to
    120 Hz (see :data:`DEFAULT_PHYSICS_HZ`). The result depends only on the world's seed and
    its controllers, never on the wall clock.

    Args:
        world: the world to run, agents' controllers already plugged in.
        duration_s: simulated seconds to run at most (rounded up to whole behavior ticks).
        physics_hz: physics steps per simulated second (>= 100).
        behavior_hz: behavior ticks per simulated second (30..50), dividing ``physics_hz``.
        on_tick: called after each tick with the tick's ``now_ms``; returning True stops the run.
        stop_when_finished: stop as soon as ``world.finished`` is true.

    Returns:
        The number of ticks, simulated and wall seconds, and seconds spent per phase.

    Example::

        stats = run_headless(build_world(seed=1), duration_s=600)
        print(stats.real_time_factor, stats.phases.shares())
    """
    loop = BehaviorLoop(world, physics_hz, behavior_hz)
    ticks = max(0, -(-round(duration_s * behavior_hz * 1000) // 1000))  # ceil, robust to 0.1 + 0.2
    wall_start = perf_counter()
    for _ in range(ticks):
        if stop_when_finished and world.finished:
            break
        now = loop.now_ms
        loop.tick()
        if on_tick is not None and on_tick(now):
            break
    return RunStats(
        ticks=loop.ticks,
        physics_steps=loop.physics_steps,
        sim_seconds=loop.sim_seconds,
        wall_seconds=perf_counter() - wall_start,
        phases=loop.phases,
    )
