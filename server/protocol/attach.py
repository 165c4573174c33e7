"""The studio <-> host protocol over a socket (attach, docs/attach.md): framing, JSON codec, limits.

The messages are those of ``xabsl_studio.server.protocol.host`` (``Sample``, ``NewGeneration``,
``WorkerRequest``, ``WorkerReply``, ``Hit``) plus the handshake, control and heartbeat messages
below. On the wire:

* TCP; each message is a 4-byte big-endian length, then that many bytes of one UTF-8 JSON object
  with a ``type``. Nothing is ever unpickled: both ends decode JSON and check every field
  (:func:`decode_from_studio`, :func:`decode_from_host`), and a frame over the limit of its
  direction (:data:`MAX_STUDIO_MESSAGE`, :data:`MAX_HOST_MESSAGE`) closes the connection;
* the studio speaks first: ``attach`` with the protocol version, the token and whether it wants
  control; the host answers ``welcome`` (its name, robots, capabilities, who holds control) or
  ``refused`` and closes; then the current ``generation`` and ``sample``, then every tick;
* both ends send something at least every :data:`HEARTBEAT_SECONDS`; an end that hears nothing
  for :data:`HEARTBEAT_TIMEOUT` closes the connection (the host then releases what that studio
  forced and overrode, and resumes if it had paused it).

Commands travel as the websocket's command objects (``op`` and arguments, validated on the host
by ``xabsl_studio.server.protocol.commands.parse_command``) or as the internal ops named in
:data:`INTERNAL_OPS`; a hot reload carries intermediate code (``load_ic``), never a program object.
"""

from __future__ import annotations

import dataclasses
import struct
from dataclasses import dataclass
from typing import Any, get_args

import orjson

from xabsl_studio.engine.runtime.breakpoints import Breakpoint
from xabsl_studio.server.protocol.commands import parse_command
from xabsl_studio.server.protocol.errors import ServerError
from xabsl_studio.server.protocol.host import (
    ExplainRecorded,
    Hit,
    LoadIntermediateCode,
    NewGeneration,
    ReleaseOwner,
    Sample,
    SetBreakpoints,
    WorkerCommand,
    WorkerReply,
    WorkerRequest,
)
from xabsl_studio.server.protocol.types import HelloReason, ProtocolError, WireValue

#: The attach protocol's version, named in ``attach`` and ``welcome``; both ends refuse another.
#: 2: hosts send raw symbol values (``raw_values`` in ``generation``), the studio converts them.
PROTOCOL = 2
#: The port a host listens on unless told otherwise.
DEFAULT_PORT = 7410
#: Largest message a studio may send (a hot reload's intermediate code is the big one).
MAX_STUDIO_MESSAGE = 8 * 1024 * 1024
#: Largest message a host may send (a generation carries every program's description and code).
MAX_HOST_MESSAGE = 64 * 1024 * 1024
#: Studios attached to one host at once (more are refused).
MAX_PEERS = 8
#: Seconds between heartbeats of an end that has nothing else to say.
HEARTBEAT_SECONDS = 1.0
#: Seconds of silence after which the other end counts as gone (its control is released).
HEARTBEAT_TIMEOUT = 3.0
#: Seconds a new connection has to send its ``attach``.
HANDSHAKE_TIMEOUT = 5.0
#: Bytes waiting for one studio before the host drops ticks for it (it never blocks on a studio).
MAX_BACKLOG = 32 * 1024 * 1024
#: Commands of one studio waiting to be carried out (more close the connection).
MAX_QUEUED_REQUESTS = 256
#: The longest studio name or token accepted in ``attach``.
MAX_NAME = 200

_HEADER = struct.Struct(">I")

#: Ops that are not client commands: what the studio's session sends on behalf of the studio.
INTERNAL_OPS = frozenset({"load_ic", "set_breakpoints", "explain_recorded", "release_owner"})


class WireError(ServerError, ValueError):
    """A message that breaks the attach protocol (too big, not JSON, a field of the wrong type)."""


@dataclass(frozen=True, slots=True)
class Attach:
    """Studio -> host, first: who attaches and whether it wants control."""

    token: str | None
    studio: str
    control: bool
    protocol: int = PROTOCOL


@dataclass(frozen=True, slots=True)
class Welcome:
    """Host -> studio: accepted; the host's name, robots and what it allows."""

    host: str
    robots: tuple[str, ...]
    capabilities: dict[str, bool]
    #: this connection's name on the host (owners it sets are ``peer/owner``)
    peer: str
    #: the studio that holds control (its ``studio`` name and peer), None: nobody
    control: dict[str, str] | None
    protocol: int = PROTOCOL


@dataclass(frozen=True, slots=True)
class Refused:
    """Host -> studio: not accepted (the connection closes after it)."""

    reason: str


@dataclass(frozen=True, slots=True)
class Control:
    """Studio -> host: take (or give up) control; host -> studio: who holds it now."""

    take: bool = True
    holder: dict[str, str] | None = None


@dataclass(frozen=True, slots=True)
class Heartbeat:
    """Either way: still here (sent when there was nothing else to say)."""


@dataclass(frozen=True, slots=True)
class HostGeneration:
    """Host -> studio: a new generation, with each running program's intermediate code."""

    generation: NewGeneration
    #: per behavior key: the IC of the program its engines run (the studio reads it back for
    #: graphs, breakpoints and recordings)
    ics: dict[str, str]
    #: per behavior key: its source files as the host read them (``xabsl_studio.engine.record.sources``:
    #: ``{"agents": NAME, "files": {NAME: TEXT}}``), for recordings a fork can run again; absent
    #: when the host cannot read them (a program loaded from intermediate code)
    sources: dict[str, dict[str, Any]] = dataclasses.field(default_factory=dict)


FromStudio = Attach | WorkerRequest | Control | Heartbeat
FromHost = Welcome | Refused | HostGeneration | Sample | WorkerReply | Hit | Control | Heartbeat


# -- framing -------------------------------------------------------------------------------------------


def frame(payload: bytes) -> bytes:
    """One message on the wire: its length, then its bytes."""
    return _HEADER.pack(len(payload)) + payload


class FrameReader:
    """Cuts a byte stream into messages; refuses one larger than ``limit`` before reading it."""

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self._buffer = bytearray()

    def feed(self, data: bytes) -> list[bytes]:
        """The complete messages among the bytes so far (a partial one is kept).

        Raises:
            WireError: a message over the limit.
        """
        buffer = self._buffer
        buffer += data
        messages: list[bytes] = []
        start = 0
        while len(buffer) - start >= _HEADER.size:
            (size,) = _HEADER.unpack_from(buffer, start)
            if size > self.limit:
                raise WireError(f"a message of {size} bytes (at most {self.limit})")
            end = start + _HEADER.size + size
            if end > len(buffer):
                break
            messages.append(bytes(buffer[start + _HEADER.size : end]))
            start = end
        if start:
            del buffer[:start]
        return messages


# -- the host's side ------------------------------------------------------------------------------------


def encode_sample(sample: Sample) -> bytes:
    """A tick as one framed message (the paths, scene and status are JSON already: spliced in)."""
    fragment = orjson.Fragment
    reads = sample.reads or (b"",) * len(sample.paths)
    robots = [
        [
            fragment(path),
            fragment(b"{" + extra[1:] + b"}") if extra else None,
            inputs,
            outputs,
            fragment(read) if read else None,
        ]
        for path, extra, inputs, outputs, read in zip(
            sample.paths, sample.extras, sample.inputs, sample.outputs, reads, strict=True
        )
    ]
    return frame(
        orjson.dumps(
            {
                "type": "sample",
                "seq": sample.seq,
                "gen": sample.gen,
                "t": sample.t,
                "wall": sample.wall,
                "paused": sample.paused,
                "speed": sample.speed,
                "robots": robots,
                "scene": fragment(sample.scene),
                "status": fragment(sample.status),
            },
            # raw symbol values as the host's getters gave them: numpy scalars as numbers, a value
            # JSON cannot hold (NaN, infinities, another type) as null, unknown
            default=_null,
            option=orjson.OPT_SERIALIZE_NUMPY,
        )
    )


def _null(value: Any) -> None:
    return None


def encode_generation(message: HostGeneration) -> bytes:
    """A generation as one framed message."""
    gen = message.generation
    return frame(
        orjson.dumps(
            {
                "type": "generation",
                "number": gen.number,
                "reason": gen.reason,
                "structure": orjson.Fragment(gen.structure),
                "scene": orjson.Fragment(gen.scene),
                "input_ids": gen.input_ids,
                "output_ids": gen.output_ids,
                "seed": gen.seed,
                "errors": gen.errors,
                "ics": message.ics,
                "enums": gen.enums,
                "raw_values": gen.raw_values,
                "sources": message.sources,
            },
            option=orjson.OPT_NON_STR_KEYS,  # enum host values are integers
        )
    )


def encode_from_host(message: Welcome | Refused | WorkerReply | Hit | Control | Heartbeat) -> bytes:
    """Any other host message as one framed message."""
    if isinstance(message, Welcome):
        body: dict[str, Any] = {"type": "welcome", **dataclasses.asdict(message)}
    elif isinstance(message, Refused):
        body = {"type": "refused", "reason": message.reason}
    elif isinstance(message, WorkerReply):
        body = {"type": "reply", **dataclasses.asdict(message)}
    elif isinstance(message, Hit):
        body = {"type": "hit", **dataclasses.asdict(message)}
    elif isinstance(message, Control):
        body = {"type": "control", "holder": message.holder}
    else:
        body = {"type": "heartbeat"}
    return frame(orjson.dumps(body, default=_json_default))


def _json_default(value: Any) -> Any:
    if isinstance(value, tuple | frozenset | set):
        return list(value)
    raise TypeError(f"{type(value).__name__} is not JSON")


def decode_from_studio(data: bytes) -> FromStudio:
    """A studio's message, checked field by field.

    Raises:
        WireError: not JSON, an unknown type, a missing or ill-typed field, a command that does
            not validate (its message says what is wrong).
    """
    message = _object(data)
    kind = message.get("type")
    if kind == "heartbeat":
        return Heartbeat()
    if kind == "attach":
        token = message.get("token")
        if token is not None and not isinstance(token, str):
            raise WireError("attach: token must be a string or null")
        studio = message.get("studio", "studio")
        if not isinstance(studio, str) or not 0 < len(studio) <= MAX_NAME:
            raise WireError(f"attach: studio must be a name of 1..{MAX_NAME} characters")
        if token is not None and len(token) > MAX_NAME:
            raise WireError("attach: the token is too long")
        return Attach(token, studio, _bool(message, "control", False), _int(message, "protocol"))
    if kind == "control":
        return Control(take=_bool(message, "take", True))
    if kind == "request":
        ident = message.get("id")
        if ident is not None and (isinstance(ident, bool) or not isinstance(ident, int)):
            raise WireError("request: id must be an integer or null")
        owner = message.get("owner")
        if owner is not None and (not isinstance(owner, str) or len(owner) > MAX_NAME):
            raise WireError("request: owner must be a short string or null")
        body = message.get("command")
        if not isinstance(body, dict):
            raise WireError("request: command must be an object")
        return WorkerRequest(ident, _command(body), owner)
    raise WireError(f"unknown message type {kind!r}")


def _command(body: dict[str, Any]) -> WorkerCommand:
    op = body.get("op")
    if op == "load_ic":
        return LoadIntermediateCode(_str(body, "key"), _str(body, "ic"))
    if op == "set_breakpoints":
        points = body.get("points")
        if not isinstance(points, list):
            raise WireError("set_breakpoints: points must be a list")
        return SetBreakpoints(_str(body, "key"), tuple(_breakpoint(p) for p in points))
    if op == "explain_recorded":
        ticks = body.get("ticks")
        if not isinstance(ticks, list) or not all(isinstance(t, list) and len(t) == 10 for t in ticks):
            raise WireError("explain_recorded: ticks must be a list of 10-item lists")
        why_not = body.get("why_not")
        if why_not is not None and (isinstance(why_not, bool) or not isinstance(why_not, int | str)):
            raise WireError("explain_recorded: why_not must be a state id, a name or null")
        return ExplainRecorded(
            _int(body, "robot"),
            _str(body, "option"),
            _int(body, "generation"),
            tuple(tuple(t) for t in ticks),
            why_not=why_not,
        )
    if op == "release_owner":
        return ReleaseOwner()
    try:
        command = parse_command(orjson.dumps(body))
    except ProtocolError as error:
        raise WireError(str(error)) from None
    return command  # type: ignore[return-value]  # the host refuses the ops it does not carry out


_BREAKPOINT_FIELDS = {f.name for f in dataclasses.fields(Breakpoint)}


def _breakpoint(value: Any) -> Breakpoint:
    if not isinstance(value, dict) or set(value) - _BREAKPOINT_FIELDS:
        raise WireError("set_breakpoints: a breakpoint must be an object of breakpoint fields")
    try:
        point = Breakpoint(**value)
    except TypeError as error:
        raise WireError(f"set_breakpoints: {error}") from None
    if not _is_int(point.id) or not isinstance(point.kind, str) or not isinstance(point.option, str | None):
        raise WireError("set_breakpoints: id must be an integer, kind a string, option a string or null")
    return point


# -- the studio's side -----------------------------------------------------------------------------------


def encode_attach(message: Attach) -> bytes:
    """The studio's first message."""
    return frame(orjson.dumps({"type": "attach", **dataclasses.asdict(message)}))


def encode_from_studio(message: WorkerRequest | Control | Heartbeat) -> bytes:
    """A request (its command as the websocket's command object), control or a heartbeat."""
    if isinstance(message, Heartbeat):
        return frame(b'{"type":"heartbeat"}')
    if isinstance(message, Control):
        return frame(orjson.dumps({"type": "control", "take": message.take}))
    command = dataclasses.asdict(message.body)
    command.pop("type", None)
    command.pop("id", None)
    if isinstance(message.body, LoadIntermediateCode | SetBreakpoints | ExplainRecorded | ReleaseOwner):
        command["op"] = message.body.op
    return frame(
        orjson.dumps(
            {"type": "request", "id": message.ident, "owner": message.owner, "command": command},
            default=_json_default,
        )
    )


_REASONS = frozenset(get_args(HelloReason))


def decode_from_host(data: bytes) -> FromHost:
    """A host's message, checked field by field (a host is a network peer too).

    Raises:
        WireError: not JSON, an unknown type, a missing or ill-typed field.
    """
    message = _object(data)
    kind = message.get("type")
    if kind == "sample":
        return _sample(message)
    if kind == "heartbeat":
        return Heartbeat()
    if kind == "reply":
        ident = message.get("ident")
        if ident is not None and (isinstance(ident, bool) or not isinstance(ident, int)):
            raise WireError("reply: ident must be an integer or null")
        error = message.get("error")
        if error is not None and not isinstance(error, str):
            raise WireError("reply: error must be a string or null")
        return WorkerReply(ident, _bool(message, "ok", False), message.get("result"), error)
    if kind == "generation":
        return _generation(message)
    if kind == "hit":
        return Hit(
            _str(message, "key"),
            _int(message, "breakpoint"),
            _int(message, "robot"),
            _int(message, "seq"),
            _int(message, "t"),
            _str(message, "description"),
        )
    if kind == "control":
        return Control(holder=_holder(message.get("holder")))
    if kind == "welcome":
        robots = message.get("robots")
        if not isinstance(robots, list) or not all(isinstance(r, str) for r in robots):
            raise WireError("welcome: robots must be a list of names")
        capabilities = message.get("capabilities")
        if not isinstance(capabilities, dict) or not all(isinstance(v, bool) for v in capabilities.values()):
            raise WireError("welcome: capabilities must map names to booleans")
        return Welcome(
            _str(message, "host"),
            tuple(robots),
            capabilities,
            _str(message, "peer"),
            _holder(message.get("control")),
            _int(message, "protocol"),
        )
    if kind == "refused":
        return Refused(_str(message, "reason"))
    raise WireError(f"unknown message type {kind!r}")


def _holder(value: Any) -> dict[str, str] | None:
    if value is None:
        return None
    if not isinstance(value, dict) or not all(isinstance(v, str) for v in value.values()):
        raise WireError("control: the holder must be an object of strings or null")
    return {str(k): v for k, v in value.items()}


def _sample(message: dict[str, Any]) -> Sample:
    robots = message.get("robots")
    if not isinstance(robots, list):
        raise WireError("sample: robots must be a list")
    dumps = orjson.dumps
    paths: list[bytes] = []
    extras: list[bytes] = []
    inputs: list[tuple[WireValue, ...]] = []
    outputs: list[tuple[WireValue, ...]] = []
    reads: list[bytes] = []
    for robot in robots:
        if not isinstance(robot, list) or len(robot) not in (4, 5):
            raise WireError("sample: a robot must be [path, extras, inputs, outputs, reads]")
        path, extra, ins, outs = robot[:4]
        reads.append(_reads(robot[4]) if len(robot) == 5 else b"")
        if not isinstance(path, list):
            raise WireError("sample: a path must be a list")
        paths.append(dumps(path))
        if extra is None:
            extras.append(b"")
        elif isinstance(extra, dict) and set(extra) <= {"fault", "forced", "overrides"}:
            extras.append(b"," + dumps(extra)[1:-1] if extra else b"")
        else:
            raise WireError("sample: extras must be null or an object of fault, forced, overrides")
        inputs.append(_values(ins))
        outputs.append(_values(outs))
    scene, status = message.get("scene"), message.get("status")
    if not isinstance(scene, dict) or not isinstance(status, dict):
        raise WireError("sample: scene and status must be objects")
    return Sample(
        _int(message, "seq"),
        _int(message, "gen"),
        _int(message, "t"),
        _number(message, "wall"),
        _bool(message, "paused", False),
        _number(message, "speed"),
        tuple(paths),
        tuple(extras),
        tuple(inputs),
        tuple(outputs),
        dumps(scene),
        dumps(status),
        tuple(reads),
    )


def _reads(value: Any) -> bytes:
    """A robot's reads (``Engine.reads()``: option ids, each followed by its decision's read tuples), or b''."""
    if value is None:
        return b""
    if not isinstance(value, list):
        raise WireError("sample: reads must be a list or null")
    for item in value:
        if isinstance(item, list):
            if not all(v is None or isinstance(v, bool | int | float | str) for v in item):
                raise WireError("sample: a read must be a list of numbers, booleans, strings or null")
        elif not _is_int(item):
            raise WireError("sample: reads must hold option ids and read lists")
    return orjson.dumps(value)


def _values(values: Any) -> tuple[WireValue, ...]:
    if not isinstance(values, list) or not all(v is None or isinstance(v, bool | int | float) for v in values):
        raise WireError("sample: symbol values must be a list of numbers, booleans or null")
    return tuple(values)


def _generation(message: dict[str, Any]) -> HostGeneration:
    structure = message.get("structure")
    if (
        not isinstance(structure, dict)
        or not isinstance(structure.get("programs"), dict)
        or not isinstance(structure.get("robots"), list)
    ):
        raise WireError("generation: structure must hold programs and robots")
    for robot in structure["robots"]:
        if not isinstance(robot, dict) or not isinstance(robot.get("name"), str):
            raise WireError("generation: every robot needs a name")
        program = robot.get("program")
        if program is not None and program not in structure["programs"]:
            raise WireError(f"generation: robot {robot['name']} runs an undescribed program")
    scene = message.get("scene")
    if not isinstance(scene, dict):
        raise WireError("generation: scene must be an object")
    reason: HelloReason = message.get("reason")  # type: ignore[assignment]  # checked here
    if reason not in _REASONS:
        raise WireError(f"generation: unknown reason {reason!r}")
    ids = [message.get("input_ids"), message.get("output_ids")]
    for table in ids:
        if not isinstance(table, list) or len(table) != len(structure["robots"]):
            raise WireError("generation: symbol ids must be one list per robot")
        if not all(isinstance(row, list) and all(_is_int(i) for i in row) for row in table):
            raise WireError("generation: symbol ids must be integers")
    errors = message.get("errors", {})
    if not isinstance(errors, dict) or not all(e is None or isinstance(e, str) for e in errors.values()):
        raise WireError("generation: errors must map keys to strings or null")
    ics = message.get("ics", {})
    if not isinstance(ics, dict) or not all(isinstance(v, str) for v in ics.values()):
        raise WireError("generation: ics must map keys to intermediate code")
    generation = NewGeneration(
        _int(message, "number"),
        reason,
        orjson.dumps(structure),
        orjson.dumps(scene),
        tuple(tuple(row) for row in ids[0]),  # type: ignore[union-attr]
        tuple(tuple(row) for row in ids[1]),  # type: ignore[union-attr]
        _int(message, "seed"),
        errors,
        enums=_enums(message.get("enums", {})),
        raw_values=_bool(message, "raw_values", False),
    )
    return HostGeneration(generation, ics, _sources(message.get("sources", {})))


def _sources(value: Any) -> dict[str, dict[str, Any]]:
    """Per behavior set: ``{"agents": NAME, "files": {NAME: TEXT}}`` (the agents file among the files)."""
    if not isinstance(value, dict):
        raise WireError("generation: sources must be an object")
    for key, sources in value.items():
        files = sources.get("files") if isinstance(sources, dict) else None
        if (
            not isinstance(files, dict)
            or not all(isinstance(n, str) and isinstance(t, str) for n, t in files.items())
            or sources.get("agents") not in files
        ):
            raise WireError(f"generation: sources of {key} must be an agents file name and files of texts")
    return value


def _enums(value: Any) -> dict[str, dict[str, dict[int, str]]]:
    """Per behavior set: enum name -> host value -> qualified element (what the raw enum values of reads mean)."""
    if not isinstance(value, dict):
        raise WireError("generation: enums must be an object")
    enums: dict[str, dict[str, dict[int, str]]] = {}
    for key, tables in value.items():
        if not isinstance(tables, dict):
            raise WireError("generation: enums must map behavior sets to enum tables")
        enums[key] = {}
        for name, table in tables.items():
            if not isinstance(table, dict) or not all(isinstance(e, str) for e in table.values()):
                raise WireError("generation: an enum table must map host values to element names")
            try:
                enums[key][name] = {int(v): e for v, e in table.items()}
            except ValueError:
                raise WireError("generation: an enum's host values must be integers") from None
    return enums


# -- fields ---------------------------------------------------------------------------------------------


def _object(data: bytes) -> dict[str, Any]:
    try:
        message = orjson.loads(data)
    except orjson.JSONDecodeError as error:
        raise WireError(f"not JSON: {error}") from None
    if not isinstance(message, dict):
        raise WireError("a message must be a JSON object")
    return message


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and -(2**63) <= value < 2**63


def _int(message: dict[str, Any], name: str) -> int:
    value = message.get(name)
    if not _is_int(value):
        raise WireError(f"{message.get('type', 'message')}: {name} must be an integer")
    return int(value)  # type: ignore[arg-type]  # an int, checked above


def _number(message: dict[str, Any], name: str) -> float:
    value = message.get(name)
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise WireError(f"{message.get('type', 'message')}: {name} must be a number")
    return float(value)


def _bool(message: dict[str, Any], name: str, default: bool) -> bool:
    value = message.get(name, default)
    if not isinstance(value, bool):
        raise WireError(f"{message.get('type', 'message')}: {name} must be true or false")
    return value


def _str(message: dict[str, Any], name: str) -> str:
    value = message.get(name)
    if not isinstance(value, str):
        raise WireError(f"{message.get('type', message.get('op', 'message'))}: {name} must be a string")
    return value
