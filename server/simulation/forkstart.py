"""Run from here, the simulation's half: the recorded world re-simulated to the fork tick.

:func:`resimulated` (from ``Simulation.__init__``, when the session was started by
``xabsl_studio.server.session.fork.fork_session``) builds the world from the recorded seed with the
*recorded* behaviors (compiled again from the sources the recording keeps,
``xabsl_studio.engine.record.sources``), re-simulates ticks ``0 .. at - 1`` and checks tick ``at - 1``
against the recording (``xabsl_studio.engine.record.fork.resimulate``), then switches in the
behaviors on disk that differ from the recorded ones. The session's seqs continue the
recording's: its first sample is tick ``at - 1`` as recorded, the first tick it runs is ``at``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from xabsl_studio.engine.host import BehaviorLoop, Example, World
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.record import Recording, RecordingError
from xabsl_studio.engine.record.fork import fork_programs, resimulate
from xabsl_studio.engine.record.sources import program_sources
from xabsl_studio.engine.runtime import Engine

__all__ = ["ForkStart", "Resimulated", "resimulated"]


@dataclass(frozen=True, slots=True)
class ForkStart:
    """How a simulation worker starts a fork: the recording and the fork tick (pickled to it)."""

    recording: str
    at: int


@dataclass(slots=True)
class Resimulated:
    """The world of a fork at its fork tick, as :func:`resimulated` returns it."""

    world: World
    loop: BehaviorLoop
    engines: list[Engine | None]
    keys: list[str | None]
    switched: list[str]


def resimulated(
    example: Example,
    programs: Mapping[str, tuple[Program, Any] | None],
    fork: ForkStart,
    physics_hz: int,
    behavior_hz: int,
) -> Resimulated:
    """The recorded world re-simulated to ``fork.at`` and switched to ``programs`` (see the module docstring).

    Raises:
        xabsl_studio.engine.record.RecordingError: the recording cannot be re-simulated (other behaviors or
            another world before the fork tick, sources that do not compile).
    """
    agents_files = {source.key: source.agents_file for source in example.sources}
    current: dict[str, tuple[Program, Any]] = {}
    for key, running in programs.items():
        if running is None:
            raise RecordingError(f"behavior {key!r} does not compile: fix it, then run from here again")
        sources = (
            program_sources(agents_files[key], running[0].files, Path(example.root)) if key in agents_files else None
        )
        current[key] = (running[0], sources)
    with Recording(fork.recording) as recording:
        if (int(recording.header["physics_hz"]), int(recording.header["behavior_hz"])) != (physics_hz, behavior_hz):
            raise RecordingError("the recording's rates are not the session's")
        recorded, switch = fork_programs(recording, current)
        engines: list[Engine | None] = []
        keys: list[str | None] = []

        def build(seed: int) -> World:
            world = example.build_world(seed)
            for agent in world.agents:
                key = example.program_key(agent)
                engine = None
                if key is not None and key in recorded:
                    agent.controller, engine = example.make_controller(agent, recorded[key])
                engines.append(engine)
                keys.append(key)
            return world

        loop = resimulate(recording, build, fork.at)
    for engine, name in zip(engines, keys, strict=True):
        if engine is not None and name is not None and name in switch:
            engine.reload(switch[name])
    return Resimulated(loop.world, loop, engines, keys, sorted(switch))
