"""What a client sends the studio: ``subscribe``, ``resync`` and one dataclass per command ``op``.

:func:`parse_message` (websocket) and :func:`parse_command` (``POST /api/command``) parse *and
validate* them once, at the server's edge, with pydantic in strict mode (no coercion, no NaN or
infinities, integers within 64 bits, unknown fields refused): what gets past them is well typed,
and what does not is a :class:`~xabsl_studio.server.protocol.types.ProtocolError` whose text goes
into an error ``reply``. docs/protocol.md lists the ops.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Annotated, Any, Literal

import orjson
from pydantic import Discriminator, Field, TypeAdapter, ValidationError, with_config
from pydantic_core import ErrorDetails

from xabsl_studio.server.protocol.limits import (
    DEFAULT_RATE,
    MAX_RATE,
    MAX_SPEED,
    MAX_STEP_TICKS,
    MIN_RATE,
    MIN_SPEED,
)

if TYPE_CHECKING:
    pass
from xabsl_studio.server.protocol.replies import RestReply
from xabsl_studio.server.protocol.types import (
    INTEGRAL,
    MAX_INT,
    STRICT,
    CommandId,
    CommandValue,
    Ms,
    ProtocolError,
    Ref,
    RobotId,
)


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Subscribe:
    """Frames wanted: ``rate`` per second, values of ``robots`` only (``None``: all)."""

    type: Literal["subscribe"]
    rate: Annotated[float, Field(ge=MIN_RATE, le=MAX_RATE)] = DEFAULT_RATE
    robots: tuple[RobotId, ...] | None = None
    #: answered with an ok reply when given
    id: CommandId | None = None


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Resync:
    """Ask for a ``hello`` and a full frame (a frame's ``gen`` did not match the last hello)."""

    type: Literal["resync"]


# Every command has ``type`` (optional over REST), ``op`` and the client's ``id``; its arguments
# follow. ``op`` names the command; the classes are named after it.


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Pause:
    """Stop the simulation clock."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["pause"]


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Resume:
    """Restart the simulation clock."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["resume"]


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Step:
    """While paused: run ``ticks`` ticks."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["step"]
    ticks: Annotated[int, Field(ge=1, le=MAX_STEP_TICKS), INTEGRAL] = 1


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Speed:
    """Run at real time x ``speed``."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["speed"]
    speed: Annotated[float, Field(ge=MIN_SPEED, le=MAX_SPEED)]


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Reset:
    """Rebuild the world and the engines (``seed``: default the current one); restarts a crashed simulation."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["reset"]
    seed: Annotated[int, Field(ge=0, le=2**32 - 1), INTEGRAL] | None = None


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class SelectAgent:
    """The engine of ``robot`` runs the XABSL agent ``agent`` (a name of the program's ``agents``)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["select_agent"]
    robot: RobotId
    agent: str


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class ForceOption:
    """Replace the root of ``robot``'s engine by ``option`` with ``params`` (by name or short name)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["force_option"]
    robot: RobotId
    option: Ref
    params: dict[str, CommandValue] = field(default_factory=dict)


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class ForceBehavior:
    """Replace the root of ``robot``'s engine by the basic behavior ``behavior`` with ``params``."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["force_behavior"]
    robot: RobotId
    behavior: Ref
    params: dict[str, CommandValue] = field(default_factory=dict)


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Release:
    """Back to the normal root of ``robot``'s engine."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["release"]
    robot: RobotId


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class OverrideInput:
    """The input symbol ``symbol`` of ``robot``'s engine reads ``value``."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["override_input"]
    robot: RobotId
    symbol: Ref
    value: CommandValue


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class ReleaseInput:
    """``symbol`` (``None``: every overridden input of ``robot``) reads the host value again."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["release_input"]
    robot: RobotId
    symbol: Ref | None = None


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class ResetAgent:
    """Restart every option of ``robot``'s XABSL agent and clear a fault."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["reset_agent"]
    robot: RobotId


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Reload:
    """Recompile ``program`` (``None``: every behavior set) from disk and hot-swap it when clean."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["reload"]
    program: str | None = None


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Explain:
    """Why ``option`` of ``robot``'s engine took its leaf in the last tick or at tick ``seq`` (:class:`Explanation`).

    With ``why_not``, the answer also says why that decision did not go to state ``why_not``,
    from the same values (:class:`~xabsl_studio.server.protocol.replies.WhyNot`).
    """

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["explain"]
    robot: RobotId
    option: Ref
    #: the tick (a ring buffer seq) to explain from recorded values; null: the live engine now
    seq: Annotated[int, Field(ge=0, le=2**62), INTEGRAL] | None = None
    #: also say why the decision did not go to this state of the option (id or name): ``why_not``
    why_not: Ref | None = None


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Seek:
    """A replay: make tick ``seq`` of the recording the current one (a live session refuses it)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["seek"]
    seq: Annotated[int, Field(ge=0, le=2**62), INTEGRAL]


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class History:
    """Stream the ring buffer between behavior times ``t0`` and ``t1`` (every ``every``-th frame)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["history"]
    t0: Ms = 0
    t1: Ms = 2**62
    every: Annotated[int, Field(ge=1, le=2**31), INTEGRAL] = 1


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Status:
    """The session status (as ``GET /api/status``)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["status"]


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class WorldCommand:
    """A command of the world itself (``engine.host.CommandableWorld``); without ``name``, the list of them."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["world_command"]
    name: str | None = None
    args: dict[str, Any] = field(default_factory=dict)


@with_config(STRICT)
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
    seq: Annotated[int, Field(ge=0, le=2**62), INTEGRAL]


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class AttachHost:
    """Attach one more host to an attached session (``xabsl attach``, docs/attach.md): Connect… in the studio.

    ``address`` is ``HOST:PORT`` (``[::1]:7410`` for IPv6), ``token`` what that host requires
    (None: the session's ``--token``). The reply's result is the host as ``attached[]`` in the
    status shows it, once it answered (or refused) or a few seconds passed.
    """

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["attach_host"]
    address: Annotated[str, Field(min_length=3, max_length=300, pattern=r"^[^\s/]+:[0-9]{1,5}$")]
    token: Annotated[str, Field(min_length=1, max_length=200)] | None = None


#: A breakpoint kind (``xabsl_studio.engine.runtime.breakpoints``).
BreakpointKindName = Literal["enter_option", "leave_option", "enter_state", "leave_state", "leaf", "condition"]
#: A breakpoint's id within its behavior set.
BreakpointId = Annotated[int, Field(ge=1, le=2**31), INTEGRAL]


@with_config(STRICT)
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
    leaf: Annotated[int, Field(ge=0, le=2**31), INTEGRAL] | None = None
    condition: Annotated[str, Field(max_length=2000)] | None = None
    robot: RobotId | None = None
    enabled: bool = True


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class RemoveBreakpoint:
    """Remove breakpoint ``breakpoint`` of behavior set ``program`` (default: the first)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["remove_breakpoint"]
    program: str | None = None
    breakpoint: BreakpointId


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class EnableBreakpoint:
    """Enable or disable breakpoint ``breakpoint`` of behavior set ``program`` (default: the first)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["enable_breakpoint"]
    program: str | None = None
    breakpoint: BreakpointId
    enabled: bool


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class ListBreakpoints:
    """The breakpoints of every behavior set (or of ``program``)."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["list_breakpoints"]
    program: str | None = None


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class CheckCondition:
    """Check ``condition`` against behavior set ``program``'s symbols (default: the first): diagnostics."""

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["check_condition"]
    program: str | None = None
    condition: Annotated[str, Field(max_length=2000)]


@with_config(STRICT)
@dataclass(frozen=True, slots=True, kw_only=True)
class Query:
    """The intervals of ticks in which ``condition`` holds (docs/queries.md), for ``robot`` or every robot.

    A replay answers over its recording, a live or attached session over its history (the ring).
    """

    type: Literal["command"] = "command"
    id: CommandId | None = None
    op: Literal["query"]
    condition: Annotated[str, Field(max_length=2000)]
    robot: RobotId | None = None


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
    | Fork
    | Query
    | AttachHost,
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
