"""Run from here: a live session that starts at a tick of a recording (a simulation worker's start).

Two halves, one per process:

* :func:`fork_session` (server process) checks that a recording can be forked at a tick (a
  deterministic run, not itself a fork, the tick inside it, its example installed here), loads the
  example's world plug-in with the recorded world options and returns a
  :class:`~xabsl_studio.server.session.Session` whose worker starts from :class:`ForkStart` instead of a fresh
  world. Its behaviors are the ones on disk now (the session compiles them as always).
* :func:`resimulated` (simulation process, from ``Simulation.__init__``) builds the world from the
  recorded seed with the *recorded* behaviors (compiled again from the sources the recording
  keeps, ``xabsl_studio.engine.record.sources``), re-simulates ticks ``0 .. at - 1`` and checks tick ``at - 1``
  against the recording (``xabsl_studio.engine.record.fork.resimulate``), then switches in the behaviors on
  disk that differ from the recorded ones. The session's seqs continue the recording's: its first
  sample is tick ``at - 1`` as recorded, the first tick it runs is ``at``.
"""

from __future__ import annotations

import contextlib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from xabsl_studio.engine.errors import ServerError
from xabsl_studio.engine.host import BehaviorLoop, Example, World
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.runtime import Engine

if TYPE_CHECKING:
    from xabsl_studio.engine.record import Recording
    from xabsl_studio.server.session import Session

__all__ = ["ForkError", "ForkStart", "fork_session", "resimulated"]


class ForkError(ServerError, ValueError):
    """A recording that cannot be forked at that tick here (the message says why)."""


@dataclass(frozen=True, slots=True)
class ForkStart:
    """How a simulation worker starts a fork: the recording and the fork tick (pickled to it)."""

    recording: str
    at: int


def _example_folder(name: str) -> Path:
    from xabsl_studio import examples

    folder = Path(examples.__file__).resolve().parent / name
    if not name.isidentifier() or not (folder / "studio.py").is_file():
        raise ForkError(f"the recording is of example {name!r}, which this installation does not have")
    return folder


def fork_session(recording: Recording, at: int, home: tuple[Path, str | None] | None = None) -> Session:
    """A live session that will start at tick ``at`` of ``recording`` (not started yet).

    ``home``: the main studio's example as ``(path, world)``; when it is the recorded example,
    the fork runs its behaviors, otherwise those of the installed example of that name.

    Raises:
        ForkError: not deterministic, itself a fork, ``at`` outside it, its example or world
            options missing here.
    """
    from xabsl_studio.server.examples import ExampleError, load_example
    from xabsl_studio.server.session import Session

    header = recording.header
    if not header.get("deterministic"):
        raise ForkError(f"{Path(recording.path).name} is not a recording of a deterministic run (a live session?)")
    if recording.first:
        raise ForkError(
            f"{Path(recording.path).name} is itself a fork (from tick {recording.first}): fork its original"
        )
    if not 1 <= at < len(recording):
        raise ForkError(f"fork tick {at} is outside the recording (1..{len(recording) - 1})")
    early = sorted({e["kind"] for e in recording.events if e["seq"] < at and e["kind"] != "note"})
    if early:
        raise ForkError(f"the recording has session events before tick {at} ({', '.join(early)}): not replayed yet")
    options = header.get("world_options")
    if not isinstance(options, dict):
        raise ForkError(f"{Path(recording.path).name} does not say how its world was built (no world_options)")
    name = str(header.get("example"))
    example = None
    if home is not None:
        with contextlib.suppress(ExampleError):
            candidate = load_example(home[0], home[1], **options)
            example = candidate if candidate.name == name else None
    if example is None:
        try:
            example = load_example(_example_folder(name), None, **options)
        except ExampleError as error:
            raise ForkError(f"the recorded world does not load: {error}") from None
    if (example.behavior_hz, example.physics_hz) != (int(header["behavior_hz"]), int(header["physics_hz"])):
        raise ForkError("the recording's rates are not the example's")
    session = Session(
        example,
        seed=int(header["seed"]),
        behavior_hz=example.behavior_hz,
        physics_hz=example.physics_hz,
    )
    session.fork_start = ForkStart(str(Path(recording.path).resolve()), at)
    return session


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
    from xabsl_studio.engine.record import Recording, RecordingError
    from xabsl_studio.engine.record.fork import fork_programs, resimulate
    from xabsl_studio.engine.record.sources import program_sources

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
