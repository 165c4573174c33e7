"""Adapters from an example folder to what a session runs: a world, behavior sources, engines.

The server does not know worlds; an :class:`Example` tells it, for one example folder:

* ``sources``: the behavior folders (one compiled program each, keyed by the folder's path
  relative to the example, e.g. ``behavior`` and ``chase``) and their agents files;
* ``build_world(seed)``: a fresh world without controllers;
* ``program_key(agent)``: which behavior an agent runs (``None``: no XABSL engine);
* ``make_controller(agent, program)``: the agent's ``AgentController`` and the
  :class:`engine.runtime.Engine` inside it, so the session can sample, steer and hot-reload it.

Two adapters exist: :class:`SoccerExample` (``examples/soccer``: the home team runs
``behavior/``, the away team ``chase/`` when present) and :class:`DemoExample` (any folder whose
top level holds ``agents.xabsl``, run in :mod:`server.demo_world`). :func:`load_example` picks one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

from engine.errors import HostError
from engine.host import Agent, AgentController, World
from engine.ir.model import Program
from engine.runtime import Engine

AGENTS_FILE = "agents.xabsl"


class ExampleError(HostError, ValueError):
    """The folder is not an example the studio can run."""


@dataclass(frozen=True, slots=True)
class BehaviorSource:
    """One behavior folder: compiled as one program, identified by ``key``."""

    key: str
    folder: Path
    agents_file: Path


class Example(Protocol):
    """What the session needs from an example folder (see the module docstring)."""

    name: str
    root: Path
    sources: Sequence[BehaviorSource]

    def build_world(self, seed: int) -> World: ...

    def program_key(self, agent: Agent) -> str | None: ...

    def make_controller(self, agent: Agent, program: Program) -> tuple[AgentController, Engine]: ...


def _source(root: Path, folder: Path, fallback_key: str) -> BehaviorSource:
    folder = folder.resolve()
    relative = folder.relative_to(root).as_posix()
    return BehaviorSource(relative if relative != "." else fallback_key, folder, folder / AGENTS_FILE)


class SoccerExample:
    """``examples/soccer``: SoccerWorld, XABSL controllers from ``examples.soccer.bindings``.

    Args:
        root: the example folder.
        players_per_team: robots per team (tests use 1 or 2).
        half_duration_s: seconds per half.
    """

    def __init__(self, root: Path, players_per_team: int = 5, half_duration_s: float = 600.0) -> None:
        self.name = "soccer"
        #: modules the simulation process imports ahead (the forkserver preloads them once)
        self.preload = ("examples.soccer.world", "examples.soccer.bindings")
        self.root = root.resolve()
        self.players_per_team = players_per_team
        self.half_duration_s = half_duration_s
        home = _source(self.root, self.root / "behavior", "behavior")
        sources = [home]
        if (self.root / "chase" / AGENTS_FILE).is_file():
            sources.append(_source(self.root, self.root / "chase", "chase"))
        self.sources = tuple(sources)

    def build_world(self, seed: int) -> World:
        from examples.soccer.world import build_world

        return build_world(seed, players_per_team=self.players_per_team, half_duration_s=self.half_duration_s)

    def program_key(self, agent: Agent) -> str | None:
        # Team 0 (blue) plays the example team, team 1 (red) the simpler opponent when it exists.
        away = len(self.sources) > 1 and getattr(agent, "team_index", 0) == 1
        return self.sources[1 if away else 0].key

    def make_controller(self, agent: Agent, program: Program) -> tuple[AgentController, Engine]:
        from examples.soccer.bindings import XabslController

        soccer_agent: Any = agent
        controller = XabslController(soccer_agent.perception, soccer_agent.motion, program, name=agent.name)
        return controller, controller.engine


class DemoExample:
    """A behavior folder without a world: runs in :class:`server.demo_world.DemoWorld`."""

    def __init__(self, root: Path, n_agents: int = 2) -> None:
        self.root = root.resolve()
        self.name = self.root.name
        self.n_agents = n_agents
        self.sources = (_source(self.root, self.root, self.root.name),)

    def build_world(self, seed: int) -> World:
        from server.demo_world import DemoWorld

        return DemoWorld(seed, self.n_agents)

    def program_key(self, agent: Agent) -> str | None:
        return self.sources[0].key

    def make_controller(self, agent: Agent, program: Program) -> tuple[AgentController, Engine]:
        from server.demo_world import DemoAgent, DemoController

        assert isinstance(agent, DemoAgent), "the demo example runs DemoWorld agents"
        controller = DemoController(agent, program)
        return controller, controller.engine


def load_example(folder: str | Path, **options: Any) -> Example:
    """The adapter for an example folder.

    Args:
        folder: ``examples/soccer``, ``examples/demo`` or any folder with ``agents.xabsl``.
        **options: adapter options (``players_per_team``, ``half_duration_s``, ``n_agents``).

    Raises:
        ExampleError: the folder does not exist or holds no behavior the studio knows how to run.
    """
    root = Path(folder).resolve()
    if not root.is_dir():
        raise ExampleError(f"{folder}: no such folder")
    if (root / "world.py").is_file() and (root / "behavior").is_dir() and root.name == "soccer":
        return SoccerExample(root, **options)
    if (root / AGENTS_FILE).is_file():
        return DemoExample(root, **options)
    raise ExampleError(f"{folder}: neither the soccer example nor a folder with {AGENTS_FILE}")
