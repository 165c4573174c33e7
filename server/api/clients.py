"""Websocket clients: one :class:`Client` per connection, and the :class:`Hub` that feeds them frames.

Backpressure is the point of this module. The simulation (its own process) never waits for a
client and a client is never queued frames without bound:

* each client has a *latest-frame slot* (``Client.target``): the hub overwrites it with the newest
  frame due for that client; the client's sender task sends whatever the slot holds when the
  previous send finished, encoded as a delta against what this client last received
  (``frames.FrameEncoder``). A slow reader therefore just gets fewer, larger-delta frames;
* replies, events and history chunks wait in a bounded deque (``MAX_PENDING_CONTROL``); a client
  that floods commands without reading their replies is closed with 1008;
* a send blocked on a client that does not read at all only blocks that client's sender task.

A client's rate is honoured by a schedule that depends only on the frame's seq (``Client.due``),
so clients with the same rate receive the same ticks and share one encoding.

Connection states (``ClientState``) go CONNECTING -> LIVE -> CLOSING -> CLOSED and are checked
on every transition; receive loops end on ``WebSocketDisconnect`` rather than on flags.
"""

from __future__ import annotations

import asyncio
import contextlib
import enum
import itertools
import logging
from collections import deque
from collections.abc import Awaitable, Callable, Iterator
from typing import Any

from starlette.websockets import WebSocket, WebSocketDisconnect

from xabsl_studio.engine.errors import RecordError
from xabsl_studio.server.protocol.commands import Command, Resync, Subscribe, guess_id, parse_message
from xabsl_studio.server.protocol.host import Hit
from xabsl_studio.server.protocol.limits import DEFAULT_RATE, MAX_MESSAGE_BYTES, MAX_PENDING_CONTROL, CloseCode
from xabsl_studio.server.protocol.replies import (
    BreakpointEvent,
    CrashEvent,
    Reply,
    ServerEvent,
    SessionInfo,
    encode,
    encode_hello,
)
from xabsl_studio.server.protocol.types import HelloReason, ProtocolError
from xabsl_studio.server.session.frames import Entry, FrameEncoder, Generation
from xabsl_studio.server.session.live import Session

log = logging.getLogger("xabsl.server")

#: Runs a command for a client: returns its reply.
CommandRunner = Callable[[Command, "Client"], Awaitable[Reply]]


class ClientState(enum.Enum):
    """Where a connection is (see the module docstring)."""

    CONNECTING = "connecting"
    LIVE = "live"
    CLOSING = "closing"
    CLOSED = "closed"


_TRANSITIONS = {
    ClientState.CONNECTING: {ClientState.LIVE, ClientState.CLOSING, ClientState.CLOSED},
    ClientState.LIVE: {ClientState.CLOSING, ClientState.CLOSED},
    ClientState.CLOSING: {ClientState.CLOSED},
    ClientState.CLOSED: set(),
}

_ids = itertools.count(1)


class Client:
    """One websocket connection: state, subscription, latest-frame slot, control queue, counters."""

    def __init__(self, websocket: WebSocket, hub: Hub) -> None:
        self.id = f"client-{next(_ids)}"
        self.websocket = websocket
        self.hub = hub
        self.state = ClientState.CONNECTING
        self.rate = DEFAULT_RATE
        #: the robots whose values are streamed (None: all)
        self.robots: frozenset[int] | None = None
        self.last_seq: int | None = None
        self.last_gen: int | None = None
        self.hello_reason: HelloReason | None = "connect"
        self.target: Entry | None = None
        self._due_seq = -1
        self.control: deque[bytes] = deque()
        self.history: deque[Iterator[bytes]] = deque()
        self.wake = asyncio.Event()
        self.frames_sent = 0
        self.bytes_sent = 0
        self.close_code: int | None = None

    def _move(self, state: ClientState) -> None:
        if state not in _TRANSITIONS[self.state]:
            raise RuntimeError(f"{self.id}: cannot go from {self.state.value} to {state.value}")
        self.state = state

    # -- feeding (asyncio thread) ---------------------------------------------------------------

    def due(self, entry: Entry, ticks_per_second: float) -> bool:
        """Whether ``entry`` falls on this client's schedule (see the module docstring)."""
        if entry.gen.number != self.last_gen or ticks_per_second <= 0.0:
            return True
        ratio = self.rate / ticks_per_second
        if ratio >= 1.0:
            return True
        # The same seqs for every client of a rate: tick n is due when floor(n * ratio) steps.
        return int(entry.seq * ratio) != int(self._due_seq * ratio) and entry.seq > self._due_seq

    def offer(self, entry: Entry) -> None:
        """Put ``entry`` in the latest-frame slot (replacing one not sent yet) and wake the sender."""
        self._due_seq = entry.seq
        self.target = entry
        self.wake.set()

    def push(self, message: bytes | Reply | ServerEvent) -> None:
        """Queue a reply/event; a client that lets MAX_PENDING_CONTROL pile up is closed (1008)."""
        if self.state is not ClientState.LIVE:
            return
        if len(self.control) >= MAX_PENDING_CONTROL:
            self.hub.close_soon(self, CloseCode.POLICY_VIOLATION)
            return
        self.control.append(message if isinstance(message, bytes) else encode(message))
        self.wake.set()

    def resync(self, reason: HelloReason = "resync") -> None:
        """Send a hello (and then a full frame) next."""
        self.hello_reason = reason
        self.wake.set()

    # -- the two tasks ----------------------------------------------------------------------------

    async def send(self, data: bytes) -> None:
        """Send one text message.

        Raises:
            WebSocketDisconnect: the connection is closing or gone (the peer left, or we closed it):
                the server then sends nothing more on it.
        """
        if self.state is not ClientState.LIVE:
            raise WebSocketDisconnect(self.close_code or CloseCode.NORMAL)
        self.bytes_sent += len(data)
        try:
            await self.websocket.send_text(data.decode("utf-8"))
        except (RuntimeError, OSError) as error:
            # The peer went away between our state check and the send (uvicorn: "Unexpected ASGI
            # message 'websocket.send', after sending 'websocket.close'"): a disconnect, not a bug.
            raise WebSocketDisconnect(CloseCode.GOING_AWAY) from error

    async def sender(self) -> None:
        """The task that sends hellos, control messages, frames and history chunks, in that order."""
        hub = self.hub
        while self.state is ClientState.LIVE:
            await self.wake.wait()
            self.wake.clear()
            while self.state is ClientState.LIVE:
                latest = hub.session.ring.latest
                if latest is not None and latest.gen.number != self.last_gen and self.hello_reason is None:
                    self.hello_reason = latest.gen.reason
                if self.hello_reason is not None:
                    gen = latest.gen if latest is not None else hub.session.generation
                    if gen is None:  # nothing recorded yet (the session is starting)
                        break
                    await self.send(hub.hello(gen, self.hello_reason))
                    self.hello_reason = None
                    self.last_gen = gen.number
                    self.last_seq = None
                    self.target = latest
                    continue
                if self.control:
                    await self.send(self.control.popleft())
                    continue
                target = self.target
                if target is not None and target.seq != self.last_seq:
                    self.target = None
                    if target.paths is None or target.gen.number != self.last_gen:
                        target = latest  # too old to encode (or a reload came in between): the newest
                    if target is None or target.gen.number != self.last_gen:
                        continue
                    await self.send(hub.encoder.frame(self.last_seq, self.last_gen, target, self.robots))
                    self.frames_sent += 1
                    self.last_seq = target.seq
                    continue
                if self.history:
                    job = self.history[0]
                    chunk = next(job, None)
                    if chunk is None:
                        self.history.popleft()
                    else:
                        await self.send(chunk)
                    continue
                break

    async def receiver(self, run_command: CommandRunner) -> None:
        """The task that reads the client's messages until it disconnects."""
        websocket = self.websocket
        while True:
            message = await websocket.receive()
            if message["type"] == "websocket.disconnect":
                raise WebSocketDisconnect(message.get("code", CloseCode.NORMAL))
            if message.get("bytes") is not None:
                await self.close(CloseCode.UNSUPPORTED_DATA)
                return
            text = message.get("text") or ""
            if len(text) > MAX_MESSAGE_BYTES or len(text.encode("utf-8")) > MAX_MESSAGE_BYTES:
                await self.close(CloseCode.MESSAGE_TOO_BIG)
                return
            await self.handle(text, run_command)

    async def handle(self, text: str, run_command: CommandRunner) -> None:
        """Carry out one client message; every problem is an error reply (the connection stays)."""
        try:
            message = parse_message(text)
        except ProtocolError as error:
            self.push(Reply(id=guess_id(text), ok=False, error=str(error)))
            return
        if isinstance(message, Subscribe):
            self.rate = message.rate
            self.robots = frozenset(message.robots) if message.robots is not None else None
            self.last_seq = None  # the subscribed robots changed: the next frame is full
            if message.id is not None:
                self.push(Reply(id=message.id, ok=True))
            return
        if isinstance(message, Resync):
            self.resync()
            return
        try:
            answer = await run_command(message, self)
        except RecordError as exc:  # a replay's file damaged where the command read it: say so
            answer = Reply(id=message.id, ok=False, error=str(exc))
        except Exception as exc:  # a bug must not end the connection: answer and log it
            log.exception("command %s failed", message.op)
            answer = Reply(id=message.id, ok=False, error=f"internal error: {type(exc).__name__}: {exc}")
        self.push(answer)

    async def close(self, code: int) -> None:
        """Close the connection with ``code`` (once; later calls do nothing)."""
        if self.state in (ClientState.CLOSING, ClientState.CLOSED):
            return
        self._move(ClientState.CLOSING)
        self.close_code = code
        self.wake.set()
        with contextlib.suppress(Exception):  # the peer may be gone already
            await self.websocket.close(code)


class Hub:
    """All live clients of a session; hands them frames from the session's ring."""

    def __init__(self, session: Session, loop: asyncio.AbstractEventLoop) -> None:
        self.session = session
        self.loop = loop
        self.clients: dict[str, Client] = {}
        self.encoder = FrameEncoder(session.ring)
        self._scheduled = False
        self._hello_cache: tuple[int, bytes] | None = None
        self._tasks: set[asyncio.Task[Any]] = set()

    # -- from the session ----------------------------------------------------------------------------

    def on_entry(self, entry: Entry) -> None:
        """Called after frames were recorded: never blocks, coalesces wake-ups."""
        if not self._scheduled:
            self._scheduled = True
            try:
                self.loop.call_soon_threadsafe(self._dispatch)
            except RuntimeError:  # the loop is closed: the server is shutting down
                self._scheduled = False

    def _dispatch(self) -> None:
        self._scheduled = False
        entry = self.session.ring.latest
        if entry is None:
            return
        # While paused, frames come only from step, reset and reload: every client wants each.
        ticks_per_second = 0.0 if self.session.paused else self.session.behavior_hz * self.session.speed
        for client in self.clients.values():
            if client.state is ClientState.LIVE and client.due(entry, ticks_per_second):
                client.offer(entry)

    def on_breakpoint(self, hit: Hit) -> None:
        """A breakpoint hit and paused the simulation: tell every client (``event`` ``breakpoint``)."""
        self.broadcast(
            BreakpointEvent(
                program=hit.key,
                breakpoint=hit.breakpoint,
                robot=hit.robot,
                seq=hit.seq,
                t=hit.t,
                description=hit.description,
            )
        )

    def on_crash(self, crash: dict[str, Any]) -> None:
        """The simulation process ended unasked: tell every client (``event`` ``crash``)."""
        self.broadcast(CrashEvent(message=crash["message"], seq=crash["seq"], t=crash["t"]))

    # -- messages ------------------------------------------------------------------------------------

    def hello(self, gen: Generation, reason: HelloReason) -> bytes:
        """A :class:`~xabsl_studio.server.protocol.replies.Hello`, spliced from the generation's pre-encoded parts."""
        session = self.session
        latest = session.ring.latest
        info = SessionInfo(
            example=session.example.name,
            paused=session.paused,
            speed=session.speed,
            seed=session.seed,
            behavior_hz=session.behavior_hz,
            seq=latest.seq if latest else 0,
            t=latest.t if latest else 0,
            token_required=self.token_required,
            offset=gen.offset,
        )
        _, structure, compressed = gen.wire_structure()
        return encode_hello(reason, gen.number, info, structure, gen.scene_bytes, session.fork, compressed)

    token_required = False

    def broadcast(self, message: Reply | ServerEvent) -> None:
        """Queue ``message`` for every client (encoded once)."""
        data = encode(message)
        for client in list(self.clients.values()):
            client.push(data)

    # -- connections -----------------------------------------------------------------------------------

    async def serve(self, websocket: WebSocket, run_command: CommandRunner, max_clients: int) -> None:
        """Run one connection until it ends; releases what the client forced."""
        client = Client(websocket, self)
        if len(self.clients) >= max_clients:
            await websocket.accept()
            await websocket.close(CloseCode.TRY_AGAIN_LATER)
            return
        await websocket.accept()
        client._move(ClientState.LIVE)
        self.clients[client.id] = client
        client.wake.set()  # sends the hello and the first (full) frame at once
        sender = asyncio.create_task(client.sender(), name=f"{client.id}-sender")
        try:
            receiver = asyncio.create_task(client.receiver(run_command), name=f"{client.id}-receiver")
            done, _ = await asyncio.wait({sender, receiver}, return_when=asyncio.FIRST_COMPLETED)
            for task in done:
                error = task.exception()
                if error is not None and not isinstance(error, WebSocketDisconnect):
                    log.warning("%s ended: %r", client.id, error)
        finally:
            for task in (sender, receiver):
                task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await asyncio.gather(sender, receiver, return_exceptions=True)
            if client.state is not ClientState.CLOSED:
                if client.state is ClientState.LIVE:
                    await client.close(CloseCode.NORMAL)
                client._move(ClientState.CLOSED)
            self.clients.pop(client.id, None)
            self.session.release_owner(client.id)

    def close_soon(self, client: Client, code: int) -> None:
        """Close ``client`` from a callback that cannot await."""
        task = self.loop.create_task(client.close(code))
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def close_all(self, code: int = CloseCode.GOING_AWAY) -> None:
        """Close every client (the server shuts down)."""
        await asyncio.gather(*(c.close(code) for c in list(self.clients.values())), return_exceptions=True)

    def stats(self) -> dict[str, Any]:
        """Counters for ``GET /api/status``."""
        return {
            "clients": len(self.clients),
            "encoded": self.encoder.encoded,
            "cache_hits": self.encoder.cache_hits,
            "pending_control": {c.id: len(c.control) for c in self.clients.values()},
            "frames_sent": {c.id: c.frames_sent for c in self.clients.values()},
        }
