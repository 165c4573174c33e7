"""A recording served as a studio session: ``xabsl serve --replay FILE.mcap``.

:class:`ReplaySession` offers the app and the websocket hub what a live
:class:`~xabsl_studio.server.session.live.Session` offers (a ring of frames, generations, ``history``, ``status``,
the playback commands), with the recording (``xabsl_studio.engine.record.Recording``) in place of a simulation
process. Every tick of the file is reachable: ``seek`` puts any tick in the ring (the MCAP chunk
index makes that a read of at most ``key_every`` ticks), ``pause``/``resume``/``step``/``speed``
play the file at its own rate, and ``history`` decodes any range of ticks from the file, so the
timeline covers the whole recording, not the live ring's 120 s.

A recorded tick becomes the same :class:`~xabsl_studio.server.protocol.host.Sample` the simulation would have sent
(paths, display values aligned with the generation's symbol ids, fault, scene, status), and the
usual :class:`~xabsl_studio.server.session.frames.FrameRecorder` turns it into frames, so every panel reads a replay
exactly as it reads a live session.

``explain`` works at any tick: :func:`explain` rebuilds the recorded generation from its
intermediate code and lets the engine's debugger (``xabsl_studio.engine.runtime.debug.explain_decision``, the
evaluator the live studio uses) walk its decision tree to the recorded leaf, evaluating every
condition and both operands of every comparison from what the decision read in that tick (the
tick's ``reads``: inputs, input function calls with their arguments and results, outputs,
parameters, times, ``action_done``; ``xabsl_studio.engine.runtime.debug.ReadValues``), exactly as
the live why does. Recordings made before the reads were recorded are explained from what they
hold (:class:`TickValues`: the tick's plain inputs; outputs as the decision saw them, the
previous tick's updated by the assignments that ran before the option in this tick; the
option's parameters and times); there input functions and ``action_done`` are ``null``. The
branch taken is always the recorded one.

Commands that need a live world (forcing, overrides, resets, world commands) answer an error.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import functools
import logging
import time
from bisect import bisect_right
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import orjson

from xabsl_studio.engine.errors import DebugError
from xabsl_studio.engine.host import Agent, AgentController, BehaviorSource, ExampleError, World
from xabsl_studio.engine.ir.model import Expression, Option, Program
from xabsl_studio.engine.record import Recording, RecordingError, TickView
from xabsl_studio.engine.record.reader import AgentTick, ProgramView
from xabsl_studio.engine.runtime import AssignmentNode, Engine, OptionNode
from xabsl_studio.engine.runtime.debug import (
    ReadValues,
    Unknown,
    Values,
    decision_reads,
    explain_decision,
    render,
    show_value,
)
from xabsl_studio.engine.types import Kind, Value
from xabsl_studio.server.protocol.commands import (
    AttachHost,
    BreakpointCommand,
    Explain,
    Fork,
    Pause,
    Query,
    Resume,
    Seek,
    Speed,
    Status,
    Step,
)
from xabsl_studio.server.protocol.host import WorkerCommand
from xabsl_studio.server.protocol.rest import ReplayInfo
from xabsl_studio.server.session import frames
from xabsl_studio.server.session.frames import Entry, FrameRecorder, Generation, Ring
from xabsl_studio.server.session.live import CommandError, Session
from xabsl_studio.server.session.query import RecordingQueries
from xabsl_studio.server.simulation.explain import (
    copy_texts,
    explanation_result,
    source_texts,
    tree_result,
    why_not_result,
)
from xabsl_studio.server.simulation.worker import check_speed

log = logging.getLogger("xabsl.server")

__all__ = ["MAX_HISTORY_TICKS", "ReplayExample", "ReplaySession", "explain"]

#: The most ticks one ``history`` request of a replay decodes (ask for longer spans in hunks).
MAX_HISTORY_TICKS = 4800
#: Ticks the replay's ring keeps (what the client encoder needs for deltas; history reads the file).
RING_TICKS = 256


@dataclass(frozen=True, slots=True)
class ReplayExample:
    """The :class:`~xabsl_studio.engine.host.Example` of a replay: a name and a folder, no world to build."""

    name: str
    root: Path
    sources: Sequence[BehaviorSource] = ()
    preload: Sequence[str] = ()
    behavior_hz: int = 40
    physics_hz: int = 120

    def build_world(self, seed: int) -> World:
        """A replay has no world."""
        raise ExampleError("a replay has no world to build")

    def program_key(self, agent: Agent) -> str | None:
        """A replay has no world."""
        raise ExampleError("a replay has no world")

    def make_controller(self, agent: Agent, program: Program) -> tuple[AgentController, Engine]:
        """A replay has no world."""
        raise ExampleError("a replay has no world")


class _Codec:
    """Recorded values of one program generation -> the frames' display values and id order."""

    def __init__(self, view: ProgramView, decimals: int) -> None:
        description = view.description
        self.scale = 10.0**decimals
        elements = {e["name"]: list(e["elements"]) for e in description["enums"]}
        self.element_index = {name: {el: i for i, el in enumerate(els)} for name, els in elements.items()}
        host = view.tables["enums"]
        # enum -> host value -> element index
        self.host_index = {
            name: {int(v): self.element_index.get(name, {}).get(el, -1) for v, el in table.items()}
            for name, table in host.items()
        }
        self.inputs = [s for s in description["inputs"] if not s.get("params")]
        self.outputs = list(description["outputs"])
        self.input_ids = tuple(int(s["id"]) for s in self.inputs)
        self.output_ids = tuple(int(s["id"]) for s in self.outputs)
        self.option_params = {
            o["id"]: [(p["type"], p.get("enum")) for p in o["params"]] for o in description["options"]
        }
        self.behavior_params = {
            b["id"]: [(p["type"], p.get("enum")) for p in b["params"]] for b in description["behaviors"]
        }

    def named(self, kind: str, enum: str | None, value: Any) -> Any:
        """A recorded value (enums as element names) as frames carry it."""
        if value is None:
            return None
        if kind == "decimal":
            return round(float(value) * self.scale) / self.scale
        if kind == "boolean":
            return bool(value)
        if kind == "enum":
            return self.element_index.get(enum or "", {}).get(value, -1)
        return value

    def raw(self, kind: str, enum: str | None, value: Any) -> Any:
        """A raw path parameter (enums as host values) as frames carry it."""
        if kind == "decimal":
            return round(float(value) * self.scale) / self.scale
        if kind == "boolean":
            return bool(value)
        if kind == "enum":
            return self.host_index.get(enum or "", {}).get(int(value), -1)
        return value

    def path(self, path: list[list[Any]]) -> list[list[Any]]:
        """The recorded path with display parameter values (the frame's path layout)."""
        out = []
        for node in path:
            if node[0] == 0:
                params = node[8]
                if params:
                    kinds = self.option_params[node[2]]
                    node = [*node[:8], [self.raw(k, e, v) for (k, e), v in zip(kinds, params, strict=False)]]
            else:
                params = node[4]
                if params:
                    kinds = self.behavior_params[node[2]]
                    node = [*node[:4], [self.raw(k, e, v) for (k, e), v in zip(kinds, params, strict=False)]]
            out.append(node)
        return out

    def values(self, symbols: list[dict[str, Any]], values: dict[str, Any]) -> tuple[Any, ...]:
        """The recorded values of ``symbols`` in id order, as display values."""
        return tuple(self.named(s["type"], s.get("enum"), values.get(s["name"])) for s in symbols)


class ReplaySource:
    """The frames of a recording: generations by segment, ticks as samples (no asyncio here)."""

    def __init__(self, recording: Recording) -> None:
        self.recording = recording
        header = recording.header
        self.decimals = int(header.get("decimals") or 3)
        self.robots = [
            {
                "id": a["id"],
                "name": a["name"],
                "team": a.get("team"),
                "number": a.get("number"),
                "program": a["program"],
            }
            for a in header["agents"]
        ]
        # A new generation (a hello) where a program generation or a static scene starts.
        starts = {view.seq for view in recording.programs.values()} | {s["seq"] for s in recording.static_scenes}
        #: the seqs of the first tick and one past the last (a fork's recording starts at its fork tick)
        self.first, self.end = recording.first, recording.end
        self.boundaries = sorted(seq for seq in starts if seq > self.first)
        self._generations: dict[int, Generation] = {}
        self._codecs: dict[tuple[str, int], _Codec] = {}

    def __len__(self) -> int:
        return len(self.recording)

    def generation_number(self, seq: int) -> int:
        """The hello generation tick ``seq`` belongs to."""
        return bisect_right(self.boundaries, seq)

    def generation(self, seq: int) -> Generation:
        """The generation (structure, static scene, symbol ids) in force at tick ``seq``."""
        number = self.generation_number(seq)
        gen = self._generations.get(number)
        if gen is not None:
            return gen
        start = self.boundaries[number - 1] if number else self.first
        recording = self.recording
        programs: dict[str, dict[str, Any]] = {}
        input_ids: list[tuple[int, ...]] = []
        output_ids: list[tuple[int, ...]] = []
        for robot in self.robots:
            key = robot["program"]
            if key is None:
                input_ids.append(())
                output_ids.append(())
                continue
            view = recording.program(robot["name"], _latest_gen(recording, key, start))
            programs[key] = view.description
            codec = self.codec(view)
            input_ids.append(codec.input_ids)
            output_ids.append(codec.output_ids)
        scenes = [s for s in recording.static_scenes if s["seq"] <= start] or recording.static_scenes[:1]
        structure = {"programs": programs, "robots": self.robots}
        structure_bytes = orjson.dumps(structure)
        gen = Generation(
            number=number,
            reason="connect" if number == 0 else "reload",
            structure=orjson.loads(structure_bytes),
            structure_bytes=structure_bytes,
            scene_bytes=orjson.dumps(scenes[-1]["scene"] if scenes else {}),
            input_ids=tuple(input_ids),
            output_ids=tuple(output_ids),
            engines=tuple(r["program"] is not None for r in self.robots),
        )
        self._generations[number] = gen
        return gen

    def codec(self, view: ProgramView) -> _Codec:
        """The value conversion of one program generation (cached)."""
        codec = self._codecs.get((view.key, view.gen))
        if codec is None:
            codec = self._codecs[(view.key, view.gen)] = _Codec(view, self.decimals)
        return codec

    def sample(self, view: TickView, number: int, paused: bool, speed: float) -> Any:
        """The :class:`~xabsl_studio.server.protocol.host.Sample` the simulation would have sent for ``view``."""
        from xabsl_studio.server.protocol.host import Sample

        paths: list[bytes] = []
        extras: list[bytes] = []
        inputs: list[tuple[Any, ...]] = []
        outputs: list[tuple[Any, ...]] = []
        gen = self.generation(view.seq)
        for i, robot in enumerate(self.robots):
            agent = view.agents.get(robot["name"])
            if agent is None:  # no engine, or no tick of it in the file: its values are unknown
                paths.append(b"[]")
                extras.append(b"")
                inputs.append((None,) * len(gen.input_ids[i]))
                outputs.append((None,) * len(gen.output_ids[i]))
                continue
            codec = self.codec(agent.program)
            paths.append(orjson.dumps(codec.path(agent.path)))
            fault = agent.fault
            if fault:
                part = {"message": fault.get("message"), "option": fault.get("option"), "state": fault.get("state")}
                extras.append(b',"fault":' + orjson.dumps(part))
            else:
                extras.append(b"")
            inputs.append(codec.values(codec.inputs, agent.inputs))
            outputs.append(codec.values(codec.outputs, agent.outputs))
        return Sample(
            view.seq,
            number,
            view.t,
            time.time() * 1000.0,
            paused,
            speed,
            tuple(paths),
            tuple(extras),
            tuple(inputs),
            tuple(outputs),
            orjson.dumps(view.scene or {}),
            orjson.dumps(view.status or {}),
        )

    def history(self, start: int, stop: int, t0: int, t1: int, every: int) -> Iterator[bytes]:
        """The frames of ticks ``start`` .. ``stop - 1`` with ``t0 <= t <= t1`` (``frames.history``)."""
        ring = Ring(max(1, stop - start) / self.recording.behavior_hz, self.recording.behavior_hz)
        recorder = FrameRecorder(ring)
        gen: Generation | None = None
        for view in self.recording.ticks(start, stop):
            number = self.generation_number(view.seq)
            gen = self.generation(view.seq)
            recorder.record(gen, self.sample(view, number, True, 1.0))
        if gen is None:
            return iter(())
        return frames.history(ring, t0, t1, every)


def _latest_gen(recording: Recording, key: str, seq: int) -> int:
    gens = [view.gen for (k, _), view in recording.programs.items() if k == key and view.seq <= seq]
    return max(gens, default=0)


class ReplaySession(Session):
    """A recording served like a live session (see the module docstring).

    Args:
        path: the ``.mcap`` file.
        root: the folder the studio's file API serves (default: the recording's folder).
        speed: playback speed, x the recording's rate.
    """

    keeps_sources: ClassVar[bool] = False

    @property
    def played(self) -> Recording:
        """The recording this session plays back."""
        return self.recording

    def history_span(self, x0: int, x1: int, every: int) -> tuple[list[Generation], int, Iterator[bytes]]:
        """The whole recording's frames of behavior times ``x0 .. x1``, read from the file (no ring)."""
        count, encoded = self.history_frames(x0, x1, every)
        return [], count, encoded

    def __init__(self, path: str | Path, root: Path | None = None, speed: float = 1.0) -> None:
        try:
            recording = Recording(path)
        except (RecordingError, OSError) as error:
            raise ExampleError(str(error)) from None
        try:
            self._open(path, recording, root, speed)
        except RecordingError as error:  # a damaged first or last tick, program or scene
            recording.close()
            raise ExampleError(str(error)) from None
        except BaseException:
            recording.close()
            raise

    def _open(self, path: str | Path, recording: Recording, root: Path | None, speed: float) -> None:
        if len(recording) == 0:
            raise ExampleError(f"{path}: the recording holds no tick")
        header = recording.header
        name = f"{header.get('example') or header.get('world') or 'recording'} (replay of {Path(path).name})"
        example = ReplayExample(
            name,
            (root or Path(path).resolve().parent),
            behavior_hz=int(header["behavior_hz"]),
            physics_hz=int(header.get("physics_hz") or 120),
        )
        super().__init__(
            example,
            seed=int(header.get("seed") or 0),
            speed=speed,
            behavior_hz=example.behavior_hz,
            physics_hz=example.physics_hz,
            ring_seconds=RING_TICKS / example.behavior_hz,
        )
        self.recording = recording
        self.source = ReplaySource(recording)
        self.paused = True
        self.position = recording.first
        self._last_recorded: int | None = None
        self._player: asyncio.Task[None] | None = None
        self.seek_seconds = 0.0
        self.seeks = 0
        #: per (behavior key, generation): its program rebuilt from the recorded IC (graphs)
        self._programs_shown: dict[tuple[str, int], tuple[Program | None]] = {}
        #: the ticks ``explain`` read last, by seq (the why pane asks for several options of one tick)
        self._explained: dict[int, TickView] = {}
        #: behavior times of the first and the last tick (the UI's timeline extent)
        self.t_first = recording.tick(recording.first).t
        self.t_last = recording.tick(recording.end - 1).t
        #: the ``query`` command over the file (docs/queries.md)
        self.queries = RecordingQueries(recording.path, self.source.robots)

    # -- the session's lifetime ---------------------------------------------------------------------

    @property
    def running(self) -> bool:
        """A replay never has a simulation process."""
        return False

    async def start(self) -> None:
        """Put the first tick in the ring (paused)."""
        self.seek(self.source.first)

    async def aclose(self) -> None:
        """Stop playing and close the file."""
        self.stop()

    def stop(self) -> None:
        """Stop playing and close the file."""
        if self._player is not None:
            self._player.cancel()
            self._player = None
        self.recording.close()

    def release_owner(self, owner: str) -> None:
        """Nothing is forced in a replay."""

    def shown_program(self, key: str) -> Program | None:
        """The recorded generation of ``key`` in force at the playback position, rebuilt from its IC.

        None for recordings without intermediate code (made before it was recorded).
        """
        return self.recorded_program(key, _latest_gen(self.recording, key, self.position))

    def recorded_program(self, key: str, gen: int) -> Program | None:
        """Generation ``gen`` of behavior ``key`` rebuilt from its recorded IC (None without IC)."""
        cached = self._programs_shown.get((key, gen))
        if cached is None:
            view = self.recording.programs.get((key, gen))
            cached = self._programs_shown[(key, gen)] = (view.program() if view is not None else None,)
        return cached[0]

    # -- seeking and playing -----------------------------------------------------------------------

    def seek(self, seq: int) -> Entry:
        """Make tick ``seq`` the ring's newest entry and tell the clients.

        Raises:
            CommandError: ``seq`` is outside the recording.
        """
        if not self.source.first <= seq < self.source.end:
            raise CommandError(f"tick {seq} is outside the recording ({self.source.first}..{self.source.end - 1})")
        started = time.perf_counter()
        view = self.recording.tick(seq)
        entry = self._record(view)
        self.seek_seconds += time.perf_counter() - started
        self.seeks += 1
        self.notify(entry)
        return entry

    def _record(self, view: TickView) -> Entry:
        number = self.source.generation_number(view.seq)
        gen = self.source.generation(view.seq)
        if self._last_recorded is not None and view.seq != self._last_recorded + 1:
            # Not the next tick: a copy of the generation makes the frame recorder start over
            # (a full frame; no delta against a tick the clients may not have), same number.
            gen = dataclasses.replace(gen)
        self.generation = gen
        entry = self.recorder.record(gen, self.source.sample(view, number, self.paused, self.speed))
        self._last_recorded = view.seq
        self.position = view.seq
        return entry

    def _advance(self, ticks: int) -> int:
        """Record the next ``ticks`` ticks (fewer at the end); the ticks recorded."""
        start = self.position + 1
        stop = min(self.source.end, start + ticks)
        last: Entry | None = None
        if self._last_recorded != self.position:
            self.seek(self.position)
        for view in self.recording.ticks(start, stop):
            last = self._record(view)
        if last is not None:
            self.notify(last)
        return max(0, stop - start)

    async def _play(self) -> None:
        period = 1.0 / self.behavior_hz
        due = time.perf_counter()
        while not self.paused and self.position < self.source.end - 1:
            due += period / self.speed
            delay = due - time.perf_counter()
            if delay > 0:
                await asyncio.sleep(delay)
            # Catch up by recording the ticks that fell due (clients pick their own rate).
            behind = max(1, 1 + int((time.perf_counter() - due) * self.behavior_hz * self.speed))
            try:
                self._advance(min(behind, 40))
            except RecordingError as error:  # a damaged tick further on: playing stops before it
                log.warning("the replay stops playing: %s", error)
                self.paused = True
                break
            if behind > 1:
                due = time.perf_counter()
        self.paused = True

    # -- commands ----------------------------------------------------------------------------------

    async def request(
        self, command: WorkerCommand | BreakpointCommand | Fork | Query | AttachHost, owner: str | None = None
    ) -> Any:
        """Playback commands, ``seek``, ``explain`` and ``query``; anything needing a world is refused."""
        if isinstance(command, Query):
            return await self.queries.answer(command)
        if isinstance(command, Status):
            return await self.status()
        if isinstance(command, Seek):
            self.seek(command.seq)
            return {"seq": self.position, "ticks": len(self.source)}
        if isinstance(command, Pause):
            self.paused = True
            if self._player is not None:
                self._player.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await self._player
                self._player = None
            return {"paused": True}
        if isinstance(command, Resume):
            if self.paused:
                self.paused = False
                self._player = asyncio.get_running_loop().create_task(self._play())
            return {"paused": False}
        if isinstance(command, Step):
            if not self.paused:
                raise CommandError("step needs a paused replay")
            self._advance(command.ticks)
            return {"seq": self.position, "t": self.ring.latest.t if self.ring.latest else 0}
        if isinstance(command, Speed):
            self.speed = check_speed(command.speed)
            return {"speed": self.speed}
        if isinstance(command, Explain):
            return await self.explain(command, owner)
        raise CommandError(f"{command.op} needs a live world; this is a replay of {self.recording.path}")

    async def explain(self, command: Explain, owner: str | None = None) -> Any:
        """``explain`` at tick ``command.seq`` (default: the current one), from the recording."""
        return self.explain_at(command.robot, command.option, command.seq, command.why_not)

    def explain_at(
        self, robot: int, option: str | int, seq: int | None = None, why_not: int | str | None = None
    ) -> dict[str, Any]:
        """``explain`` at tick ``seq`` (default: the current one) of ``robot``; with why not state ``why_not``."""
        robots = self.source.robots
        if not 0 <= robot < len(robots) or robots[robot]["program"] is None:
            raise CommandError(f"no XABSL robot {robot} in this recording")
        at = self.position if seq is None else seq
        if not self.source.first <= at < self.source.end:
            raise CommandError(f"tick {at} is outside the recording ({self.source.first}..{self.source.end - 1})")
        name = robots[robot]["name"]
        view = self._tick_view(at)
        agent = view.agents.get(name)
        if agent is None:
            raise CommandError(f"{name} has no tick {at} in the recording")
        # Older recordings hold no reads: then the tick before gives the outputs and times the decision saw.
        previous = self._tick_view(at - 1) if agent.reads is None and at > self.source.first else None
        program = self.recorded_program(robots[robot]["program"], agent.gen)
        if program is None:
            raise CommandError(f"{self.recording.path} holds no intermediate code (an older recording): no why")
        result = explain(
            program, agent, previous.agents.get(name) if previous else None, option, view.t, previous, why_not
        )
        # Asked without a tick (the page's "live" view: the playback position): shown as live.
        result.update(seq=at if seq is not None else None, t=view.t, recorded=seq is not None)
        return result

    def _tick_view(self, seq: int) -> TickView:
        """Tick ``seq`` of the recording, read once for the explains of its options (a seek per tick)."""
        view = self._explained.get(seq)
        if view is None:
            if len(self._explained) >= 4:
                self._explained.pop(next(iter(self._explained)))
            view = self._explained[seq] = self.recording.tick(seq)
        return view

    # -- history and status ---------------------------------------------------------------------------

    def history_frames(self, t0: int, t1: int, every: int) -> tuple[int, Iterator[bytes]]:
        """The frames of behavior times ``t0`` .. ``t1`` of the recording, and how many.

        Times map to ticks by the recording's rate within the current generation's segment (a
        reset sets the clock back).
        """
        source = self.source
        number = source.generation_number(self.position)
        seg_start = source.boundaries[number - 1] if number else source.first
        seg_stop = source.boundaries[number] if number < len(source.boundaries) else source.end
        base = self.recording.tick(seg_start).t
        step = 1000.0 / self.behavior_hz
        start = max(seg_start, seg_start + int((t0 - base) // step))
        stop = min(seg_stop, seg_start + int((t1 - base) // step) + 2)
        if stop <= start:
            return 0, iter(())
        if stop - start > MAX_HISTORY_TICKS:
            raise CommandError(
                f"history of a replay spans at most {MAX_HISTORY_TICKS} ticks "
                f"({MAX_HISTORY_TICKS / self.behavior_hz:g} s); ask for the rest in further requests"
            )
        encoded = list(source.history(start, stop, t0, t1, every))
        return len(encoded), iter(encoded)

    async def status(self) -> dict[str, Any]:
        """The status of a replay: position, length, the live session's fields where they apply."""
        latest = self.ring.latest
        gen = self.generation
        replay: ReplayInfo = {
            "file": self.recording.path,
            "ticks": len(self.source),
            "first": self.source.first,
            "position": self.position,
            "t0": self.t_first,
            "t1": self.t_last,
            "seconds": round(len(self.source) / self.behavior_hz, 3),
            "header": {k: v for k, v in self.recording.header.items() if k != "tables"},
            "events": len(self.recording.events),
            "seeks": self.seeks,
            "seek_ms": round(1000 * self.seek_seconds / self.seeks, 3) if self.seeks else 0.0,
        }
        return {
            "example": self.example.name,
            "paused": self.paused,
            "finished": self.position >= self.source.end - 1,
            "speed": self.speed,
            "seed": self.seed,
            "behavior_hz": self.behavior_hz,
            "seq": latest.seq if latest else 0,
            "t": latest.t if latest else 0,
            "generation": gen.number if gen is not None else 0,
            "real_time_factor": 0.0 if self.paused else self.speed,
            "tick_ms": 0.0,
            "timing": {},
            "ring": {
                "frames": len(self.ring),
                "capacity": self.ring.capacity,
                "seconds": round(len(self.ring) / self.behavior_hz, 1),
                "bytes": self.ring.nbytes(),
                "record_seconds": self.recorder.record_seconds,
                "recorded": self.recorder.recorded,
            },
            "simulation": {"running": False, "pid": None, "restarts": 0, "crash": None, "pipe": {}},
            "programs": {},
            "world": latest_status(latest),
            "replay": replay,
        }


def latest_status(entry: Entry | None) -> dict[str, Any]:
    """The world status of ``entry`` (empty before the first tick)."""
    if entry is None or not entry.status:
        return {}
    status: dict[str, Any] = orjson.loads(entry.status)
    return status


# -- explain --------------------------------------------------------------------------------------


class TickValues:
    """What a recording without reads tells of one decision (``xabsl_studio.engine.runtime.debug.Values``).

    Enum values are element indices in their enumeration (the reader gives element names;
    unknown names are -1); plain inputs are the tick's,
    outputs as the decision saw them (the previous tick's, updated by the assignments that ran
    earlier in the same tick), parameters and times from the option's path node. Input functions
    with parameters, ``action_done`` and ``conflict`` are not recorded: :class:`Unknown`.
    """

    def __init__(
        self,
        agent: AgentTick,
        outputs: dict[str, Any],
        params: dict[str, Any],
        state_time: float | None,
        option_time: float,
    ) -> None:
        self.agent = agent
        self.outputs = outputs
        self.params = params
        self._state_time = state_time
        self.option_time = option_time
        enums = agent.program.description["enums"]
        self._elements: dict[str, list[str]] = {e["name"]: e["elements"] for e in enums}
        self._index = {element: i for e in enums for i, element in enumerate(e["elements"])}

    @property
    def state_time(self) -> float:
        """The decided-in state's time as the decision saw it (unknown after an unrecorded transition)."""
        if self._state_time is None:
            raise Unknown("the state's time before this tick's transition is not recorded")
        return self._state_time

    @state_time.setter
    def state_time(self, value: float) -> None:
        self._state_time = value

    def input(self, name: str, args: Mapping[str, Value]) -> Value:
        """The recorded value of a plain input."""
        if args or name not in self.agent.inputs:
            raise Unknown(f"{name} is not recorded")
        return self._value(self.agent.inputs[name])

    def output(self, name: str) -> Value:
        """The output as the decision saw it."""
        if name not in self.outputs:
            raise Unknown(f"{name} is not recorded")
        return self._value(self.outputs[name])

    def parameter(self, name: str) -> Value:
        """The option's parameter in the path node."""
        if name not in self.params:
            raise Unknown(f"parameter {name} is not recorded")
        return self._value(self.params[name])

    def element(self, element: str) -> Value:
        """The element's index in its enumeration."""
        return self._index.get(element, -1)

    def show(self, kind: Kind, enum: str | None, value: Value) -> str:
        """Enum elements by name, without their enumeration's prefix (an element's own dots stay)."""
        if kind is Kind.ENUM:
            elements = self._elements.get(enum or "", [])
            if isinstance(value, int) and 0 <= value < len(elements):
                return elements[value].removeprefix(f"{enum}.")
            return f"{value}?"
        return show_value(value)

    def _value(self, recorded: Any) -> Value:
        if recorded is None:
            raise Unknown("not recorded")
        if isinstance(recorded, str):  # an enum element
            return self._index.get(recorded, -1)
        value: Value = recorded
        return value

    def special(self, expression: Expression) -> Value:
        """``action_done`` and ``conflict`` are not recorded."""
        raise Unknown("not recorded")


def _decision_outputs(agent: AgentTick, previous: AgentTick | None, option_id: int) -> dict[str, Any]:
    """Outputs as option ``option_id``'s decision read them: last tick's, then this tick's earlier writes."""
    outputs = dict(previous.outputs) if previous is not None else dict(agent.outputs)
    enums = agent.program.tables["enums"]
    description = agent.program.description
    target = description["options"][option_id]["name"]

    def walk(nodes: Sequence[Any]) -> bool:
        for node in nodes:
            if isinstance(node, OptionNode):
                if node.option == target:
                    return True
                if walk(node.sub):
                    return True
            elif isinstance(node, AssignmentNode):
                value: Any = node.value
                if node.enum is not None:
                    value = enums.get(node.enum, {}).get(str(int(value)), value)
                outputs[node.symbol] = value
        return False

    walk(agent.tree())
    return outputs


def explain(
    program: Program,
    agent: AgentTick,
    previous: AgentTick | None,
    option: str | int,
    t: int,
    previous_view: TickView | None = None,
    why_not: int | str | None = None,
) -> dict[str, Any]:
    """Why ``option`` took its leaf in the recorded tick of ``agent`` (the live ``explain``'s shape).

    ``program`` is the agent's recorded generation (rebuilt from its IC). Each condition on the
    way to the recorded leaf has ``branch`` (taken, as recorded), ``value`` (computed from the
    recorded values; null when they do not tell) and ``comparisons``: per comparison its text,
    the value of each side (``?``: not recorded) and its result; ``tree`` is the decision tree
    with the path taken; with ``why_not`` (a state), ``why_not`` says why the decision did not
    go there, from the same values.

    Raises:
        CommandError: no such option or state, or it did not decide anything in that tick.
    """
    if isinstance(option, int):
        found = [o for o in program.options.values() if o.index == option]
        if not found:
            raise CommandError(f"no option {option}")
    else:
        found = [program.options[option]] if option in program.options else []
        if not found:
            raise CommandError(f"unknown option {option}")
    ir_option = found[0]
    node = next((n for n in agent.path if n[0] == 0 and n[2] == ir_option.index), None)
    if node is None:
        raise CommandError(f"option {ir_option.name} did not run in tick {agent.tick} of {agent.name}")
    decided_in, leaf = node[6], node[7]
    if leaf < 0:
        # a NaoTH game log (docs/naoth.md) says no leaf unless the structure made it certain
        raise CommandError(
            f"option {ir_option.name} decided nothing in that tick, or the recording does not say which leaf it took"
        )
    if not 0 <= decided_in < len(ir_option.states):
        raise CommandError(f"option {ir_option.name} has no state {decided_in}")
    decided = ir_option.states[decided_in]
    values: Values
    if agent.reads is not None:
        # What the decision read in that tick, exact (recordings since the reads were recorded).
        description = agent.program.description
        values = ReadValues(
            program,
            ir_option,
            decision_reads(agent.reads, ir_option.index),
            agent.program.read_enums(),
            {s["name"]: s["id"] for s in description["inputs"]},
            {s["name"]: s["id"] for s in description["outputs"]},
        )
    else:
        values = _recorded_values(agent, previous, ir_option, node, t, previous_view)
    try:
        explanation = explain_decision(
            ir_option, decided, leaf, values, functools.partial(render, option=ir_option.name)
        )
    except KeyError:
        raise CommandError(f"state {ir_option.name}.{decided.name} has no leaf {leaf}") from None
    result = explanation_result(ir_option, explanation)
    tree = tree_result(ir_option, decided.name, leaf, values)
    # The IC has no source text: show the conditions as they were written (the description's).
    source_texts(result, tree, agent.program.option(ir_option.index)["states"][decided_in]["decision"])
    result.update(recorded=True, tree=tree, last_transition=None)
    if why_not is not None:
        try:
            result["why_not"] = why_not_result(
                ir_option, decided, leaf, why_not, values, functools.partial(render, option=ir_option.name)
            )
        except DebugError as error:
            raise CommandError(str(error)) from None
        described = agent.program.option(ir_option.index)["states"][decided_in]["decision"]
        for route in result["why_not"]["routes"]:
            copy_texts(route["conditions"], described)
    return result


def _recorded_values(
    agent: AgentTick,
    previous: AgentTick | None,
    ir_option: Option,
    node: list[Any],
    t: int,
    previous_view: TickView | None,
) -> TickValues:
    """The values of a recording without reads: the tick's plain inputs, outputs and times (functions unknown)."""
    state_id, option_time, state_time, decided_in = node[3], node[4], node[5], node[6]
    # The decision saw the decided-in state's time: after a transition this tick, last tick's + a period.
    decision_state_time: float | None = float(state_time)
    if decided_in != state_id:
        decision_state_time = None
        if previous is not None and previous_view is not None:
            before = next((n for n in previous.path if n[0] == 0 and n[2] == ir_option.index), None)
            if before is not None and before[3] == decided_in:
                decision_state_time = float(before[5] + (t - previous_view.t))
    enums = agent.program.tables["enums"]
    params: dict[str, Any] = {}
    for p, value in zip(ir_option.params, node[8], strict=False):
        params[p.name] = enums.get(p.enum, {}).get(str(int(value)), value) if p.enum else value
    return TickValues(
        agent, _decision_outputs(agent, previous, ir_option.index), params, decision_state_time, float(option_time)
    )
