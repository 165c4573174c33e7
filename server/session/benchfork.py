"""Run from here on a recording that cannot be re-simulated: the bench world, fed the recorded inputs.

A recording of an attached session (robots elsewhere, docs/attach.md) or of any live run that
is not deterministic cannot be re-run to a tick: its world is not ours. What it holds is enough
to go on from a tick in the bench world (``xabsl_studio.engine.worlds.bench``) instead:

* the behavior that ran then: its source files as the host sent them (``sources`` of the
  recorded program), written to a folder of the fork's own, where the fork's editor edits them;
* one robot's recorded plain input values from that tick on, as an input trace in the
  ``xabsl trace`` format (enum values by element name, a line where a value changed, times
  from the fork tick), which the bench world plays on its behavior clock.

Input functions (inputs with parameters) are not recorded: the bench world answers them with
the values set by hand. After the recording's last tick the inputs keep their last values.
"""

from __future__ import annotations

import atexit
import shutil
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

import orjson

from xabsl_studio.engine.record.reader import RecordingError
from xabsl_studio.engine.record.sources import write_sources
from xabsl_studio.engine.worlds.loader import ExampleError, load_example
from xabsl_studio.server.protocol.errors import ServerError
from xabsl_studio.server.session.live import Session

if TYPE_CHECKING:
    from xabsl_studio.engine.record import Recording

__all__ = ["BenchForkError", "bench_fork", "input_trace"]

#: The input trace's name in the fork's folder.
TRACE_NAME = "recorded-inputs.jsonl"

_UNSET = object()


class BenchForkError(ServerError, ValueError):
    """A recording that cannot be forked into the bench world (the message says why)."""


def input_trace(recording: Recording, at: int, agent: str) -> list[dict[str, Any]]:
    """``agent``'s recorded plain inputs from tick ``at`` on, as input trace lines (``{"t", "set"}``).

    Raises:
        BenchForkError: the agent is not in the recording at tick ``at``.
    """
    lines: list[dict[str, Any]] = []
    last: dict[str, Any] = {}
    t0: int | None = None
    for view in recording.ticks(at):
        tick = view.agents.get(agent)
        if tick is None:
            continue
        if t0 is None:
            t0 = view.t
        program = tick.program
        enums: dict[str, dict[str, str]] = program.tables.get("enums", {})
        changed: dict[str, Any] = {}
        for symbol in program.description["inputs"]:
            name = symbol["name"]
            if symbol.get("params") or name not in tick.inputs:
                continue
            value: Any = tick.inputs[name]
            if value is None:
                continue  # the host could not read it in that tick: leave the last value
            if symbol["type"] == "enum" and not isinstance(value, str):
                # live recordings hold enum values as element indices (the header's tables name them)
                value = enums.get(symbol.get("enum") or "", {}).get(str(int(value)))
                if value is None:
                    continue
            if last.get(name, _UNSET) != value:
                changed[name] = value
        if changed or not lines:
            lines.append({"t": view.t - t0, "set": changed})
            last.update(changed)
    if t0 is None:
        raise BenchForkError(f"{agent} is not in the recording from tick {at} on")
    return lines


def bench_fork(recording: Recording, at: int, robot: int = 0) -> Session:
    """A bench-world session running robot ``robot``'s recorded behavior on its recorded inputs from ``at``.

    Raises:
        BenchForkError: ``at`` or ``robot`` outside the recording, the recorded program holds no
            sources (a host that loaded intermediate code) or they do not load.
    """
    if not recording.first <= at < recording.end:
        raise BenchForkError(f"fork tick {at} is outside the recording ({recording.first}..{recording.end - 1})")
    agents = recording.header.get("agents", [])
    if not 0 <= robot < len(agents):
        raise BenchForkError(f"robot must be a robot of the recording (0..{len(agents) - 1})")
    name = str(agents[robot]["name"])
    try:
        tick = recording.tick(at).agents.get(name)
    except RecordingError as error:
        raise BenchForkError(str(error)) from None
    if tick is None:
        raise BenchForkError(f"{name} runs no behavior at tick {at}")
    sources = tick.program.sources
    if sources is None:
        raise BenchForkError(
            f"the recording does not hold the source files of {name}'s behavior (its host sent none): "
            "it replays, but cannot run again"
        )
    folder = Path(tempfile.mkdtemp(prefix="xabsl-bench-fork-"))
    atexit.register(shutil.rmtree, folder, True)
    try:
        _, agents_file = write_sources(sources, folder / "behavior", f"{name}'s recorded behavior")
        trace = folder / TRACE_NAME
        trace.write_bytes(b"".join(orjson.dumps(line) + b"\n" for line in input_trace(recording, at, name)))
        example = load_example(agents_file, None, robots=1, inputs=str(trace))
    except (RecordingError, ExampleError, OSError) as error:
        shutil.rmtree(folder, ignore_errors=True)
        raise BenchForkError(f"the recorded behavior does not load in the bench world: {error}") from None
    return Session(example, behavior_hz=example.behavior_hz, physics_hz=example.physics_hz)
