"""What the studio sends a client: ``reply`` and its results per op, the events, ``hello``, frames.

``reply`` and the events are dataclasses encoded by :func:`encode`; ``hello``, ``frame`` and
``history`` are spliced from pre-encoded bytes for speed (``xabsl_studio.server.api.clients``,
``xabsl_studio.server.session.frames``), and their dataclasses here are the schema those bytes
follow (tests validate real messages against it). Generated into ``web/src/messages.gen.ts``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

import orjson
from pydantic import with_config

from xabsl_studio.engine.lang.diagnostics import DiagnosticJson
from xabsl_studio.engine.runtime.debug import Comparison
from xabsl_studio.server.protocol.limits import VERSION
from xabsl_studio.server.protocol.types import SCHEMA, CommandId, HelloReason, PathNode, WireValue


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class Reply:
    """The answer to a command (and the error answer to a bad message: ``id`` then may be null)."""

    type: Literal["reply"] = "reply"
    id: CommandId | None
    ok: bool
    result: Any = None
    error: str | None = None


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class RestReply(Reply):
    """A reply over REST (``POST /api/command``): ``detail`` repeats ``error``, as in every REST error."""

    detail: str | None = None


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class FileEvent:
    """A behavior file was written, created, renamed or deleted: by a client of the studio, or on disk.

    ``by`` is ``"studio"`` for a save through the file API (any client's), ``"disk"`` for a change
    made outside the studio (a ``git checkout``, another editor) that the file watcher noticed.
    """

    type: Literal["event"] = "event"
    event: Literal["file"] = "file"
    path: str
    version: str | None
    deleted: bool
    by: Literal["studio", "disk"] = "studio"


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class CompileEvent:
    """A behavior set was compiled after a file change (``ok``: a ``hello`` with reason reload follows)."""

    type: Literal["event"] = "event"
    event: Literal["compile"] = "compile"
    program: str
    ok: bool
    diagnostics: list[DiagnosticJson]


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class CrashEvent:
    """The simulation process stopped (``seq``/``t`` of its last tick); ``reset`` restarts it."""

    type: Literal["event"] = "event"
    event: Literal["crash"] = "crash"
    message: str
    seq: int
    t: int | None


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class BreakpointEvent:
    """A breakpoint hit: the simulation paused after tick ``seq`` (time ``t``) of robot ``robot``."""

    type: Literal["event"] = "event"
    event: Literal["breakpoint"] = "breakpoint"
    program: str
    breakpoint: int
    robot: int
    seq: int
    t: int
    description: str


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class SessionInfo:
    """The session as a ``hello`` describes it."""

    example: str
    paused: bool
    speed: float
    seed: int
    behavior_hz: int
    seq: int
    t: int
    token_required: bool
    #: ms the timeline adds to this generation's ``t`` (a reset restarts the clock, not the timeline)
    offset: int = 0


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class RobotInfo:
    """A robot of the world; ``program``: the behavior set it runs (``None``: no XABSL behavior).

    ``engine`` is false while its behavior set has errors and never compiled clean: ``program``
    then names the set whose parsed part the studio shows, and the robot stands until it compiles.
    """

    id: int
    name: str
    team: str
    number: int
    program: str | None
    engine: bool = True


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class Structure:
    """The ids of a generation: one program JSON per behavior set (``xabsl_studio.engine.emit.json``), the robots."""

    programs: dict[str, dict[str, Any]]
    robots: list[RobotInfo]


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class ForkOrigin:
    """Where the running world was forked (``fork``): the original's tick ``seq`` (time ``t``) ran again as ``start``.

    The original run's ticks stay in the ring at the older seqs (``GET /api/fork/original``).
    """

    seq: int
    t: int
    start: int


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class Hello:
    """Sent on connect, after every reload and reset, and in answer to ``resync``: the ids from now on."""

    type: Literal["hello"] = "hello"
    version: int
    reason: HelloReason
    generation: int
    session: SessionInfo
    #: the robots and behavior descriptions (spans packed: ``xabsl_studio.server.protocol.packing``);
    #: null when ``structure_z`` carries it
    structure: Structure | None
    #: the world's static scene (world-defined)
    scene: dict[str, Any]
    #: the fork the running world comes from (null: none since the last reset); kept across reloads
    fork: ForkOrigin | None = None
    #: a large structure, compressed: base64 of the zlib-compressed JSON of ``structure``
    #: (``packing.compress_structure``; the receiver inflates it before use)
    structure_z: str | None = None


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class Fault:
    """Why a robot's engine stopped (until ``reset_agent``)."""

    message: str
    option: str | None
    state: str | None


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class RobotFrame:
    """One robot in a frame; values only for subscribed robots, extras only while they apply."""

    id: int
    path: list[PathNode]
    outputs: dict[str, WireValue] | None = None
    inputs: dict[str, WireValue] | None = None
    fault: Fault | None = None
    #: ``[0, option_id]`` or ``[1, behavior_id]``
    forced: tuple[Literal[0, 1], int] | None = None
    overrides: dict[str, WireValue] | None = None


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class Frame:
    """One tick: full, or the changes since the previous frame this client received."""

    type: Literal["frame"] = "frame"
    seq: int
    gen: int
    t: int
    wall: float
    full: bool
    robots: list[RobotFrame]
    #: the world's dynamic scene (world-defined)
    scene: dict[str, Any]
    #: the world's status, when it changed (and in every full frame)
    status: dict[str, Any] | None = None


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class HistoryChunk:
    """Frames of the ring buffer answering a ``history`` command (its own delta stream)."""

    type: Literal["history"] = "history"
    id: CommandId | None
    chunk: int
    last: bool
    frames: list[Frame]


# One comparison inside a condition with the values of its two sides: the engine's own
# definition is the wire shape (validated like the others: no key it does not declare).
with_config(SCHEMA)(Comparison)


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class Condition:
    """One ``if`` on the path to the leaf an option's decision took, with the values it had."""

    text: str
    source: str
    value: bool | int | float | str | None
    branch: bool
    span: dict[str, Any] | None
    comparisons: list[Comparison] = field(default_factory=list)


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class LastTransition:
    """The last transition of the option up to the explained tick: when, from where to where, why."""

    seq: int
    t: int
    decided_in: int
    decided_in_name: str
    target: int
    target_name: str
    leaf: int
    conditions: list[Condition]
    tree: dict[str, Any]


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class Route:
    """One leaf of the decision that goes to the asked-for state, and the conditions on its way.

    Each condition's ``branch`` is the branch this route needs, ``value`` what it was (null:
    the decision did not read what it takes: it never got that far).
    """

    leaf: int
    stay: bool
    leaf_span: dict[str, Any] | None
    conditions: list[Condition]
    #: the first condition whose value is not the branch needed (null: none known)
    blocked_at: int | None
    #: the condition where this route leaves the path the decision took (null: the leaf taken)
    parts_at: int | None


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class WhyNot:
    """Why the explained decision did not go to state ``target``: every route there, each with its blocker."""

    target: int
    target_name: str
    #: the decision did go there (one route is then the leaf taken)
    went: bool
    routes: list[Route]


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class Explanation:
    """The result of ``explain``."""

    option: int
    option_name: str
    decided_in: int
    decided_in_name: str
    leaf: int
    target: int
    target_name: str
    stay: bool
    leaf_span: dict[str, Any] | None
    conditions: list[Condition]
    #: the explained tick (null: the live engine now) and whether values are the recorded ones
    seq: int | None = None
    t: int | None = None
    recorded: bool = False
    #: the decision tree of ``decided_in``: ``{"if", "value", "taken", "then", "else"}`` or
    #: ``{"leaf", "target", "stay", "taken"}`` (``taken``: on the path of this decision)
    tree: dict[str, Any] = field(default_factory=dict)
    #: the last transition up to this tick found in the ring buffer (null: none recorded)
    last_transition: LastTransition | None = None
    #: with ``why_not`` asked: why this decision did not go to that state
    why_not: WhyNot | None = None


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class PausedResult:
    """The result of ``pause`` and ``resume``."""

    paused: bool


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class SeekResult:
    """The result of ``seek``: the current tick and the recording's length in ticks."""

    seq: int
    ticks: int


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class ForkResult:
    """The result of ``fork``: tick ``seq`` runs again as ``start`` after re-simulating ``ticks`` ticks in ``ms``."""

    seq: int
    t: int
    start: int
    ticks: int
    ms: float


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class StepResult:
    """The result of ``step``: the last tick run."""

    seq: int
    t: int


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class SpeedResult:
    """The result of ``speed``."""

    speed: float


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class ResetResult:
    """The result of ``reset``: the seed the new world was built with."""

    seed: int


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class ProgramCompile:
    """One behavior set's compile in a ``reload`` result (``error``: why the running one was kept)."""

    ok: bool
    diagnostics: list[dict[str, Any]]
    error: str | None


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class ReloadResult:
    """The result of ``reload``, per behavior set."""

    programs: dict[str, ProgramCompile]


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class HistoryResult:
    """The result of ``history``: how many frames and chunks follow, and the generations they belong to."""

    frames: int
    chunks: int
    generations: list[GenerationInfo] = field(default_factory=list)


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class GenerationInfo:
    """A generation whose ticks a ``history`` answer holds (docs/protocol.md "history").

    ``structure`` and ``scene`` (as in its hello) are sent for every generation but the current
    one, whose hello the client has; ``offset`` is what the timeline adds to its ticks' ``t``;
    ``seq``, ``t``: its first tick still in the ring buffer; ``changed_files``: the behavior files
    whose text differs from the previous generation's (``GET /api/generations/{number}/diff``).
    """

    number: int
    reason: HelloReason
    offset: int
    seq: int
    t: int
    changed_files: list[str]
    structure: Structure | None = None
    scene: dict[str, Any] | None = None


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class BreakpointInfo:
    """One breakpoint as ``list_breakpoints`` shows it (``problem``: why it is not checked now)."""

    program: str
    breakpoint: int
    kind: str
    option: str | None
    state: str | None
    leaf: int | None
    condition: str | None
    robot: int | None
    enabled: bool
    description: str
    problem: str | None


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class BreakpointList:
    """The result of ``list_breakpoints`` (and of the commands that change them)."""

    breakpoints: list[BreakpointInfo]


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class ConditionCheck:
    """The result of ``check_condition``: diagnostics with line and column in the condition's text."""

    ok: bool
    diagnostics: list[dict[str, Any]]


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class QueryInterval:
    """Ticks ``first_seq`` .. ``last_seq`` of robot ``robot`` (id; ``name``) in which the query holds; times in ms."""

    robot: int
    name: str
    first_seq: int
    last_seq: int
    first_t: int
    last_t: int


@with_config(SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class QueryAnswer:
    """The result of ``query``: the intervals by first tick, the robot ticks evaluated, matching, unknown.

    ``skipped``: per robot name, why the condition was not evaluated for it (its behavior lacks a
    name the condition uses).
    """

    condition: str
    intervals: list[QueryInterval]
    ticks: int
    matched: int
    unknown: int
    skipped: dict[str, str]


#: The ``result`` of a successful reply, per op (None: no result; ``status``: the session status).
RESULTS: dict[str, Any] = {
    "pause": PausedResult,
    "resume": PausedResult,
    "step": StepResult,
    "speed": SpeedResult,
    "reset": ResetResult,
    "select_agent": None,
    "force_option": None,
    "force_behavior": None,
    "release": None,
    "override_input": None,
    "release_input": None,
    "reset_agent": None,
    "reload": ReloadResult,
    "explain": Explanation,
    "history": HistoryResult,
    "status": dict[str, Any],
    "world_command": Any,
    "seek": SeekResult,
    "fork": ForkResult,
    "set_breakpoint": BreakpointList,
    "remove_breakpoint": BreakpointList,
    "enable_breakpoint": BreakpointList,
    "list_breakpoints": BreakpointList,
    "check_condition": ConditionCheck,
    "query": QueryAnswer,
    "attach_host": dict[str, Any],
}

ServerEvent = FileEvent | CompileEvent | CrashEvent | BreakpointEvent
ServerMessage = Hello | Frame | Reply | HistoryChunk | FileEvent | CompileEvent | CrashEvent | BreakpointEvent


def encode(message: Reply | ServerEvent) -> bytes:
    """A server message as JSON bytes (orjson encodes the dataclasses natively)."""
    return orjson.dumps(message, option=orjson.OPT_NON_STR_KEYS)


def encode_hello(
    reason: HelloReason,
    generation: int,
    session: SessionInfo,
    structure: bytes,
    scene: bytes,
    fork: ForkOrigin | None = None,
    structure_z: bytes | None = None,
) -> bytes:
    """A :class:`Hello` spliced from the generation's pre-encoded ``structure`` and ``scene``.

    With ``structure_z`` (the compressed structure, base64 ASCII) that is sent instead.
    """
    head = b'{"type":"hello","version":%d,"reason":%s,"generation":%d,"session":' % (
        VERSION,
        orjson.dumps(reason),
        generation,
    )
    tail = b',"fork":%s}' % orjson.dumps(fork)
    if structure_z is not None:
        structure, tail = b"null", b',"fork":%s,"structure_z":"%s"}' % (orjson.dumps(fork), structure_z)
    return b"".join([head, orjson.dumps(session), b',"structure":', structure, b',"scene":', scene, tail])


def encode_history_chunk(command_id: CommandId | None, index: int, last: bool, frames: list[bytes]) -> bytes:
    """A :class:`HistoryChunk` around frames encoded already (``xabsl_studio.server.session.frames.history``)."""
    return b'{"type":"history","id":%s,"chunk":%d,"last":%s,"frames":[%s]}' % (
        orjson.dumps(command_id),
        index,
        b"true" if last else b"false",
        b",".join(frames),
    )
