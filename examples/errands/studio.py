"""How the studio runs the errands example (the world plug-in, see ``xabsl_studio.engine.host.Example``).

``xabsl serve examples/errands`` finds this module and calls :func:`example`: the errands robot
of :mod:`xabsl_studio.examples.errands.world` (the arena, Dual Dynamics, derived facts, the plan board) whose
controller is the XABSL plan monitor compiled from ``behavior/`` by the studio, so that the
option graph, the symbols, forcing and hot reload work on it like on any behavior. The world is
built for a 20 ms tick (50 Hz, physics at 100 Hz), as ``xabsl run examples/errands``.

Options: ``plan`` (default True: XABSL agent ``planner``; False: ``reactive``), ``noise`` (the DD
noise factor) and ``robots`` (only 1: the errands world has one robot).
"""

from __future__ import annotations

import math
from pathlib import Path

from xabsl_studio.engine.host import Agent, AgentController, BehaviorSource, ExampleError, World, behavior_source
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.runtime import Engine

#: The tick of the example (s): the rates below follow from it.
DT = 0.02


class ErrandsExample:
    """The errands robot as a world plug-in.

    Args:
        root: the example folder (holding ``behavior/agents.xabsl``).
        plan: run the plan monitor (``planner``) or the reactive robot (``reactive``).
        noise: multiplies the DD model's σ (0: deterministic dynamics).

    Raises:
        ExampleError: ``root`` has no ``behavior/agents.xabsl``, or a bad option.
    """

    name = "errands"
    preload: tuple[str, ...] = ("xabsl_studio.examples.errands.world", "pymunk", "numpy")
    behavior_hz = 50
    physics_hz = 100

    def __init__(self, root: Path, plan: bool = True, noise: float = 1.0) -> None:
        if not isinstance(plan, bool):
            raise ExampleError(f"plan must be true or false, got {plan!r}")
        if isinstance(noise, bool) or not isinstance(noise, int | float) or not math.isfinite(noise) or noise < 0:
            raise ExampleError(f"noise must be a finite number >= 0, got {noise!r}")
        self.root = root.resolve()
        agents = self.root / "behavior" / "agents.xabsl"
        if not agents.is_file():
            raise ExampleError(f"{self.root}: the errands world needs behavior/agents.xabsl")
        self.plan = plan
        self.noise = float(noise)
        self.sources: tuple[BehaviorSource, ...] = (behavior_source(agents, "behavior"),)

    def build_world(self, seed: int) -> World:
        """The errands world of §1.5, without a controller until :meth:`make_controller`."""
        from xabsl_studio.examples.errands.commands import StudioErrandsWorld
        from xabsl_studio.examples.errands.world import MODEL_PATH

        model = self.root / "model" / "errands_dd.json"  # the served folder's model, if it has one
        return StudioErrandsWorld(
            seed,
            plan=self.plan,
            dt=DT,
            noise=self.noise,
            controller=False,
            model_path=model if model.is_file() else MODEL_PATH,
        )

    def program_key(self, agent: Agent) -> str | None:
        """The robot runs the plan monitor."""
        return self.sources[0].key

    def make_controller(self, agent: Agent, program: Program) -> tuple[AgentController, Engine]:
        """The plan monitor's engine on the world's bindings (the robot's controller)."""
        from xabsl_studio.examples.errands.world import ErrandsAgent

        if not isinstance(agent, ErrandsAgent):
            raise TypeError("the errands example runs the ErrandsWorld robot")
        engine = agent.world.attach(program)
        return engine, engine


def example(path: Path, plan: bool = True, noise: float = 1.0, robots: int = 1) -> ErrandsExample:
    """The errands world plug-in for the example folder ``path``."""
    if robots != 1:
        raise ExampleError(f"the errands world has one robot, not {robots!r}")
    return ErrandsExample(path, plan=plan, noise=noise)
