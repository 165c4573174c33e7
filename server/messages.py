"""Every message of the studio, typed: the websocket protocol and the pipe to the simulation process.

This module is the one vocabulary (docs/protocol.md), the way ``starlette/types.py`` is
Starlette's. Three groups of frozen dataclasses:

* **client -> server** (:data:`ClientMessage`): ``subscribe``, ``resync`` and one dataclass per
  command ``op`` with its typed arguments (:data:`Command`). :func:`parse_message` (websocket) and
  :func:`parse_command` (``POST /api/command``) parse *and validate* them once, at the server's
  edge, with pydantic in strict mode (no coercion, no NaN or infinities, integers within 64 bits,
  unknown fields refused): what gets past them is well typed, and what does not is a
  :class:`ProtocolError` whose text goes into an error ``reply``;
* **server -> client** (:data:`ServerMessage`): ``reply`` and the events are dataclasses encoded
  by :func:`encode`; ``hello``, ``frame`` and ``history`` are spliced from pre-encoded bytes for
  speed (``xabsl_studio.server.clients``, ``xabsl_studio.server.frames``), and their dataclasses here are
  the schema those bytes follow (tests validate real messages against it);
* **server <-> simulation process** (:data:`ToWorker`, :data:`FromWorker`): plain slotted
  dataclasses pickled over ``xabsl_studio.server.channel``; the per-tick :class:`Sample` is built without any
  validation (it is the hot path).

The TypeScript types of the web UI (``web/src/messages.gen.ts``) are generated from the JSON
Schema of the first two groups (``python -m xabsl_studio.server.tsgen``); a test fails when they drift.

The activation-path node layout is the engine's (``xabsl_studio.engine.runtime.activation.compact_path``);
:data:`OptionNode` and :data:`BehaviorNode` describe it and the ``*_INDEX`` constants name its
positions, so no other server module indexes a node by a bare number.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Annotated, Any, Literal

import orjson
from pydantic import BeforeValidator, ConfigDict, Discriminator, Field, TypeAdapter, ValidationError, with_config
from pydantic_core import ErrorDetails

from xabsl_studio.engine.errors import ServerError
from xabsl_studio.engine.runtime.activation import BEHAVIOR_NODE, OPTION_NODE
from xabsl_studio.server.protocol import DEFAULT_RATE, MAX_RATE, MAX_SPEED, MAX_STEP_TICKS, MIN_RATE, MIN_SPEED, VERSION

if TYPE_CHECKING:
    from xabsl_studio.engine.ir.model import Program
    from xabsl_studio.engine.runtime.breakpoints import Breakpoint

__all__ = [
    "BEHAVIOR_NODE",
    "OPTION_NODE",
    "ClientMessage",
    "Command",
    "ProtocolError",
    "ServerMessage",
    "encode",
    "parse_command",
    "parse_message",
]

# Strict: a string is not a number, a float is not an integer, a bool is neither; JSON numbers
# must be finite; a field the message type does not have is an error (a typo must not be ignored).
_STRICT = ConfigDict(strict=True, allow_inf_nan=False, extra="forbid")

# Server messages are never validated in production; tests validate real ones against these
# dataclasses, and a key the server sends that a dataclass does not declare must fail them.
_SCHEMA = ConfigDict(extra="forbid")


def _integral(value: object) -> object:
    """``3.0`` -> ``3``: JSON (and JSON Schema's ``integer``) does not tell 3.0 from 3; 3.5 stays a float."""
    return int(value) if isinstance(value, float) and value.is_integer() else value


# Integer arguments take an integral JSON number: ``3`` or ``3.0``, not ``3.5``, ``"3"`` or ``true``
# (the bounds come before the validator so that they stay in the JSON Schema).
_INTEGRAL = BeforeValidator(_integral)
#: The largest integer a command accepts (64-bit, as the engine's integers and JSON readers).
MAX_INT = 2**63 - 1
Int64 = Annotated[int, Field(ge=-MAX_INT - 1, le=MAX_INT)]
#: A number in a command: finite (``allow_inf_nan``), an integer within 64 bits.
Number = Int64 | float
#: A parameter or input value in a command: a number, a boolean, or an enum element (its index is
#: a number; its qualified name, ``"game.state.playing"``, a string).
CommandValue = bool | Int64 | float | str


def _not_integer(value: object) -> object:
    """An integer is no float id: one beyond 64 bits would come back rounded, not as it was sent."""
    if isinstance(value, int) and not isinstance(value, bool):
        raise ValueError("an integer id must fit in 64 bits")
    return value


#: A command's client-chosen id, echoed in its reply.
CommandId = Int64 | Annotated[float, BeforeValidator(_not_integer)] | str
#: A robot id: its index in ``hello.structure.robots``.
RobotId = Annotated[int, Field(ge=0, le=2**31), _INTEGRAL]
#: An option, basic behavior or symbol by id (the program JSON's) or by name.
Ref = Annotated[int, Field(ge=0, le=2**31), _INTEGRAL] | str
#: Behavior time in ms.
Ms = Annotated[int, Field(ge=0, le=2**62), _INTEGRAL]

HelloReason = Literal["connect", "reload", "reset", "resync", "fork"]


class ProtocolError(ServerError, ValueError):
    """A client message that cannot be carried out; its text goes into the error reply."""


# -- client -> server ------------------------------------------------------------------------------


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Subscribe:
    """Frames wanted: ``rate`` per second, values of ``robots`` only (``None``: all)."""

    type: Literal["subscribe"]
    rate: Annotated[float, Field(ge=MIN_RATE, le=MAX_RATE)] = DEFAULT_RATE
    robots: tuple[RobotId, ...] | None = None
    #: answered with an ok reply when given
    id: CommandId | None = None


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Resync:
    """Ask for a ``hello`` and a full frame (a frame's ``gen`` did not match the last hello)."""

    type: Literal["resync"]


# Every command has ``type`` (optional over REST), ``op`` and the client's ``id``; its arguments
# follow. ``op`` names the command; the classes are named after it.


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Pause:
    """Stop the simulation clock."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["pause"]


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Resume:
    """Restart the simulation clock."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["resume"]


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Step:
    """While paused: run ``ticks`` ticks."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["step"]
    ticks: Annotated[int, Field(ge=1, le=MAX_STEP_TICKS), _INTEGRAL] = 1


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Speed:
    """Run at real time x ``speed``."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["speed"]
    speed: Annotated[float, Field(ge=MIN_SPEED, le=MAX_SPEED)]


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Reset:
    """Rebuild the world and the engines (``seed``: default the current one); restarts a crashed simulation."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["reset"]
    seed: Annotated[int, Field(ge=0, le=2**32 - 1), _INTEGRAL] | None = None


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class SelectAgent:
    """The engine of ``robot`` runs the XABSL agent ``agent`` (a name of the program's ``agents``)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["select_agent"]
    robot: RobotId
    agent: str


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class ForceOption:
    """Replace the root of ``robot``'s engine by ``option`` with ``params`` (by name or short name)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["force_option"]
    robot: RobotId
    option: Ref
    params: dict[str, CommandValue] = field(default_factory=dict)


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class ForceBehavior:
    """Replace the root of ``robot``'s engine by the basic behavior ``behavior`` with ``params``."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["force_behavior"]
    robot: RobotId
    behavior: Ref
    params: dict[str, CommandValue] = field(default_factory=dict)


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Release:
    """Back to the normal root of ``robot``'s engine."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["release"]
    robot: RobotId


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class OverrideInput:
    """The input symbol ``symbol`` of ``robot``'s engine reads ``value``."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["override_input"]
    robot: RobotId
    symbol: Ref
    value: CommandValue


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class ReleaseInput:
    """``symbol`` (``None``: every overridden input of ``robot``) reads the host value again."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["release_input"]
    robot: RobotId
    symbol: Ref | None = None


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class ResetAgent:
    """Restart every option of ``robot``'s XABSL agent and clear a fault."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["reset_agent"]
    robot: RobotId


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Reload:
    """Recompile ``program`` (``None``: every behavior set) from disk and hot-swap it when clean."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["reload"]
    program: str | None = None


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Explain:
    """Why ``option`` of ``robot``'s engine took its leaf in the last tick or at tick ``seq`` (:class:`Explanation`)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["explain"]
    robot: RobotId
    option: Ref
    #: the tick (a ring buffer seq) to explain from recorded values; null: the live engine now
    seq: Annotated[int, Field(ge=0, le=2**62), _INTEGRAL] | None = None


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Seek:
    """A replay: make tick ``seq`` of the recording the current one (a live session refuses it)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["seek"]
    seq: Annotated[int, Field(ge=0, le=2**62), _INTEGRAL]


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class History:
    """Stream the ring buffer between behavior times ``t0`` and ``t1`` (every ``every``-th frame)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["history"]
    t0: Ms = 0
    t1: Ms = 2**62
    every: Annotated[int, Field(ge=1, le=2**31), _INTEGRAL] = 1


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Status:
    """The session status (as ``GET /api/status``)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["status"]


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class WorldCommand:
    """A command of the world itself (``engine.host.CommandableWorld``); without ``name``, the list of them."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["world_command"]
    name: str | None = None
    args: dict[str, Any] = field(default_factory=dict)


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Fork:
    """Run from tick ``seq`` of the live history again, with the current behavior (docs/studio.md "Fork").

    The world is rebuilt from its seed and re-simulated up to ``seq`` with the commands and
    behavior versions of the original run; tick ``seq`` and the ticks after it run live with the
    programs in force now, as a new generation (reason ``fork``).
    """

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["fork"]
    seq: Annotated[int, Field(ge=0, le=2**62), _INTEGRAL]


#: A breakpoint kind (``xabsl_studio.engine.runtime.breakpoints``).
BreakpointKindName = Literal["enter_option", "leave_option", "enter_state", "leave_state", "leaf", "condition"]
#: A breakpoint's id within its behavior set.
BreakpointId = Annotated[int, Field(ge=1, le=2**31), _INTEGRAL]


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class SetBreakpoint:
    """Add a breakpoint to behavior set ``program`` (or replace breakpoint ``breakpoint``); see docs/studio.md.

    ``program`` defaults to the behavior set of ``robot``, else the first one; ``robot`` null: any robot.
    """

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["set_breakpoint"]
    program: str | None = None
    breakpoint: BreakpointId | None = None
    kind: BreakpointKindName
    option: str | None = None
    state: str | None = None
    leaf: Annotated[int, Field(ge=0, le=2**31), _INTEGRAL] | None = None
    condition: Annotated[str, Field(max_length=2000)] | None = None
    robot: RobotId | None = None
    enabled: bool = True


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class RemoveBreakpoint:
    """Remove breakpoint ``breakpoint`` of behavior set ``program`` (default: the first)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["remove_breakpoint"]
    program: str | None = None
    breakpoint: BreakpointId


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class EnableBreakpoint:
    """Enable or disable breakpoint ``breakpoint`` of behavior set ``program`` (default: the first)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["enable_breakpoint"]
    program: str | None = None
    breakpoint: BreakpointId
    enabled: bool


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class ListBreakpoints:
    """The breakpoints of every behavior set (or of ``program``)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["list_breakpoints"]
    program: str | None = None


@with_config(_STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class CheckCondition:
    """Check ``condition`` against behavior set ``program``'s symbols (default: the first): diagnostics."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["check_condition"]
    program: str | None = None
    condition: Annotated[str, Field(max_length=2000)]


Command = Annotated[
    Pause
    | Resume
    | Step
    | Speed
    | Reset
    | SelectAgent
    | ForceOption
    | ForceBehavior
    | Release
    | OverrideInput
    | ReleaseInput
    | ResetAgent
    | Reload
    | Explain
    | History
    | Status
    | WorldCommand
    | SetBreakpoint
    | RemoveBreakpoint
    | EnableBreakpoint
    | ListBreakpoints
    | CheckCondition
    | Seek
    | Fork,
    Discriminator("op"),
]
#: Breakpoint commands: the server process keeps (and persists) breakpoints, the simulation checks them.
BreakpointCommand = SetBreakpoint | RemoveBreakpoint | EnableBreakpoint | ListBreakpoints | CheckCondition
#: Commands that address one robot's engine (they have a ``robot`` field).
RobotCommand = SelectAgent | ForceOption | ForceBehavior | Release | OverrideInput | ReleaseInput | ResetAgent | Explain
ClientMessage = Annotated[Subscribe | Resync | Command, Discriminator("type")]

_client_adapter: TypeAdapter[Subscribe | Resync | Command] = TypeAdapter(ClientMessage)
_command_adapter: TypeAdapter[Command] = TypeAdapter(Command)
#: The ops, in the order of docs/protocol.md (the discriminator's tags).
OPS: tuple[str, ...] = tuple(_command_adapter.core_schema["choices"])


def openapi_schemas(ref_template: str = "#/components/schemas/{model}") -> dict[str, Any]:
    """JSON Schemas of ``Command`` and ``Reply`` and every type they use, for an OpenAPI document."""
    reply: TypeAdapter[RestReply] = TypeAdapter(RestReply)
    schemas, defs = TypeAdapter.json_schemas(
        [("Command", "validation", _command_adapter), ("RestReply", "serialization", reply)],
        ref_template=ref_template,
    )
    result: dict[str, Any] = dict(defs.get("$defs", {}))
    result["Command"] = schemas[("Command", "validation")]
    return result


def parse_message(data: str | bytes) -> Subscribe | Resync | Command:
    """Read and validate one websocket message.

    Raises:
        ProtocolError: bad JSON, not an object, unknown ``type`` or ``op``, a missing, unknown or
            ill-typed argument, a number out of range or not finite.
    """
    try:
        return _client_adapter.validate_json(data)
    except ValidationError as error:
        raise ProtocolError(_explain(error)) from None


def parse_command(data: str | bytes) -> Command:
    """Read and validate one command without ``type`` (``POST /api/command``); see :func:`parse_message`."""
    try:
        return _command_adapter.validate_json(data)
    except ValidationError as error:
        raise ProtocolError(_explain(error)) from None


_TYPE_NAMES = {
    "bool_type": "a boolean",
    "int_type": "an integer",
    "float_type": "a number",
    "string_type": "a string",
    "none_required": "null",
    "tuple_type": "a list",
    "list_type": "a list",
    "dict_type": "an object",
}


def guess_id(data: str | bytes) -> int | float | str | None:
    """The ``id`` of a message that did not validate, when it has a usable one (for the error reply)."""
    try:
        message = orjson.loads(data)
    except orjson.JSONDecodeError:
        return None
    value = message.get("id") if isinstance(message, dict) else None
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        return None
    return value if not isinstance(value, int) or -MAX_INT - 1 <= value <= MAX_INT else None


def _explain(error: ValidationError) -> str:
    """A ValidationError as one line a user can act on (one problem per argument, at most three)."""
    problems: list[str] = []
    groups: dict[str, list[ErrorDetails]] = {}
    for item in error.errors(include_url=False):
        kind, ctx, loc = item["type"], item.get("ctx", {}), item["loc"]
        if kind == "json_invalid":
            problems.append(f"bad JSON: {ctx.get('error', item['msg'])}")
        elif not loc and kind in ("dict_type", "model_attributes_type", "dataclass_type"):
            problems.append("a message must be a JSON object")
        elif kind == "union_tag_invalid" and ctx.get("discriminator") == "'type'":
            problems.append(f"unknown message type {ctx.get('tag')!r} (expected one of: subscribe, command, resync)")
        elif kind == "union_tag_invalid":
            problems.append(f"unknown op {ctx.get('tag')!r} (expected one of: {', '.join(OPS)})")
        elif kind == "union_tag_not_found":
            problems.append(f"{str(ctx.get('discriminator', 'a tag')).strip(chr(39))} is required")
        else:
            # The members of a union (``value`` may be a boolean, an integer, a number, a string)
            # fail one by one: gather them under the argument they belong to.
            parts = [str(part) for part in loc]
            while len(parts) > 1 and parts[0] in ("command", "subscribe", "resync", *OPS):
                parts.pop(0)
            if len(parts) > 1 and (parts[-1] in _UNION_MEMBERS or "[" in parts[-1]):
                parts.pop()
            groups.setdefault(".".join(parts), []).append(item)
    for where, items in groups.items():
        if len(items) == 1:
            item = items[0]
            text = "unknown argument" if item["type"] == "unexpected_keyword_argument" else item["msg"]
            problems.append(f"{where}: {text}")
            continue
        # A bound or finiteness problem of one member says more than "not a string" of another.
        specific = [i["msg"] for i in items if i["type"] not in _TYPE_NAMES]
        if specific:
            problems.append(f"{where}: {'; '.join(dict.fromkeys(specific))}")
        else:
            names = dict.fromkeys(_TYPE_NAMES.get(i["type"], i["type"]) for i in items)
            problems.append(f"{where}: must be {' or '.join(names)}")
    if len(problems) > 3:
        problems[3:] = [f"and {len(problems) - 3} more"]
    return "; ".join(problems)


_UNION_MEMBERS = frozenset({"bool", "int", "constrained-int", "float", "constrained-float", "str", "none"})


# -- server -> client ------------------------------------------------------------------------------


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class Reply:
    """The answer to a command (and the error answer to a bad message: ``id`` then may be null)."""

    type: Literal["reply"] = "reply"
    id: CommandId | None
    ok: bool
    result: Any = None
    error: str | None = None


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class RestReply(Reply):
    """A reply over REST (``POST /api/command``): ``detail`` repeats ``error``, as in every REST error."""

    detail: str | None = None


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class FileEvent:
    """A behavior file was written, created, renamed or deleted (by any client)."""

    type: Literal["event"] = "event"
    event: Literal["file"] = "file"
    path: str
    version: str | None
    deleted: bool


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class CompileEvent:
    """A behavior set was compiled after a file change (``ok``: a ``hello`` with reason reload follows)."""

    type: Literal["event"] = "event"
    event: Literal["compile"] = "compile"
    program: str
    ok: bool
    diagnostics: list[dict[str, Any]]


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class CrashEvent:
    """The simulation process stopped (``seq``/``t`` of its last tick); ``reset`` restarts it."""

    type: Literal["event"] = "event"
    event: Literal["crash"] = "crash"
    message: str
    seq: int
    t: int | None


@with_config(_SCHEMA)
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


@with_config(_SCHEMA)
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


@with_config(_SCHEMA)
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


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class Structure:
    """The ids of a generation: one program JSON per behavior set (``xabsl_studio.engine.emit.json``), the robots."""

    programs: dict[str, dict[str, Any]]
    robots: list[RobotInfo]


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class ForkOrigin:
    """Where the running world was forked (``fork``): the original's tick ``seq`` (time ``t``) ran again as ``start``.

    The original run's ticks stay in the ring at the older seqs (``GET /api/fork/original``).
    """

    seq: int
    t: int
    start: int


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class Hello:
    """Sent on connect, after every reload and reset, and in answer to ``resync``: the ids from now on."""

    type: Literal["hello"] = "hello"
    version: int
    reason: HelloReason
    generation: int
    session: SessionInfo
    structure: Structure
    #: the world's static scene (world-defined)
    scene: dict[str, Any]
    #: the fork the running world comes from (null: none since the last reset); kept across reloads
    fork: ForkOrigin | None = None


#: A symbol or parameter value in a frame: decimals rounded, enums as element indices (-1: none),
#: null when the host value cannot be shown (NaN).
WireValue = bool | int | float | None

#: ``[0, depth, option_id, state_id, option_time, state_time, decided_in_state_id, leaf_id, [params]]``
OptionNode = tuple[Literal[0], int, int, int, int, int, int, int, list[WireValue]]
#: ``[1, depth, behavior_id, time_of_execution, [params]]``
BehaviorNode = tuple[Literal[1], int, int, int, list[WireValue]]
PathNode = OptionNode | BehaviorNode
#: Positions in a node (both kinds): kind, depth, option or basic behavior id.
KIND_INDEX, DEPTH_INDEX, ID_INDEX = 0, 1, 2
#: Position of the parameter values in an option node and in a basic behavior node.
OPTION_PARAMS_INDEX, BEHAVIOR_PARAMS_INDEX = 8, 4


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class Fault:
    """Why a robot's engine stopped (until ``reset_agent``)."""

    message: str
    option: str | None
    state: str | None


@with_config(_SCHEMA)
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


@with_config(_SCHEMA)
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


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class HistoryChunk:
    """Frames of the ring buffer answering a ``history`` command (its own delta stream)."""

    type: Literal["history"] = "history"
    id: CommandId | None
    chunk: int
    last: bool
    frames: list[Frame]


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class Comparison:
    """One comparison inside a condition with the values of its two sides (``ball.distance (412.3) < 500``)."""

    text: str
    op: str
    left: str
    left_value: str
    right: str
    right_value: str
    value: bool | None
    shown: str


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class Condition:
    """One ``if`` on the path to the leaf an option's decision took, with the values it had."""

    text: str
    source: str
    value: bool | int | float | str | None
    branch: bool
    span: dict[str, Any] | None
    comparisons: list[Comparison] = field(default_factory=list)


@with_config(_SCHEMA)
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


@with_config(_SCHEMA)
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


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class PausedResult:
    """The result of ``pause`` and ``resume``."""

    paused: bool


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class SeekResult:
    """The result of ``seek``: the current tick and the recording's length in ticks."""

    seq: int
    ticks: int


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class ForkResult:
    """The result of ``fork``: tick ``seq`` runs again as ``start`` after re-simulating ``ticks`` ticks in ``ms``."""

    seq: int
    t: int
    start: int
    ticks: int
    ms: float


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class StepResult:
    """The result of ``step``: the last tick run."""

    seq: int
    t: int


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class SpeedResult:
    """The result of ``speed``."""

    speed: float


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class ResetResult:
    """The result of ``reset``: the seed the new world was built with."""

    seed: int


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class ProgramCompile:
    """One behavior set's compile in a ``reload`` result (``error``: why the running one was kept)."""

    ok: bool
    diagnostics: list[dict[str, Any]]
    error: str | None


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class ReloadResult:
    """The result of ``reload``, per behavior set."""

    programs: dict[str, ProgramCompile]


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class HistoryResult:
    """The result of ``history``: how many frames and chunks follow, and the generations they belong to."""

    frames: int
    chunks: int
    generations: list[GenerationInfo] = field(default_factory=list)


@with_config(_SCHEMA)
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


@with_config(_SCHEMA)
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


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class BreakpointList:
    """The result of ``list_breakpoints`` (and of the commands that change them)."""

    breakpoints: list[BreakpointInfo]


@with_config(_SCHEMA)
@dataclass(frozen=True, slots=True, kw_only=True)
class ConditionCheck:
    """The result of ``check_condition``: diagnostics with line and column in the condition's text."""

    ok: bool
    diagnostics: list[dict[str, Any]]


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
) -> bytes:
    """A :class:`Hello` spliced from the generation's pre-encoded ``structure`` and ``scene``."""
    head = b'{"type":"hello","version":%d,"reason":%s,"generation":%d,"session":' % (
        VERSION,
        orjson.dumps(reason),
        generation,
    )
    tail = b',"fork":%s}' % orjson.dumps(fork)
    return b"".join([head, orjson.dumps(session), b',"structure":', structure, b',"scene":', scene, tail])


def encode_history_chunk(command_id: CommandId | None, index: int, last: bool, frames: list[bytes]) -> bytes:
    """A :class:`HistoryChunk` around frames encoded already (``xabsl_studio.server.frames.history``)."""
    return b'{"type":"history","id":%s,"chunk":%d,"last":%s,"frames":[%s]}' % (
        orjson.dumps(command_id),
        index,
        b"true" if last else b"false",
        b",".join(frames),
    )


# -- server <-> simulation process -----------------------------------------------------------------


@dataclass(frozen=True, slots=True)
class Sample:
    """One tick as the simulation sends it (built every tick, never validated).

    Per robot (world order): the path as JSON bytes, the extras (fault, force, overrides:
    ``b',"fault":...'`` or ``b''``), the input and output values aligned with the generation's
    symbol ids; then the dynamic scene and the world status as JSON bytes.
    """

    seq: int
    gen: int
    t: int
    wall: float
    paused: bool
    speed: float
    paths: tuple[bytes, ...]
    extras: tuple[bytes, ...]
    inputs: tuple[tuple[WireValue, ...], ...]
    outputs: tuple[tuple[WireValue, ...], ...]
    scene: bytes
    status: bytes


@dataclass(frozen=True, slots=True)
class NewGeneration:
    """New ids (start, reload, reset), sent before the generation's first sample."""

    number: int
    reason: HelloReason
    #: the hello's ``structure`` and ``scene`` as JSON bytes
    structure: bytes
    scene: bytes
    #: per robot: the symbol ids its sample's input and output tuples are aligned with
    input_ids: tuple[tuple[int, ...], ...]
    output_ids: tuple[tuple[int, ...], ...]
    seed: int
    #: per behavior set: why it does not run on this host (None: it runs)
    errors: dict[str, str | None]
    #: a ``fork`` generation: ``(seq forked at, its time, the seq of this generation's first sample)``
    fork: tuple[int, int, int] | None = None


@dataclass(frozen=True, slots=True)
class WorkerReply:
    """The answer to a :class:`WorkerRequest` (after the samples the command produced)."""

    ident: int | None
    ok: bool
    result: Any
    error: str | None


@dataclass(frozen=True, slots=True)
class Crash:
    """An exception escaped the world: the simulation process ends after this message."""

    message: str
    traceback: str
    seq: int
    t: int


@dataclass(frozen=True, slots=True)
class Apply:
    """Hot-swap a program the server compiled clean into the engines of behavior set ``key``."""

    key: str
    program: Program
    program_json: dict[str, Any]
    op: Literal["apply"] = "apply"


@dataclass(frozen=True, slots=True)
class ReleaseOwner:
    """Release what client ``owner`` forced and overrode (it disconnected); nobody awaits the answer."""

    op: Literal["release_owner"] = "release_owner"


@dataclass(frozen=True, slots=True)
class SetBreakpoints:
    """Internal: the breakpoints of behavior set ``key`` (all of them; the server keeps and stores them)."""

    key: str
    points: tuple[Breakpoint, ...]
    op: Literal["set_breakpoints"] = "set_breakpoints"


@dataclass(frozen=True, slots=True)
class ExplainRecorded:
    """Internal: explain decisions from recorded values (``explain`` with ``seq``, prepared by the server).

    ``ticks`` holds the explained tick first, then the tick of the last transition (if any):
    ``(seq, t, decided_in, leaf, active state, inputs by id, outputs by id, option params, state_time,
    option_time)``; values as the ring buffer holds them (display values, enums as element indices).
    """

    robot: int
    option: str
    generation: int
    ticks: tuple[tuple[Any, ...], ...]
    op: Literal["explain_recorded"] = "explain_recorded"


@dataclass(frozen=True, slots=True)
class ForkAt:
    """Internal: ``fork`` at tick ``seq`` as the server prepared it, with what the ring recorded around it.

    ``recorded`` holds ticks ``seq - 1`` and ``seq`` (those still in the ring): per robot its path
    (decoded JSON) and the dynamic scene; the re-simulated state must equal the one the fork
    starts from (docs/studio.md "Fork").
    """

    seq: int
    recorded: dict[int, tuple[tuple[Any, ...], Any]]
    op: Literal["fork"] = "fork"


#: What the simulation carries out: the commands not handled in the server process, and internal ones.
WorkerCommand = (
    Pause
    | Resume
    | Step
    | Speed
    | Reset
    | RobotCommand
    | Status
    | WorldCommand
    | Seek
    | Apply
    | ReleaseOwner
    | SetBreakpoints
    | ExplainRecorded
    | ForkAt
)


@dataclass(frozen=True, slots=True)
class WorkerRequest:
    """A command for the simulation; ``owner``: the client it comes from (None: REST, the server)."""

    ident: int | None
    body: WorkerCommand
    owner: str | None


@dataclass(frozen=True, slots=True)
class Stop:
    """End the simulation process."""


@dataclass(frozen=True, slots=True)
class Hit:
    """A breakpoint hit in the tick of sample ``seq`` (sent after that sample); the simulation paused."""

    key: str
    breakpoint: int
    robot: int
    seq: int
    t: int
    description: str


ToWorker = WorkerRequest | Stop
FromWorker = Sample | NewGeneration | WorkerReply | Crash | Hit
