"""Worlds for the server tests that misbehave on purpose (imported by the simulation process too)."""

from __future__ import annotations

from pathlib import Path

from xabsl_studio.engine.host import World
from xabsl_studio.engine.worlds.bench import BenchExample, BenchWorld


class CrashingWorld(BenchWorld):
    """The bench world, whose physics raises while the file ``trigger`` exists."""

    def __init__(self, seed: int, n_agents: int, trigger: Path) -> None:
        super().__init__(seed, n_agents)
        self.trigger = trigger

    def step(self, dt: float) -> None:
        if self.trigger.exists():
            raise RuntimeError("the ball fell off the world")
        super().step(dt)


class CrashingDemo(BenchExample):
    """The bench world plug-in in a :class:`CrashingWorld`."""

    def __init__(self, root: Path, trigger: Path) -> None:
        super().__init__(root)
        self.trigger = trigger

    def build_world(self, seed: int) -> World:
        return CrashingWorld(seed, self.n_agents, self.trigger)
