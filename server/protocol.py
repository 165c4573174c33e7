"""The studio's websocket protocol, version 1: message types, close codes, limits (docs/protocol.md).

The names here are the ones the web UI mirrors in ``web/src/protocol.ts``; changing a message's
shape means bumping :data:`VERSION`. Outgoing messages are built as bytes elsewhere (``frames``,
``clients``) for speed; this module owns their vocabulary and the parsing of what clients send,
so that a bad message becomes a :class:`ProtocolError` (answered with an error reply) and never
an exception that would end the connection.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Any

import orjson

from engine.errors import ServerError

#: The schema version sent in ``hello``; a client that does not know it must not go on.
VERSION = 1

#: Largest client message in bytes (uvicorn's ``ws_max_size`` and our own check, close 1009).
MAX_MESSAGE_BYTES = 64 * 1024
#: Largest REST request body in bytes (413 above).
MAX_BODY_BYTES = 1024 * 1024
#: Most websocket clients at once (close 1013 above).
MAX_CLIENTS = 64
#: Control messages (replies, events, history chunks) waiting for one client; a client that sends
#: commands without reading the replies is closed with 1008 when it reaches this.
MAX_PENDING_CONTROL = 256

#: Frames per second a client may ask for.
MIN_RATE, MAX_RATE, DEFAULT_RATE = 1.0, 60.0, 30.0
#: Simulation speed factors the session accepts.
MIN_SPEED, MAX_SPEED = 0.1, 20.0
#: At least one full frame per this many ticks in every client's stream (see ``frame.full``).
FULL_EVERY = 200
#: Frames per ``history`` message.
HISTORY_CHUNK = 200
#: Most ticks one ``step`` command runs.
MAX_STEP_TICKS = 400


class CloseCode(enum.IntEnum):
    """Websocket close codes the server uses (RFC 6455 section 7.4.1)."""

    NORMAL = 1000
    GOING_AWAY = 1001
    UNSUPPORTED_DATA = 1003
    POLICY_VIOLATION = 1008
    MESSAGE_TOO_BIG = 1009
    INTERNAL_ERROR = 1011
    TRY_AGAIN_LATER = 1013


class ServerMessage(enum.StrEnum):
    """``type`` of the messages the server sends."""

    HELLO = "hello"
    FRAME = "frame"
    REPLY = "reply"
    HISTORY = "history"
    EVENT = "event"


class ClientMessage(enum.StrEnum):
    """``type`` of the messages a client sends."""

    SUBSCRIBE = "subscribe"
    COMMAND = "command"
    RESYNC = "resync"


class Op(enum.StrEnum):
    """The ``op`` of a ``command`` (also ``POST /api/command``)."""

    PAUSE = "pause"
    RESUME = "resume"
    STEP = "step"
    SPEED = "speed"
    RESET = "reset"
    SELECT_AGENT = "select_agent"
    FORCE_OPTION = "force_option"
    FORCE_BEHAVIOR = "force_behavior"
    RELEASE = "release"
    OVERRIDE_INPUT = "override_input"
    RELEASE_INPUT = "release_input"
    RESET_AGENT = "reset_agent"
    RELOAD = "reload"
    EXPLAIN = "explain"
    HISTORY = "history"
    STATUS = "status"


class HelloReason(enum.StrEnum):
    """Why a ``hello`` was sent."""

    CONNECT = "connect"
    RELOAD = "reload"
    RESET = "reset"
    RESYNC = "resync"


#: Node kinds in a frame's ``path``.
OPTION_NODE, BEHAVIOR_NODE = 0, 1


class ProtocolError(ServerError, ValueError):
    """A client message that cannot be carried out; its text goes into the error reply."""


@dataclass(frozen=True, slots=True)
class Subscribe:
    rate: float
    agents: frozenset[int] | None


@dataclass(frozen=True, slots=True)
class Command:
    id: Any
    op: Op
    args: dict[str, Any]


@dataclass(frozen=True, slots=True)
class Resync:
    pass


Incoming = Subscribe | Command | Resync


def parse_message(data: str | bytes) -> Incoming:
    """Read one client message.

    Raises:
        ProtocolError: bad JSON, not an object, unknown ``type`` or ``op``, bad ``rate``/``agents``.
    """
    try:
        message = orjson.loads(data)
    except orjson.JSONDecodeError as error:
        raise ProtocolError(f"bad JSON: {error}") from None
    if not isinstance(message, dict):
        raise ProtocolError("a message must be a JSON object")
    kind = message.get("type")
    if kind == ClientMessage.COMMAND:
        return parse_command(message)
    if kind == ClientMessage.SUBSCRIBE:
        return parse_subscribe(message)
    if kind == ClientMessage.RESYNC:
        return Resync()
    raise ProtocolError(f"unknown message type {kind!r} (expected one of: {', '.join(ClientMessage)})")


def parse_command(message: dict[str, Any]) -> Command:
    """A ``command`` object (with or without ``type``) -> :class:`Command`."""
    command_id = message.get("id")
    if not isinstance(command_id, int | str | float | type(None)) or isinstance(command_id, bool):
        raise ProtocolError("command id must be a number or a string")
    op = message.get("op")
    try:
        parsed = Op(op)
    except ValueError:
        raise ProtocolError(f"unknown op {op!r} (expected one of: {', '.join(Op)})") from None
    args = {k: v for k, v in message.items() if k not in ("type", "id", "op")}
    return Command(command_id, parsed, args)


def parse_subscribe(message: dict[str, Any]) -> Subscribe:
    rate = message.get("rate", DEFAULT_RATE)
    if isinstance(rate, bool) or not isinstance(rate, int | float) or not MIN_RATE <= rate <= MAX_RATE:
        raise ProtocolError(f"rate must be a number of frames per second in {MIN_RATE:g}..{MAX_RATE:g}")
    agents = message.get("agents")
    if agents is not None and (
        not isinstance(agents, list) or not all(isinstance(a, int) and not isinstance(a, bool) for a in agents)
    ):
        raise ProtocolError("agents must be a list of agent ids or null")
    return Subscribe(float(rate), frozenset(agents) if agents is not None else None)


def reply(command_id: Any, ok: bool, result: Any = None, error: str | None = None) -> bytes:
    """A ``reply`` message as JSON bytes."""
    message: dict[str, Any] = {"type": ServerMessage.REPLY.value, "id": command_id, "ok": ok}
    if result is not None:
        message["result"] = result
    if error is not None:
        message["error"] = error
    return orjson.dumps(message, option=orjson.OPT_NON_STR_KEYS)


def event(name: str, **fields: Any) -> bytes:
    """An ``event`` message as JSON bytes."""
    return orjson.dumps({"type": ServerMessage.EVENT.value, "event": name, **fields})
