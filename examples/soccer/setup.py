"""The soccer world's test setup: put robots and the ball somewhere and the game into a state.

``arrange(world, setup)`` is what ``SoccerExample.arrange`` (the behavior tests' setup hook,
``xabsl_studio.engine.testing.runner.ArrangeableExample``) runs on a freshly built world, before its first
tick. Keys (lengths in mm and angles in degrees, in the world frame of the studio's field: the
centre spot is the origin, blue attacks +x in the first half):

* ``game_state``: ``initial``, ``ready``, ``set``, ``playing`` or ``finished`` (set now; the
  referee goes on from there: ``ready`` lasts its 5 s, ``playing`` until the half ends);
* ``kickoff``: ``blue`` or ``red``, the team that kicks off;
* ``ball``: ``[x, y]``; ``ball_velocity``: ``[vx, vy]`` in mm/s (a rolling ball);
* ``robots``: ``{name = [x, y, heading]}`` (``blue1`` is blue's goalie, ``red3`` red's number 3).

Unknown keys, robots or values outside the field (with a metre of margin) are a ``ValueError``
naming them.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from functools import partial
from typing import Any

from xabsl_studio.examples.soccer.game import GameState
from xabsl_studio.examples.soccer.world import TEAM_NAMES, SoccerWorld

__all__ = ["KEYS", "arrange", "setup_from_scene"]

KEYS = ("game_state", "kickoff", "ball", "ball_velocity", "robots")
_MM_PER_M = 1000.0


def arrange(world: SoccerWorld, setup: Mapping[str, Any]) -> None:
    """Apply ``setup`` (see the module docstring) to ``world``; nothing is changed on an error."""
    unknown = set(setup) - set(KEYS)
    if unknown:
        raise ValueError(f"unknown soccer setup key(s) {', '.join(sorted(unknown))} (known: {', '.join(KEYS)})")
    limit_x = (world.dims.half_length + 1.0) * _MM_PER_M
    limit_y = (world.dims.half_width + 1.0) * _MM_PER_M
    actions: list[Callable[[], None]] = []
    if "game_state" in setup:
        name = setup["game_state"]
        states = {s.name.lower(): s for s in GameState}
        if name not in states:
            raise ValueError(f"game_state must be one of {', '.join(states)}, got {name!r}")
        kickoff = None
        if "kickoff" in setup:
            if setup["kickoff"] not in TEAM_NAMES:
                raise ValueError(f"kickoff must be one of {', '.join(TEAM_NAMES)}, got {setup['kickoff']!r}")
            kickoff = TEAM_NAMES.index(setup["kickoff"])
        actions.append(partial(world.game.set_state, states[name], kickoff))
    elif "kickoff" in setup:
        raise ValueError("kickoff goes with game_state")
    if "ball" in setup:
        bx, by = _point(setup["ball"], "ball", 2, limit_x, limit_y)
        actions.append(partial(world.place_ball, bx / _MM_PER_M, by / _MM_PER_M))
    if "ball_velocity" in setup:
        vx, vy = _point(setup["ball_velocity"], "ball_velocity", 2, 10_000.0, 10_000.0)

        def roll() -> None:
            world.physics.ball.velocity = (vx / _MM_PER_M, vy / _MM_PER_M)

        actions.append(roll)
    robots = setup.get("robots", {})
    if not isinstance(robots, Mapping):
        raise ValueError("robots must be a table {name = [x, y, heading]}")
    by_name = {a.name: a for a in world.agents}
    for name, pose in robots.items():
        agent = by_name.get(name)
        if agent is None:
            raise ValueError(f"no robot {name!r} (robots: {', '.join(by_name)})")
        x, y, heading = _point(pose, f"robots.{name}", 3, limit_x, limit_y)
        actions.append(partial(world.place_robot, agent, x / _MM_PER_M, y / _MM_PER_M, math.radians(heading)))
    for action in actions:
        action()


def _point(value: Any, where: str, size: int, limit_x: float, limit_y: float) -> list[float]:
    if (
        not isinstance(value, list | tuple)
        or len(value) != size
        or any(isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) for v in value)
    ):
        raise ValueError(f"{where} must be [{', '.join(['x', 'y', 'heading'][:size])}] (finite numbers), got {value!r}")
    x, y = float(value[0]), float(value[1])
    if abs(x) > limit_x or abs(y) > limit_y:
        raise ValueError(f"{where}: ({x:g}, {y:g}) mm is off the field")
    return [float(v) for v in value]


def setup_from_scene(scene: Mapping[str, Any], status: Mapping[str, Any], names: list[str]) -> dict[str, Any]:
    """The setup keys that put a match back into the situation of a dynamic scene and status.

    ``scene`` is ``SoccerWorld.dynamic_scene()`` (robots in agent order, ``names``), ``status``
    its ``status()``; what the scene does not hold (velocities, the referee's clocks) is not kept.
    """
    setup: dict[str, Any] = {}
    state = status.get("game_state")
    if isinstance(state, str) and state in {s.name.lower() for s in GameState}:
        setup["game_state"] = state
        if status.get("kickoff_team") in TEAM_NAMES:
            setup["kickoff"] = status["kickoff_team"]
    ball = scene.get("ball")
    if isinstance(ball, list) and len(ball) == 2:
        setup["ball"] = [float(v) for v in ball]
    robots = scene.get("robots")
    if isinstance(robots, list) and len(robots) == len(names):
        setup["robots"] = {name: [float(v) for v in pose[:3]] for name, pose in zip(names, robots, strict=True)}
    return setup
