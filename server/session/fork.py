"""Run from here, the server's half: a live session that starts at a tick of a recording.

:func:`fork_session` checks that a recording can be forked at a tick (a deterministic run, not
itself a fork, the tick inside it, its example installed here), loads the example's world plug-in
with the recorded world options and returns a :class:`~xabsl_studio.server.session.live.Session`
whose simulation starts from a :class:`~xabsl_studio.server.simulation.forkstart.ForkStart`
instead of a fresh world (the simulation's half, :mod:`xabsl_studio.server.simulation.forkstart`,
re-simulates to the tick). Its behaviors are the ones on disk now (the session compiles them as
always).
"""

from __future__ import annotations

import contextlib
from pathlib import Path
from typing import TYPE_CHECKING

import xabsl_studio
from xabsl_studio.engine.worlds.loader import ExampleError, load_example
from xabsl_studio.server.protocol.errors import ServerError
from xabsl_studio.server.session.benchfork import BenchForkError, bench_fork
from xabsl_studio.server.session.live import Session
from xabsl_studio.server.simulation.forkstart import ForkStart

if TYPE_CHECKING:
    from xabsl_studio.engine.record import Recording

__all__ = ["ForkError", "fork_session"]


class ForkError(ServerError, ValueError):
    """A recording that cannot be forked at that tick here (the message says why)."""


def _example_folder(name: str) -> Path:
    folder = Path(xabsl_studio.__file__).resolve().parent / "examples" / name
    if not name.isidentifier() or not (folder / "studio.py").is_file():
        raise ForkError(f"the recording is of example {name!r}, which this installation does not have")
    return folder


def fork_session(recording: Recording, at: int, home: tuple[Path, str | None] | None = None, robot: int = 0) -> Session:
    """A live session that will start at tick ``at`` of ``recording`` (not started yet).

    ``home``: the main studio's example as ``(path, world)``; when it is the recorded example,
    the fork runs its behaviors, otherwise those of the installed example of that name. A
    recording that is not deterministic but holds its behavior's sources (an attached session's)
    forks robot ``robot`` into the bench world on its recorded inputs
    (``xabsl_studio.server.session.benchfork``).

    Raises:
        ForkError: not deterministic (and no sources), itself a fork, ``at`` outside it, its
            example or world options missing here.
    """
    header = recording.header
    if not header.get("deterministic") and any(v.sources is not None for v in recording.programs.values()):
        try:
            return bench_fork(recording, at, robot)
        except BenchForkError as error:
            raise ForkError(str(error)) from None
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
