"""The Foxglove WebSocket protocol on the studio's port: ``/foxglove`` (docs/foxglove.md).

Foxglove and Lichtblick connect to a live source over this protocol (the ``ws-protocol`` spec,
v1; the Foxglove SDK's servers speak the same messages under the subprotocol name
``foxglove.sdk.v1``). The handshake accepts either name and answers with the one the client
offered (the new name first when it offers both); a client that offers neither is refused with
HTTP 400. The studio's token, Origin and Host checks apply before this module runs
(``xabsl_studio.server.api.security``, as for ``/ws``).

What this module owns, per connection (:class:`FoxgloveClient`) and per studio
(:class:`FoxgloveServer`):

* ``serverInfo`` (capabilities ``time``; ``services`` for a live session; for a replay the data's
  time range, ``dataStartTime``/``dataEndTime``, and the playback capability under both of its
  names, ``rangedPlayback`` (the SDK's) and ``playbackControl``), ``advertise`` of the topics of
  :class:`~xabsl_studio.server.session.feed.TopicFeed` with encoding ``json`` and the recordings'
  JSON Schemas, ``subscribe``/``unsubscribe``, and binary message data frames (opcode 1:
  u32 subscription id, u64 time in ns, payload) for every tick the session records; a ``time``
  frame (opcode 2) after each batch. A new subscriber of a topic that is not sent every tick
  (programs, static scene, field, status, faults) gets its last messages at once;
* **backpressure**: the session never waits for a viewer. Message frames wait in a bounded
  per-client queue (:data:`MAX_QUEUED_FRAMES`, :data:`MAX_QUEUED_BYTES`) that drops its oldest
  frames when a viewer reads too slowly (counted in ``dropped``); every message is complete on
  its own (``key: true``), so a dropped one loses a tick, never corrupts the next. JSON control
  messages (advertise, status) are never dropped; a client that lets :data:`MAX_PENDING_CONTROL`
  of them pile up is closed with 1008. Client messages over :data:`MAX_CLIENT_MESSAGE_BYTES` close
  the connection with 1009; at most :data:`MAX_SUBSCRIPTIONS` subscriptions per client and
  :data:`MAX_FOXGLOVE_CLIENTS` connections per studio (1013 beyond);
* **playback** of a replay: playback control requests (binary opcode 3: play or pause, speed,
  an optional seek time) become the studio's own ``speed``, ``seek``, ``resume`` and ``pause``
  commands, answered by a playback state (binary opcode 5) with the request's id. The studio's
  timeline and Foxglove's stay in step both ways: a seek or pause in the studio's page reaches
  every viewer as a playback state without a request id;
* **services** of a live session: ``/xabsl/force_option``, ``/xabsl/release``,
  ``/xabsl/override_input`` and ``/xabsl/release_input``, JSON requests validated by the same
  parser as the websocket's commands and carried out by ``Studio.run_command``, so the studio's
  checks (robot, option, symbol, parameter ranges) answer a bad call as a service call failure.

Everything here runs on the asyncio loop; the session's ``notify`` only schedules work.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import logging
import math
import os
import struct
import time
from collections import deque
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Any, TypeGuard

import orjson
from fastapi import APIRouter, WebSocket
from fastapi.responses import JSONResponse
from pydantic import TypeAdapter
from starlette.websockets import WebSocketDisconnect

from xabsl_studio.engine.record import Recording
from xabsl_studio.server.protocol.commands import (
    Command,
    ForceOption,
    OverrideInput,
    Pause,
    Release,
    ReleaseInput,
    Resume,
    Seek,
    Speed,
    parse_command,
)
from xabsl_studio.server.protocol.limits import MAX_MESSAGE_BYTES, MAX_SPEED, MIN_SPEED, CloseCode
from xabsl_studio.server.protocol.replies import Reply
from xabsl_studio.server.protocol.types import ProtocolError
from xabsl_studio.server.session.feed import FeedMessage, TopicFeed, schema_of
from xabsl_studio.server.session.frames import Entry
from xabsl_studio.server.session.live import Session
from xabsl_studio.server.session.recording import command_event

__all__ = ["SUBPROTOCOLS", "FoxgloveClient", "FoxgloveServer", "router"]

log = logging.getLogger("xabsl.server")

#: The subprotocol names accepted, preferred first: the SDK's current name, the spec's original.
SUBPROTOCOLS = ("foxglove.sdk.v1", "foxglove.websocket.v1")
#: Viewers one studio serves at once.
MAX_FOXGLOVE_CLIENTS = 16
#: The largest message a viewer may send (subscribe lists, service calls): the ``/ws`` limit.
MAX_CLIENT_MESSAGE_BYTES = MAX_MESSAGE_BYTES
#: Subscriptions one viewer may hold.
MAX_SUBSCRIPTIONS = 4096
#: Message frames waiting for one viewer; beyond, the oldest are dropped.
MAX_QUEUED_FRAMES = 4096
#: Bytes of message frames waiting for one viewer; beyond, the oldest are dropped.
MAX_QUEUED_BYTES = 16 * 1024 * 1024
#: JSON control messages waiting for one viewer; a viewer that lets more pile up is closed (1008).
MAX_PENDING_CONTROL = 256
#: Seconds between two looks at a replay's playback state (a pause or the end of the file
#: produces no tick, so no other path would tell the viewers).
PLAYBACK_POLL_SECONDS = 0.25

# Binary opcodes, server -> client and client -> server (little-endian throughout).
MESSAGE_DATA = 0x01
TIME = 0x02
SERVICE_CALL_RESPONSE = 0x03
PLAYBACK_STATE = 0x05
CLIENT_MESSAGE_DATA = 0x01
SERVICE_CALL_REQUEST = 0x02
PLAYBACK_CONTROL_REQUEST = 0x03
# Playback commands (requests) and states (answers).
PLAY, PAUSE = 0, 1
PLAYING, PAUSED, ENDED = 0, 1, 3
# Status levels.
INFO, WARNING, ERROR = 0, 1, 2

_MESSAGE_HEAD = struct.Struct("<BIQ")
_TIME = struct.Struct("<BQ")
_PLAYBACK_REQUEST = struct.Struct("<BfBQI")
_PLAYBACK_STATE = struct.Struct("<BBQfBI")
_SERVICE_HEAD = struct.Struct("<BIII")

#: Runs a validated command as the studio does (``Studio.run_command``) and returns its reply.
CommandRunner = Callable[[Command], Awaitable[Reply]]


@dataclass(frozen=True, slots=True)
class _Channel:
    id: int
    topic: str
    schema_name: str

    def advertised(self) -> dict[str, Any]:
        return {
            "id": self.id,
            "topic": self.topic,
            "encoding": "json",
            "schemaName": self.schema_name,
            "schema": _schema_text(self.schema_name),
            "schemaEncoding": "jsonschema",
        }


_SCHEMA_TEXTS: dict[str, str] = {}


def _schema_text(name: str) -> str:
    text = _SCHEMA_TEXTS.get(name)
    if text is None:
        text = _SCHEMA_TEXTS[name] = orjson.dumps(schema_of(name)).decode()
    return text


@dataclass(frozen=True, slots=True)
class _Service:
    id: int
    name: str
    op: str
    command: type[Any]
    description: str

    def advertised(self) -> dict[str, Any]:
        request = TypeAdapter(self.command).json_schema()
        properties = {k: v for k, v in request.get("properties", {}).items() if k not in ("type", "id", "op")}
        request = {
            **request,
            "$schema": "https://json-schema.org/draft/2020-12/schema",
            "title": f"xabsl.{self.command.__name__}Request",
            "description": self.description,
            "properties": properties,
            "required": [k for k in request.get("required", []) if k in properties],
            "additionalProperties": False,
        }
        # ``request``/``response`` as the SDK writes them; ``requestSchema``/``responseSchema``
        # (the schema's text) for clients of the spec's first version, which know only those
        return {
            "id": self.id,
            "name": self.name,
            "type": f"xabsl.{self.command.__name__}",
            "request": _schema_block(request),
            "response": _schema_block(_RESPONSE_SCHEMA),
            "requestSchema": orjson.dumps(request).decode(),
            "responseSchema": orjson.dumps(_RESPONSE_SCHEMA).decode(),
        }


_RESPONSE_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "xabsl.CommandResult",
    "description": "the command's result, as the studio's reply carries it",
    "type": "object",
    "required": ["ok", "result"],
    "properties": {"ok": {"const": True}, "result": {}},
}


def _schema_block(schema: dict[str, Any]) -> dict[str, Any]:
    return {
        "encoding": "json",
        "schemaName": str(schema["title"]),
        "schemaEncoding": "jsonschema",
        "schema": orjson.dumps(schema).decode(),
    }


#: The interventions a live session offers as services.
SERVICES = (
    _Service(1, "/xabsl/force_option", "force_option", ForceOption, "force an option (with parameters) as a root"),
    _Service(2, "/xabsl/release", "release", Release, "back to the robot's normal root"),
    _Service(3, "/xabsl/override_input", "override_input", OverrideInput, "an input symbol reads a given value"),
    _Service(4, "/xabsl/release_input", "release_input", ReleaseInput, "an input (or all) reads the host again"),
)
_SERVICES_BY_ID = {s.id: s for s in SERVICES}


def _timestamp(ns: int) -> dict[str, int]:
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


class FoxgloveClient:
    """One viewer's connection: its subscriptions, its bounded queues, its counters."""

    def __init__(self, websocket: WebSocket, ident: int, server: FoxgloveServer) -> None:
        self.websocket = websocket
        self.id = ident
        self.server = server
        #: subscription id -> channel id, and back
        self.subscriptions: dict[int, int] = {}
        self.by_channel: dict[int, int] = {}
        self.control: deque[str] = deque()
        self.frames: deque[bytes] = deque()
        self.queued_bytes = 0
        self.dropped = 0
        self.sent = 0
        self.wake = asyncio.Event()
        self.closing = False
        #: the viewer was sent the channels (until then, new ones are not advertised to it alone)
        self.advertised = False

    # -- queues -----------------------------------------------------------------------------------

    def json(self, message: dict[str, Any]) -> None:
        """Queue a JSON control message (never dropped; too many waiting closes the connection)."""
        if self.closing:
            return
        if len(self.control) >= MAX_PENDING_CONTROL:
            self.server.close_soon(self, CloseCode.POLICY_VIOLATION)
            return
        self.control.append(orjson.dumps(message).decode())
        self.wake.set()

    def binary(self, frame: bytes) -> None:
        """Queue a binary frame; the oldest frames go when the queue is over its bounds."""
        if self.closing:
            return
        frames = self.frames
        frames.append(frame)
        self.queued_bytes += len(frame)
        while len(frames) > MAX_QUEUED_FRAMES or (self.queued_bytes > MAX_QUEUED_BYTES and len(frames) > 1):
            self.queued_bytes -= len(frames.popleft())
            self.dropped += 1
        self.wake.set()

    def message(self, subscription: int, message: FeedMessage) -> None:
        """Queue one message data frame for ``subscription``."""
        self.binary(_MESSAGE_HEAD.pack(MESSAGE_DATA, subscription, message.time_ns) + message.data)

    def status(self, level: int, text: str) -> None:
        """Tell the viewer something (errors in its requests among them)."""
        self.json({"op": "status", "level": level, "message": text})

    # -- tasks --------------------------------------------------------------------------------------

    async def sender(self) -> None:
        """Send control messages first, then frames, until the connection ends."""
        websocket = self.websocket
        while not self.closing:
            await self.wake.wait()
            self.wake.clear()
            while not self.closing and (self.control or self.frames):
                if self.control:
                    await websocket.send_text(self.control.popleft())
                    continue
                frame = self.frames.popleft()
                self.queued_bytes -= len(frame)
                await websocket.send_bytes(frame)
                self.sent += 1

    async def receiver(self) -> None:
        """Read the viewer's messages until it disconnects."""
        websocket = self.websocket
        while True:
            message = await websocket.receive()
            if message["type"] == "websocket.disconnect":
                raise WebSocketDisconnect(message.get("code", CloseCode.NORMAL))
            data = message.get("bytes")
            text = message.get("text")
            size = len(data) if data is not None else len((text or "").encode("utf-8"))
            if size > MAX_CLIENT_MESSAGE_BYTES:
                await self.close(CloseCode.MESSAGE_TOO_BIG)
                return
            if data is not None:
                await self.server.binary_request(self, bytes(data))
            else:
                self.server.json_request(self, text or "")

    async def close(self, code: int) -> None:
        """Close the connection with ``code`` (once)."""
        if self.closing:
            return
        self.closing = True
        self.wake.set()
        with contextlib.suppress(Exception):  # the peer may be gone already
            await self.websocket.close(code)


class FoxgloveServer:
    """The Foxglove endpoint of one studio: its channels, its viewers, the feed of its session.

    Args:
        session: the studio's session (a replay gets playback control, a live one services).
        run: carries out a command as the studio does (its checks, its events).
        loop: the loop the app runs on (``notify`` may come from elsewhere).
    """

    def __init__(self, session: Session, run: CommandRunner, loop: asyncio.AbstractEventLoop) -> None:
        self.session = session
        self.run = run
        self.loop = loop
        #: the recording a replay plays back (None: a live session); everything this module needs
        #: of a replay is the recording, the ring and the session's ``paused`` and ``speed``
        self.replay: Recording | None = session.played
        self.feed = TopicFeed(session.behavior_hz, generation_events=self.replay is None)
        self.channels: dict[str, _Channel] = {}
        self.clients: dict[int, FoxgloveClient] = {}
        self.session_id = f"{os.getpid()}-{time.time_ns()}"
        self._channel_ids = itertools.count(1)
        self._client_ids = itertools.count(1)
        self._last: Entry | None = None
        self._scheduled = False
        self._held = False
        self._tasks: set[asyncio.Task[Any]] = set()
        self._poller: asyncio.Task[None] | None = None
        #: the playback state the viewers were last told: (status, seq, speed)
        self._told: tuple[int, int, float] | None = None
        self._events: dict[int, list[dict[str, Any]]] = {}
        if self.replay is not None:
            for event in self.replay.events:
                self._events.setdefault(int(event.get("seq", 0)), []).append(event)
        self._advertise_new()

    # -- from the session ---------------------------------------------------------------------------

    def on_entry(self, entry: Entry) -> None:
        """The session recorded ticks: schedule sending them (never blocks, coalesces wake-ups)."""
        if self._scheduled:
            return
        self._scheduled = True
        try:
            self.loop.call_soon_threadsafe(self._dispatch)
        except RuntimeError:  # the loop is closed: the server is shutting down
            self._scheduled = False

    def command(self, command: Command) -> None:
        """The studio carried out ``command`` (from any client): an event, or a playback change."""
        if self.replay is not None:
            self._tell_playback(isinstance(command, Seek))
            return
        if not self.clients:
            return
        event = command_event(command, self.session.generation)
        latest = self.session.ring.latest
        if event is None or latest is None:
            return
        kind, agent, data = event
        self._publish(self.feed.event(latest.seq, latest.t, kind, agent, data))

    def _new_entries(self) -> list[Entry]:
        """The entries recorded since the last dispatch, oldest first (only the newest after a jump)."""
        ring = self.session.ring
        newest = ring.newest(64)
        if not newest:
            return []
        last = self._last
        if last is None:
            return newest[-1:]
        for i in range(len(newest) - 1, -1, -1):
            if newest[i] is last:
                return newest[i + 1 :]
        return newest[-1:]

    def _dispatch(self) -> None:
        self._scheduled = False
        if self._held:
            return
        if not self.clients:
            self._last = None  # nobody listens: the next viewer starts from the newest tick
            return
        entries = self._new_entries()
        if not entries:
            return
        if self.replay is not None:
            last = self._last
            jumped = last is not None and entries[0].seq != last.seq + 1
            self._tell_playback(jumped)  # a seek's state before the ticks of its new position
        wanted = self._wanted()
        for entry in entries:
            messages = self.feed.entry(entry, wanted)
            previous = self._last
            for event in self._events.get(entry.seq, ()) if self.replay is not None else ():
                if previous is None or previous.seq != entry.seq:
                    messages.append(FeedMessage("/xabsl/events", self.feed.time_ns(entry.seq), orjson.dumps(event)))
            self._last = entry
            self._advertise_new()
            for message in messages:
                self._publish(message)
        frame = _TIME.pack(TIME, self.feed.time_ns(entries[-1].seq))
        for client in self.clients.values():
            client.binary(frame)
        if self.replay is not None:
            self._tell_playback(False)

    def _wanted(self) -> set[str]:
        topics: set[str] = set()
        ids = {channel.id: channel.topic for channel in self.channels.values()}
        for client in self.clients.values():
            topics.update(ids[c] for c in client.by_channel)
        return topics

    def _publish(self, message: FeedMessage) -> None:
        channel = self.channels.get(message.topic)
        if channel is None:
            return
        for client in self.clients.values():
            subscription = client.by_channel.get(channel.id)
            if subscription is not None:
                client.message(subscription, message)

    def _advertise_new(self) -> None:
        new = []
        for topic, schema_name in self.feed.topics.items():
            if topic not in self.channels:
                channel = self.channels[topic] = _Channel(next(self._channel_ids), topic, schema_name)
                new.append(channel.advertised())
        if new:
            for client in self.clients.values():
                if client.advertised:  # a new viewer is sent every channel at once
                    client.json({"op": "advertise", "channels": new})

    # -- playback (replays) -------------------------------------------------------------------------

    def _playback_now(self) -> tuple[int, int, float]:
        replay = self.replay
        assert replay is not None
        position = self._position()
        if not self.session.paused:
            status = PLAYING
        elif position >= replay.end - 1:
            status = ENDED
        else:
            status = PAUSED
        return status, position, self.session.speed

    def _position(self) -> int:
        """The replay's playback position: the tick it put in the ring last."""
        latest = self.session.ring.latest
        if latest is not None:
            return latest.seq
        return self.replay.first if self.replay is not None else 0

    def _playback_frame(self, request_id: str | None, did_seek: bool) -> bytes:
        status, seq, speed = self._playback_now()
        rid = (request_id or "").encode("utf-8")
        head = _PLAYBACK_STATE.pack(PLAYBACK_STATE, status, self.feed.time_ns(seq), speed, did_seek, len(rid))
        return head + rid

    def _tell_playback(self, sought: bool) -> None:
        """Tell every viewer the replay's playback state if it changed since they were told.

        A change is a new status or speed, or a new position reached by a seek (``sought``); the
        position moving by playing or stepping is what the message frames and ``time`` show.
        """
        if self.replay is None or self._held or not self.clients:
            return
        now = self._playback_now()
        told = self._told
        moved = sought and (told is None or now[1] != told[1])
        if told is not None and (now[0], now[2]) == (told[0], told[2]) and not moved:
            return
        self._told = now
        frame = self._playback_frame(None, moved)
        for client in self.clients.values():
            client.binary(frame)

    async def _poll_playback(self) -> None:
        while True:
            await asyncio.sleep(PLAYBACK_POLL_SECONDS)
            self._tell_playback(False)

    async def playback_request(self, client: FoxgloveClient, payload: bytes) -> None:
        """A playback control request: speed, seek, play or pause, then the state with its id."""
        if len(payload) < _PLAYBACK_REQUEST.size:
            client.status(ERROR, "playback control request: too short")
            return
        command, speed, had_seek, seek_ns, id_length = _PLAYBACK_REQUEST.unpack_from(payload)
        rest = payload[_PLAYBACK_REQUEST.size :]
        if len(rest) < id_length:
            client.status(ERROR, "playback control request: request id longer than the message")
            return
        try:
            request_id = rest[:id_length].decode("utf-8")
        except UnicodeDecodeError:
            client.status(ERROR, "playback control request: request id is not UTF-8")
            return
        replay = self.replay
        if replay is None:
            client.status(ERROR, "playback control needs a replay (xabsl serve --replay FILE.mcap)")
            return
        if command not in (PLAY, PAUSE):
            client.status(ERROR, f"playback control request: unknown command {command}")
            return
        if not math.isfinite(speed) or speed <= 0:
            client.status(ERROR, f"playback control request: speed {speed} is not a positive number")
            return
        self._held = True  # the state answers first, the ticks of the new position follow it
        try:
            wanted_speed = min(MAX_SPEED, max(MIN_SPEED, round(float(speed), 6)))
            if wanted_speed != self.session.speed:
                await self._run(client, Speed(op="speed", speed=wanted_speed))
            if had_seek:
                await self._run(client, Seek(op="seek", seq=self._seq_at(seek_ns)))
            if command == PLAY and self.session.paused and self._position() < replay.end - 1:
                await self._run(client, Resume(op="resume"))
            elif command == PAUSE and not self.session.paused:
                await self._run(client, Pause(op="pause"))
            self._told = self._playback_now()
            client.binary(self._playback_frame(request_id, bool(had_seek)))
            others = self._playback_frame(None, bool(had_seek))
            for other in self.clients.values():
                if other is not client:
                    other.binary(others)
        finally:
            self._held = False
        self._dispatch()

    def _seq_at(self, time_ns: int) -> int:
        """The first tick of the replay at or after ``time_ns`` (the last one past the end).

        As an MCAP player seeks: the messages that follow a seek to T are those from T on.
        """
        replay = self.replay
        assert replay is not None
        time_of = self.feed.time_ns
        seq = max(replay.first, time_ns * self.feed.behavior_hz // 1_000_000_000)
        while time_of(seq) < time_ns and seq < replay.end - 1:
            seq += 1
        while seq > replay.first and time_of(seq - 1) >= time_ns:
            seq -= 1
        return min(seq, replay.end - 1)

    async def _run(self, client: FoxgloveClient, command: Command) -> Reply:
        answer = await self.run(command)
        if not answer.ok:
            client.status(ERROR, f"{command.op}: {answer.error}")
        return answer

    # -- requests -----------------------------------------------------------------------------------

    def json_request(self, client: FoxgloveClient, text: str) -> None:
        """A text message: ``subscribe`` and ``unsubscribe``; anything else is answered by a status."""
        try:
            message = orjson.loads(text)
        except orjson.JSONDecodeError:
            client.status(ERROR, "not JSON")
            return
        op = message.get("op") if isinstance(message, dict) else None
        if op == "subscribe":
            self._subscribe(client, message.get("subscriptions"))
        elif op == "unsubscribe":
            self._unsubscribe(client, message.get("subscriptionIds"))
        elif isinstance(op, str):
            client.status(WARNING, f"{op} is not supported by this server")
        else:
            client.status(ERROR, "a message needs an op")

    def _subscribe(self, client: FoxgloveClient, subscriptions: Any) -> None:
        if not isinstance(subscriptions, list):
            client.status(ERROR, "subscribe: subscriptions must be a list")
            return
        channels = {c.id: c for c in self.channels.values()}
        for item in subscriptions:
            ident = item.get("id") if isinstance(item, dict) else None
            channel_id = item.get("channelId") if isinstance(item, dict) else None
            if not _u32(ident) or not _u32(channel_id):
                client.status(ERROR, f"subscribe: {item!r} needs an id and a channelId (unsigned 32-bit integers)")
                continue
            channel = channels.get(channel_id)
            if channel is None:
                client.status(ERROR, f"subscribe: no channel {channel_id}")
            elif ident in client.subscriptions:
                client.status(ERROR, f"subscribe: subscription id {ident} is in use")
            elif channel_id in client.by_channel:
                client.status(ERROR, f"subscribe: channel {channel_id} is subscribed already")
            elif len(client.subscriptions) >= MAX_SUBSCRIPTIONS:
                client.status(ERROR, f"subscribe: at most {MAX_SUBSCRIPTIONS} subscriptions")
            else:
                client.subscriptions[ident] = channel_id
                client.by_channel[channel_id] = ident
                for message in self.feed.latched(channel.topic):
                    client.message(ident, message)

    def _unsubscribe(self, client: FoxgloveClient, ids: Any) -> None:
        if not isinstance(ids, list):
            client.status(ERROR, "unsubscribe: subscriptionIds must be a list")
            return
        for ident in ids:
            channel_id = client.subscriptions.pop(ident, None) if _u32(ident) else None
            if channel_id is None:
                client.status(WARNING, f"unsubscribe: no subscription {ident!r}")
                continue
            client.by_channel.pop(channel_id, None)

    async def binary_request(self, client: FoxgloveClient, data: bytes) -> None:
        """A binary message: a service call or a playback control request."""
        if not data:
            client.status(ERROR, "an empty binary message")
            return
        opcode, payload = data[0], data[1:]
        if opcode == SERVICE_CALL_REQUEST:
            await self.service_call(client, payload)
        elif opcode == PLAYBACK_CONTROL_REQUEST:
            await self.playback_request(client, payload)
        elif opcode == CLIENT_MESSAGE_DATA:
            client.status(ERROR, "this server takes no client publishing (no clientPublish capability)")
        else:
            client.status(ERROR, f"unknown binary opcode {opcode}")

    async def service_call(self, client: FoxgloveClient, payload: bytes) -> None:
        """A service call: the studio's command, answered by its result or a failure with the reason."""
        if len(payload) < _SERVICE_HEAD.size - 1:
            client.status(ERROR, "service call request: too short")
            return
        service_id, call_id, length = struct.unpack_from("<III", payload)
        encoding = payload[12 : 12 + length]
        body = payload[12 + length :]

        def failure(text: str) -> None:
            client.json({"op": "serviceCallFailure", "serviceId": service_id, "callId": call_id, "message": text})

        service = _SERVICES_BY_ID.get(service_id) if self.replay is None else None
        if service is None:
            failure(f"no service {service_id}")
            return
        if len(encoding) != length or encoding != b"json":
            failure("requests are JSON (encoding json)")
            return
        try:
            arguments = orjson.loads(body)
        except orjson.JSONDecodeError:
            failure("the request is not JSON")
            return
        if not isinstance(arguments, dict) or "op" in arguments or "type" in arguments:
            failure(f"the request is a JSON object of {service.command.__name__}'s arguments")
            return
        try:
            command = parse_command(orjson.dumps({**arguments, "op": service.op}))
        except ProtocolError as error:
            failure(str(error))
            return
        answer = await self.run(command)
        if not answer.ok:
            failure(answer.error or f"{service.op} was refused")
            return
        result = orjson.dumps({"ok": True, "result": answer.result})
        client.binary(_SERVICE_HEAD.pack(SERVICE_CALL_RESPONSE, service_id, call_id, 4) + b"json" + result)

    # -- connections --------------------------------------------------------------------------------

    def server_info(self) -> dict[str, Any]:
        """The ``serverInfo`` message (see the module docstring for the capabilities)."""
        session = self.session
        info: dict[str, Any] = {
            "op": "serverInfo",
            "name": f"xabsl studio: {session.example.name}",
            "capabilities": ["time"],
            "metadata": {"example": session.example.name, "behavior_hz": str(session.behavior_hz)},
            "sessionId": self.session_id,
        }
        replay = self.replay
        if replay is None:
            info["capabilities"].append("services")
            info["supportedEncodings"] = ["json"]
        else:
            info["capabilities"] += ["rangedPlayback", "playbackControl"]
            info["dataStartTime"] = _timestamp(self.feed.time_ns(replay.first))
            info["dataEndTime"] = _timestamp(self.feed.time_ns(replay.end - 1))
            info["metadata"]["replay"] = str(replay.path)
        return info

    async def serve(self, websocket: WebSocket) -> None:
        """Run one viewer's connection until it ends."""
        offered = list(websocket.scope.get("subprotocols") or [])
        chosen = next((name for name in SUBPROTOCOLS if name in offered), None)
        if chosen is None:
            detail = f"offer the websocket subprotocol {' or '.join(SUBPROTOCOLS)} (Foxglove WebSocket protocol)"
            try:
                await websocket.send_denial_response(JSONResponse({"detail": detail}, status_code=400))
            except RuntimeError:  # a server without the denial extension: a plain refusal (403)
                await websocket.close(CloseCode.POLICY_VIOLATION)
            return
        await websocket.accept(subprotocol=chosen)
        if len(self.clients) >= MAX_FOXGLOVE_CLIENTS:
            await websocket.close(CloseCode.TRY_AGAIN_LATER)
            return
        if not self.clients:  # nobody watched meanwhile: start afresh from the newest tick
            self._last = None
            self.feed = TopicFeed(self.session.behavior_hz, generation_events=self.replay is None)
        client = FoxgloveClient(websocket, next(self._client_ids), self)
        client.json(self.server_info())  # always the first message (the spec)
        self.clients[client.id] = client
        self._dispatch()  # the newest tick: the descriptions every subscriber is sent first
        client.json({"op": "advertise", "channels": [c.advertised() for c in self.channels.values()]})
        client.advertised = True
        if self.replay is None:
            client.json({"op": "advertiseServices", "services": [s.advertised() for s in SERVICES]})
        else:
            self._told = self._playback_now()
            client.binary(self._playback_frame(None, False))
            if self._poller is None:
                self._poller = self.loop.create_task(self._poll_playback())
        sender = asyncio.create_task(client.sender(), name=f"foxglove-{client.id}-sender")
        receiver = asyncio.create_task(client.receiver(), name=f"foxglove-{client.id}-receiver")
        try:
            done, _ = await asyncio.wait({sender, receiver}, return_when=asyncio.FIRST_COMPLETED)
            for task in done:
                error = task.exception()
                if error is not None and not isinstance(error, WebSocketDisconnect | OSError | RuntimeError):
                    log.warning("foxglove client %d ended: %r", client.id, error)
        finally:
            for task in (sender, receiver):
                task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await asyncio.gather(sender, receiver, return_exceptions=True)
            await client.close(CloseCode.NORMAL)
            self.clients.pop(client.id, None)
            if not self.clients and self._poller is not None:
                self._poller.cancel()
                self._poller = None

    def close_soon(self, client: FoxgloveClient, code: int) -> None:
        """Close ``client`` from code that cannot await."""
        task = self.loop.create_task(client.close(code))
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def close_all(self, code: int = CloseCode.GOING_AWAY) -> None:
        """Close every viewer (the server shuts down)."""
        if self._poller is not None:
            self._poller.cancel()
            self._poller = None
        await asyncio.gather(*(c.close(code) for c in list(self.clients.values())), return_exceptions=True)

    def stats(self) -> dict[str, Any]:
        """Counters for ``GET /api/status``: viewers, their queues, frames sent and dropped."""
        return {
            "clients": len(self.clients),
            "channels": len(self.channels),
            "queued": {f"viewer-{c.id}": len(c.frames) for c in self.clients.values()},
            "sent": {f"viewer-{c.id}": c.sent for c in self.clients.values()},
            "dropped": {f"viewer-{c.id}": c.dropped for c in self.clients.values()},
        }


def _u32(value: object) -> TypeGuard[int]:
    return isinstance(value, int) and not isinstance(value, bool) and 0 <= value < 2**32


router = APIRouter()


@router.websocket("/foxglove")
async def foxglove_endpoint(websocket: WebSocket) -> None:
    """The Foxglove WebSocket protocol (docs/foxglove.md), behind the studio's token and Origin checks."""
    server: FoxgloveServer | None = getattr(websocket.app.state.studio, "foxglove", None)
    if server is None:  # the app's lifespan did not run
        await websocket.close(CloseCode.TRY_AGAIN_LATER)
        return
    await server.serve(websocket)
