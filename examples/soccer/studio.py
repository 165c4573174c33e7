"""How the studio runs the soccer example (the world plug-in, see ``xabsl_studio.engine.host.Example``).

``xabsl serve examples/soccer`` finds this module and calls :func:`example`: a match in
:mod:`xabsl_studio.examples.soccer.world` whose blue team (team 0) runs ``behavior/`` and whose red team runs
``chase/`` when the folder has one (else ``behavior/`` too); each robot's controller is an
:class:`xabsl_studio.examples.soccer.bindings.XabslController`. Options: ``robots`` (players per team, 1..7)
and ``half_duration_s``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from xabsl_studio.engine.host import (
    DEFAULT_BEHAVIOR_HZ,
    DEFAULT_PHYSICS_HZ,
    Agent,
    AgentController,
    BehaviorSource,
    ExampleError,
    World,
    behavior_source,
)
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.runtime import Engine

AGENTS_FILE = "agents.xabsl"


class SoccerExample:
    """The soccer match as a world plug-in.

    Args:
        root: the example folder (holding ``behavior/`` and maybe ``chase/``).
        players_per_team: robots per team (tests use 1 or 2).
        half_duration_s: seconds per half.

    Raises:
        ExampleError: ``root`` has no ``behavior/agents.xabsl``, or a team size out of 1..7.
    """

    name = "soccer"
    #: modules the simulation process imports ahead (the forkserver preloads them once)
    preload: tuple[str, ...] = ("xabsl_studio.examples.soccer.world", "xabsl_studio.examples.soccer.bindings")
    behavior_hz = DEFAULT_BEHAVIOR_HZ
    physics_hz = DEFAULT_PHYSICS_HZ

    def __init__(self, root: Path, players_per_team: int = 5, half_duration_s: float = 600.0) -> None:
        # The world checks this too, but only once built in the simulation process: say it here.
        if (
            isinstance(players_per_team, bool)
            or not isinstance(players_per_team, int)
            or not 1 <= players_per_team <= 7
        ):
            raise ExampleError(f"robots (players per team) must be an integer in 1..7, got {players_per_team!r}")
        if not half_duration_s > 0:
            raise ExampleError(f"half_duration_s must be positive, got {half_duration_s!r}")
        self.root = root.resolve()
        self.players_per_team = players_per_team
        self.half_duration_s = half_duration_s
        home = self.root / "behavior" / AGENTS_FILE
        if not home.is_file():
            raise ExampleError(f"{self.root}: the soccer world needs behavior/{AGENTS_FILE}")
        sources = [behavior_source(home, "behavior")]
        away = self.root / "chase" / AGENTS_FILE
        if away.is_file():
            sources.append(behavior_source(away, "chase"))
        self.sources: tuple[BehaviorSource, ...] = tuple(sources)

    def build_world(self, seed: int) -> World:
        """A match with ``players_per_team`` robots a side."""
        from xabsl_studio.examples.soccer.world import build_world

        return build_world(seed, players_per_team=self.players_per_team, half_duration_s=self.half_duration_s)

    def program_key(self, agent: Agent) -> str | None:
        """Team 0 (blue) plays the example team, team 1 (red) the simpler opponent when it exists."""
        away = len(self.sources) > 1 and getattr(agent, "team_index", 0) == 1
        return self.sources[1 if away else 0].key

    def make_controller(self, agent: Agent, program: Program) -> tuple[AgentController, Engine]:
        """An XABSL controller on the robot's perception and motion request."""
        from xabsl_studio.examples.soccer.bindings import XabslController
        from xabsl_studio.examples.soccer.world import SoccerAgent

        if not isinstance(agent, SoccerAgent):
            raise TypeError("the soccer example runs SoccerWorld robots")
        controller = XabslController(agent.perception, agent.motion, program, name=agent.name)
        return controller, controller.engine

    def arrange(self, world: World, setup: Mapping[str, Any]) -> None:
        """A behavior test's setup: robots, ball, game state (keys: ``xabsl_studio.examples.soccer.setup``)."""
        from xabsl_studio.examples.soccer.setup import arrange
        from xabsl_studio.examples.soccer.world import SoccerWorld

        if not isinstance(world, SoccerWorld):
            raise TypeError("the soccer setup arranges SoccerWorld matches")
        arrange(world, setup)

    def setup_from_scene(self, scene: Mapping[str, Any], status: Mapping[str, Any], names: list[str]) -> dict[str, Any]:
        """The setup that reproduces a scene ("Save as test" in the studio)."""
        from xabsl_studio.examples.soccer.setup import setup_from_scene

        return setup_from_scene(scene, status, names)


def example(path: Path, robots: int = 5, half_duration_s: float = 600.0) -> SoccerExample:
    """The soccer world plug-in for the example folder ``path`` (``robots``: players per team)."""
    return SoccerExample(path, players_per_team=robots, half_duration_s=half_duration_s)
