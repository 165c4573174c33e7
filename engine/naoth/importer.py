"""A NaoTH game log as a recording: ``xabsl import naoth LOG --behavior AGENTS_FILE -o REC.mcap``.

The behavior frames of the log (``BehaviorStateComplete`` when the behavior was loaded,
``BehaviorStateSparse`` per frame, ``FrameInfo`` for the time) are joined with our compile of
the same sources (:class:`~xabsl_studio.engine.naoth.join.BehaviorJoin`) and written as one
agent's ticks through the recordings' own encoder
(:class:`~xabsl_studio.engine.record.encoder.RecordingEncoder`), so replay, why, profile,
coverage, queries and behavior tests ``from`` a recording read a real game like any run.

What the recording holds and does not (its header says ``"source": "naoth-log"``):

* one tick per sparse frame of the log, in order; ``t`` is the frame's ``FrameInfo`` time (ms;
  the frame number times :data:`FRAME_MS` when the log has no FrameInfo) and the engine tick is
  the robot's frame number; frames the logger skipped are missing (counted: ``gaps``);
* the activation path with option and state times and parameters as the robot sent them; the
  decision leaves the robot does not send are -1 except where the structure makes them certain
  (``join.infer_decisions``: a state change between consecutive frames through the one leaf
  leading there), so transitions and leaf coverage count those; no assignment values, no ``reads``
  (a why then shows the decision with ``?`` where the log has no value);
* input and output symbols without parameters, from the complete message and the sparse diffs
  (exact; decimals kept to 3 digits as every recording); symbols the robot does not have: null;
* an agent switched on the robot is a ``select_agent`` event and new roots; a behavior loaded
  again on the robot is a ``note`` event (joined again: its load-time values are new).

A log whose behavior does not match the sources is refused with every difference named, unless
``allow_mismatch`` (the differences are then written as a ``note`` event and reported).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from xabsl_studio.engine.emit.ic import emit_ic
from xabsl_studio.engine.emit.json import program_to_json
from xabsl_studio.engine.errors import HostError
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.naoth import messages as M
from xabsl_studio.engine.naoth.join import BehaviorJoin, infer_decisions
from xabsl_studio.engine.naoth.log import LogError, LogReader
from xabsl_studio.engine.record import schema as S
from xabsl_studio.engine.record.encoder import NO_CHANGE, RecordingEncoder
from xabsl_studio.engine.record.sampler import ProgramTables
from xabsl_studio.engine.types import Kind

__all__ = ["BEHAVIOR_HZ", "FRAME_MS", "ImportResult", "SourceMismatch", "display_tables", "import_log"]

#: NaoTH's cognition runs at 30 frames per second: the recording's tick rate.
BEHAVIOR_HZ = 30
#: ms per frame when a log has no FrameInfo.
FRAME_MS = 33
_WANTED = frozenset({"FrameInfo", "BehaviorStateComplete", "BehaviorStateSparse"})


class SourceMismatch(HostError, ValueError):
    """The robot ran a behavior other than the sources'; ``mismatches`` names every difference."""

    def __init__(self, mismatches: list[str]) -> None:
        self.mismatches = mismatches
        shown = "\n  ".join(mismatches[:20])
        more = f"\n  ... and {len(mismatches) - 20} more" if len(mismatches) > 20 else ""
        super().__init__(f"the log's behavior does not match the sources:\n  {shown}{more}")


@dataclass(slots=True)
class ImportResult:
    """What an import wrote and what the log lacked."""

    path: str
    frames: int = 0
    #: frame numbers the logger skipped between two behavior frames
    gaps: int = 0
    #: sparse frames before the log's first complete message (nothing to join them with)
    unjoined: int = 0
    #: actions of the log the join could not place
    unplaced: int = 0
    loads: int = 0
    #: decision leaves the structure made certain (state changes between consecutive frames)
    inferred: int = 0
    agents: list[str] = field(default_factory=list)
    mismatches: list[str] = field(default_factory=list)
    truncated: int | None = None
    bytes: int = 0


def display_tables(program: Program) -> ProgramTables:
    """The value tables of an imported recording: enum values are element indices, decimals exact."""
    inputs = tuple(s for s in program.inputs.values() if not s.params)
    outputs = tuple(program.outputs.values())
    return ProgramTables(
        inputs=tuple(s.name for s in inputs),
        outputs=tuple(s.name for s in outputs),
        input_enums=tuple(s.enum if s.kind is Kind.ENUM else None for s in inputs),
        output_enums=tuple(s.enum if s.kind is Kind.ENUM else None for s in outputs),
        input_decimals=tuple(s.kind is Kind.DECIMAL for s in inputs),
        output_decimals=tuple(s.kind is Kind.DECIMAL for s in outputs),
        enums={name: dict(enumerate(enum.elements)) for name, enum in program.enums.items()},
        behavior_params={
            name: tuple((p.name, p.enum if p.kind is Kind.ENUM else None) for p in b.params)
            for name, b in program.behaviors.items()
        },
        assignment_sites=(),
    )


def import_log(
    log: str | Path,
    program: Program,
    out: str | Path,
    *,
    robot: str = "robot",
    sources: dict[str, Any] | None = None,
    allow_mismatch: bool = False,
) -> ImportResult:
    """Convert the behavior frames of NaoTH game log ``log`` into the recording ``out``.

    Args:
        log: the game log.
        program: our compile of the sources the robot ran.
        out: the ``.mcap`` file to write (atomically: ``out.part``, renamed when done).
        robot: the agent's name in the recording.
        sources: the program's source files (``engine.record.sources.program_sources``), for forks.
        allow_mismatch: import a log whose behavior differs from the sources (named in a note).

    Raises:
        LogError: not a game log. SourceMismatch: see ``allow_mismatch``.
        LogError: the log holds no behavior frames, or a message that does not decode.
    """
    reader = LogReader(log, _WANTED)
    result = ImportResult(str(out))
    encoder: RecordingEncoder | None = None
    join: BehaviorJoin | None = None
    key = "behavior"
    tables = display_tables(program)
    agent: str | None = None
    fault: Any = None
    last_frame: int | None = None
    previous: list[list[Any]] | None = None
    seq = 0
    try:
        for frame in reader.frames():
            complete = frame.records.get("BehaviorStateComplete")
            if complete is not None:
                join = BehaviorJoin(program, _parse(log, frame.number, "BehaviorStateComplete", complete))
                previous = None  # a loaded behavior starts afresh: no decision follows from before
                result.loads += 1
                if join.mismatches and not allow_mismatch:
                    raise SourceMismatch(join.mismatches)
                new = [m for m in join.mismatches if m not in result.mismatches]
                result.mismatches.extend(new)
                if encoder is not None:
                    _event(
                        encoder, seq, "note", None, {"text": "the robot loaded the behavior again", "mismatches": new}
                    )
            sparse_bytes = frame.records.get("BehaviorStateSparse")
            if sparse_bytes is None:
                continue
            if join is None:
                result.unjoined += 1
                continue
            sparse = _parse(log, frame.number, "BehaviorStateSparse", sparse_bytes)
            joined = join.frame(sparse)
            info = frame.records.get("FrameInfo")
            t = int(_parse(log, frame.number, "FrameInfo", info).time) if info is not None else frame.number * FRAME_MS
            if encoder is None:
                encoder = _open(out, program, key, robot, tables, sources)
                if join.mismatches:
                    _event(
                        encoder, 0, "note", None, {"text": "sources differ from the log", "mismatches": join.mismatches}
                    )
            if last_frame is not None and frame.number != last_frame + 1:
                result.gaps += max(0, frame.number - last_frame - 1)
                previous = None
            last_frame = frame.number
            result.inferred += infer_decisions(program, joined.path, previous)
            previous = joined.path
            roots: Any = NO_CHANGE
            if joined.agent != agent or seq == 0:
                if seq and joined.agent is not None:
                    _event(encoder, seq, "select_agent", robot, {"name": joined.agent})
                agent = joined.agent
                root = next((r for a, r in join.agents if a == agent), None)
                roots = [["option", root]] if root is not None else []
                if agent is not None and agent not in result.agents:
                    result.agents.append(agent)
            error = {"message": joined.error, "option": None, "state": None} if joined.error else None
            this_fault: Any = NO_CHANGE
            if error != fault or seq == 0:
                this_fault = fault = error
            result.unplaced += joined.unplaced
            sample = (frame.number, joined.path, (), joined.inputs, joined.outputs, roots, this_fault, (), None)
            encoder.handle(("tick", seq, t, [sample], {}, None))
            seq += 1
        result.truncated = reader.truncated
        if encoder is None:
            raise LogError(f"{log}: no behavior frames (BehaviorStateComplete, then BehaviorStateSparse) in the log")
        result.frames = seq
        _, _, _, result.bytes = encoder.close()
        return result
    except BaseException:
        if encoder is not None:
            encoder.abort()
        raise


def _open(
    out: str | Path, program: Program, key: str, robot: str, tables: ProgramTables, sources: dict[str, Any] | None
) -> RecordingEncoder:
    encoder = RecordingEncoder(out, BEHAVIOR_HZ, foxglove_scene=False)
    header = {
        "format": S.FORMAT,
        "version": S.VERSION,
        "example": f"naoth log {Path(out).stem}",
        "world": "naoth",
        "seed": 0,
        "behavior_hz": BEHAVIOR_HZ,
        "physics_hz": BEHAVIOR_HZ,
        "key_every": S.KEY_EVERY,
        "decimals": 3,
        "deterministic": False,
        "source": "naoth-log",
        "agents": [{"id": 0, "name": robot, "team": "", "number": 0, "program": key}],
        "tables": {key: tables.to_json()},
    }
    encoder.handle(("msg", S.RECORDING, "xabsl.Recording", 0, header))
    message: dict[str, Any] = {
        "seq": 0,
        "gen": 0,
        "key": key,
        "reason": "start",
        "program": program_to_json(program),
        "changed_files": [],
        "ic": emit_ic(program),
    }
    if sources is not None:
        message["sources"] = sources
    encoder.handle(("msg", S.PROGRAM, "xabsl.Program", 0, message))
    encoder.handle(("agent", 0, robot, tables, 0))
    encoder.handle(("static", 0, {"kind": "naoth"}, {}))
    return encoder


def _parse(log: str | Path, frame: int, name: str, data: bytes) -> Any:
    try:
        return M.parse(name, data)
    except M.DecodeError as error:
        raise LogError(f"{log}: frame {frame}: {name} does not decode ({error})") from None


def _event(encoder: RecordingEncoder, seq: int, kind: str, agent: str | None, data: dict[str, Any]) -> None:
    encoder.handle(
        ("msg", S.EVENTS, "xabsl.Event", seq, {"seq": seq, "t": 0, "kind": kind, "agent": agent, "data": data})
    )
