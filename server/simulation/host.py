"""The attach host: a program that runs its own XABSL engines exposes them to studios (docs/attach.md).

``link = serve_engines({"robot1": engine}, port=7410)`` listens for studios (``xabsl attach``);
the program calls ``link.publish()`` after every tick (or ``link.execute(now_ms)``, which ticks
every engine and publishes). Two threads share the work:

* **the program's thread** (in :meth:`HostLink.publish`): carries out the studios' commands
  between two ticks (forcing, overrides, agent selection, reset, breakpoints, hot reload from
  intermediate code: :class:`HostEngines`, an
  :class:`~xabsl_studio.server.simulation.engines.EngineSet` like the studio's own simulation),
  samples the tick and writes it to every attached studio's socket without blocking. With no
  studio attached it only counts the tick;
* **the link's thread**: accepts connections, checks the handshake and the token, reads and
  checks commands (JSON, ``xabsl_studio.server.protocol.attach``), pushes what a socket did not
  take at once, sends heartbeats and drops a studio that stays silent past
  ``HEARTBEAT_TIMEOUT``, whose forces, overrides and pause the next ``publish`` releases.

A studio that cannot keep up never blocks the program: its bytes wait in its own buffer, and
past ``MAX_BACKLOG`` its ticks are dropped and counted (the studio sees the gap in the seqs).
Pause and step exist only when the program allows them (``pausable=True``): ``publish`` then
waits while a studio holds it paused, serving commands meanwhile.
"""

from __future__ import annotations

import collections
import contextlib
import logging
import os
import selectors
import socket
import sys
import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import orjson

from xabsl_studio.engine.emit.ic import emit_ic
from xabsl_studio.engine.emit.json import program_to_json
from xabsl_studio.engine.errors import XabslError
from xabsl_studio.engine.ir.ic_reader import read_ic
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.record.sources import program_sources
from xabsl_studio.engine.runtime import DebugError, Engine, EngineError
from xabsl_studio.server.protocol.attach import (
    DEFAULT_PORT,
    HANDSHAKE_TIMEOUT,
    HEARTBEAT_SECONDS,
    HEARTBEAT_TIMEOUT,
    MAX_BACKLOG,
    MAX_PEERS,
    MAX_QUEUED_REQUESTS,
    MAX_STUDIO_MESSAGE,
    PROTOCOL,
    Attach,
    Control,
    FrameReader,
    Heartbeat,
    HostGeneration,
    Refused,
    Welcome,
    WireError,
    decode_from_studio,
    encode_from_host,
    encode_generation,
    encode_sample,
)
from xabsl_studio.server.protocol.commands import Explain, Pause, Reset, Resume, Speed, Status, Step, WorldCommand
from xabsl_studio.server.protocol.host import (
    LoadIntermediateCode,
    NewGeneration,
    Sample,
    WorkerReply,
    WorkerRequest,
)
from xabsl_studio.server.protocol.tokens import check_token, is_loopback, new_token, token_matches
from xabsl_studio.server.protocol.types import HelloReason
from xabsl_studio.server.simulation.engines import CommandError, EngineSet
from xabsl_studio.server.simulation.worker import EXPLAIN_OPS

__all__ = ["HostEngines", "HostLink", "serve_engines"]

log = logging.getLogger("xabsl.attach")

#: Ops any attached studio may send; every other op needs control (the first to send one takes it).
READ_ONLY_OPS = frozenset({"explain", "explain_recorded", "status"})
#: Seconds the link's thread sleeps at most between two looks at its timers.
_POLL = 0.2
#: While ticks stream: seconds between two flushes of what the program's thread queued (its
#: latency; the program's thread then writes no socket and wakes nobody per tick).
_FLUSH = 0.004
#: Seconds after the last queued tick during which the link's thread keeps flushing that often.
_STREAMING = 0.25
#: Bytes of queued ticks past which the program's thread sends them itself (a fast program
#: would outrun the link's thread, which waits for the GIL): one system call per this many.
_SEND_BYTES = 16 * 1024


class HostEngines(EngineSet):
    """A program's own engines as one :class:`EngineSet`: its commands, generations and samples.

    Args:
        engines: robot name -> a loaded engine, in the order the studio lists the robots.
        keys: robot name -> the name of the behavior set its engine runs (default: ``behavior``,
            or ``behavior2``... for further distinct programs).
        pausable: the program lets a studio pause and step it (``publish`` then blocks while paused).
    """

    def __init__(self, engines: Mapping[str, Engine], keys: Mapping[str, str] | None = None, pausable: bool = False):
        super().__init__()
        if not engines:
            raise ValueError("serve_engines needs at least one engine")
        self.names = list(engines)
        self.engines = list(engines.values())
        programs: dict[int, str] = {}
        for name, engine in engines.items():
            if not isinstance(engine, Engine):
                raise TypeError(f"{name}: an xabsl_studio.engine.runtime.Engine is needed, not {type(engine).__name__}")
            program = engine.program  # raises DebugError before a load
            if keys is not None and name in keys:
                key = keys[name]
            else:
                key = programs.get(id(program)) or ("behavior" if not programs else f"behavior{len(programs) + 1}")
            programs.setdefault(id(program), key)
            self.keys.append(key)
        self.pausable = pausable
        self.seq = 0
        self.generation_number = 0
        self.reason: HelloReason = "connect"
        self.errors: dict[str, str | None] = dict.fromkeys(k for k in self.keys if k is not None)
        #: what this host runs per key: (program, its JSON description, its intermediate code, its sources)
        self.running: dict[str, tuple[Program, dict[str, Any], str, dict[str, Any] | None]] = {}
        #: ticks still to run of a ``step`` (then paused again), and who waits for the answer
        self.steps = 0
        self.stepper: tuple[Any, int | None] | None = None

    def record_reads(self, on: bool) -> None:
        """Let every engine's decisions record what they read (``Engine.record_reads``), or not."""
        for engine in self.engines:
            if engine is not None:
                engine.record_reads = on

    def program_of(self, key: str) -> Program | None:
        """The program the engines of ``key`` run."""
        for engine, k in zip(self.engines, self.keys, strict=True):
            if k == key and engine is not None:
                return engine.program
        return None

    def generation(self, reason: HelloReason) -> HostGeneration:
        """A new generation of ids (start, reload, reset): its message, with every program's IC."""
        self.generation_number += 1
        self.reason = reason
        robots, input_ids, output_ids = self.sampling_tables(
            self.generation_number, ((name, None, None) for name in self.names)
        )
        for key in dict.fromkeys(k for k in self.keys if k is not None):
            program = self.program_of(key)
            have = self.running.get(key)
            if program is not None and (have is None or have[0] is not program):
                self.running[key] = (program, program_to_json(program), emit_ic(program), _sources(program))
        structure = {"programs": {k: v[1] for k, v in self.running.items()}, "robots": robots}
        message = NewGeneration(
            self.generation_number,
            reason,
            orjson.dumps(structure),
            b"{}",
            input_ids,
            output_ids,
            0,
            dict(self.errors),
            enums={key: codec.tables.enums for key, codec in self.codecs[self.generation_number].items()},
            raw_values=True,
        )
        return HostGeneration(
            message,
            {k: v[2] for k, v in self.running.items()},
            {k: v[3] for k, v in self.running.items() if v[3] is not None},
        )

    def sample(self, t: int) -> Sample:
        """The sample of the tick just run (clock ``t`` ms)."""
        self.seq += 1
        paths, extras, inputs, outputs, reads = self.robot_samples()
        return Sample(
            self.seq, self.generation_number, t, time.time() * 1000.0, self.paused, 1.0,
            paths, extras, inputs, outputs, b"{}", b"{}", reads,
        )  # fmt: skip

    # -- commands -------------------------------------------------------------------------------------

    def execute(self, command: Any, owner: str | None) -> Any:
        """Carry out one command (the link's thread checked it); generation changes are the caller's.

        Raises:
            CommandError: the command does not fit these engines, or this host does not do it.
        """
        op = command.op
        explain = EXPLAIN_OPS.get(op)
        if explain is not None:
            if isinstance(command, Explain) and command.seq is not None:
                raise CommandError("explain at a past tick is answered by the studio from its history")
            handler: Any = lambda body, who: explain(self, body, who)  # noqa: E731
        else:
            handler = getattr(self, f"_op_{op}", None)
        if handler is None:
            raise CommandError(f"an attached host does not carry out {op!r}")
        try:
            return handler(command, owner)
        except (DebugError, EngineError) as error:
            raise CommandError(str(error)) from None

    def _op_pause(self, command: Pause, owner: str | None) -> Any:
        if not self.pausable:
            raise CommandError("this host does not let studios pause it (serve_engines(..., pausable=True))")
        self.paused = True
        return {"paused": True}

    def _op_resume(self, command: Resume, owner: str | None) -> Any:
        self.paused = False
        self.steps = 0
        return {"paused": False}

    def _op_step(self, command: Step, owner: str | None) -> Any:
        if not self.pausable:
            raise CommandError("this host does not let studios step it (serve_engines(..., pausable=True))")
        if not self.paused:
            raise CommandError("step works while the host is paused")
        self.steps = command.ticks
        return None  # answered once the ticks ran (HostLink)

    def _op_speed(self, command: Speed, owner: str | None) -> Any:
        raise CommandError("an attached host runs at its own rate")

    def _op_world_command(self, command: WorldCommand, owner: str | None) -> Any:
        raise CommandError("an attached host has no world commands")

    def _op_reset(self, command: Reset, owner: str | None) -> Any:
        for engine in self.engines:
            if engine is not None:
                engine.reset()
        return {"seed": 0}

    def _op_status(self, command: Status, owner: str | None) -> Any:
        return {"paused": self.paused, "seq": self.seq, "pausable": self.pausable, "errors": dict(self.errors)}

    def _op_load_ic(self, command: LoadIntermediateCode, owner: str | None) -> Any:
        """Hot reload from intermediate code; None when swapped, else why the running behavior was kept."""
        key = command.key
        current = self.program_of(key)
        if current is None:
            raise CommandError(f"no robot of this host runs {key!r}")
        try:
            program = read_ic(command.ic, current)
        except XabslError as error:
            return f"the intermediate code does not read on this host: {error}"
        try:
            for engine, k in zip(self.engines, self.keys, strict=True):
                if k == key and engine is not None:
                    engine.reload(program)
        except EngineError as error:
            # Engines reload one by one; with one set of bindings they fail alike, so the first fails.
            self.errors[key] = str(error)
            return f"the behavior does not run on this host: {error}"
        self.errors[key] = None
        return None


@dataclass(eq=False)
class _Peer:
    """One studio's connection (the link's thread reads it; both threads write it, under ``lock``)."""

    sock: socket.socket
    name: str
    opened: float
    reader: FrameReader = field(default_factory=lambda: FrameReader(MAX_STUDIO_MESSAGE))
    studio: str = ""
    attached: bool = False
    out: bytearray = field(default_factory=bytearray)
    lock: threading.Lock = field(default_factory=threading.Lock)
    heard: float = 0.0
    said: float = 0.0
    dropped: int = 0
    sent: int = 0
    queued: int = 0
    closed: bool = False
    #: a thread is sending ``out`` (the other does not, so bytes keep their order)
    sending: bool = False
    #: the socket took nothing last time: wait for the link's thread to see it writable
    blocked: bool = False


class HostLink:
    """A program's engines served to studios (see the module docstring); made by :func:`serve_engines`."""

    def __init__(
        self,
        engines: HostEngines,
        host: str,
        port: int,
        token: str | None,
        name: str,
        backlog_bytes: int = MAX_BACKLOG,
    ) -> None:
        loopback = is_loopback(host)
        if token is None and not loopback:
            token = new_token()
            print(f"xabsl attach: serving {name} on {host}:{port} with the token {token}", file=sys.stderr)
        check_token(token, loopback)
        self.engines = engines
        self.token = token
        self.name = name
        #: bytes that may wait for one studio before its ticks are dropped
        self.backlog_bytes = backlog_bytes
        self._listener = socket.create_server((host, port), family=_family(host), backlog=16)
        self._listener.setblocking(False)
        self.address: tuple[str, int] = self._listener.getsockname()[:2]
        self._selector = selectors.DefaultSelector()
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._wake_w.setblocking(False)
        self._lock = threading.Lock()
        self._peers: dict[str, _Peer] = {}
        self._attached: tuple[_Peer, ...] = ()
        self._numbers = 0
        self._inbox: collections.deque[tuple[_Peer, WorkerRequest]] = collections.deque()
        self._gone: collections.deque[_Peer] = collections.deque()
        self._wakeup = threading.Event()
        self._holder: _Peer | None = None
        self._stopping = False
        self._generation = encode_generation(engines.generation("connect"))
        self._last_sample: bytes | None = None
        self._last_seq = -1
        #: when the program's thread last queued a tick; whether the link's thread flushes often now
        self._queued = 0.0
        self._streaming = False
        #: whether the decisions record their reads (only while a studio watches; the samplers
        #: of a generation switch it on)
        self._reading = False
        engines.record_reads(False)
        #: ticks published; samples written, dropped for slow studios
        self.ticks = 0
        self._thread = threading.Thread(target=self._serve, name="xabsl-attach", daemon=True)
        self._thread.start()

    # -- the program's thread ------------------------------------------------------------------------

    @property
    def studios(self) -> int:
        """Studios attached now."""
        return len(self._attached)

    @property
    def port(self) -> int:
        """The port listened on (the real one when 0 was asked for)."""
        return self.address[1]

    def execute(self, now_ms: int) -> None:
        """Tick every engine at ``now_ms``, then :meth:`publish`."""
        for engine in self.engines.engines:
            if engine is not None:
                engine.execute(now_ms)
        self.publish()

    def publish(self) -> None:
        """After a tick: carry out the studios' commands, push the tick to every attached studio.

        Never blocks on a studio; blocks only while a studio holds a ``pausable`` host paused.
        """
        self.ticks += 1
        engines = self.engines
        if not (self._attached or self._inbox or self._gone or self._reading or engines.paused):
            engines.seq += 1  # the tick happened; nobody watches it (the whole cost with no studio)
            return
        watched = bool(self._attached)
        if watched:
            self._publish_tick()
        else:
            engines.seq += 1  # the tick happened; nobody watches it
        # Commands after the tick's sample: what they change shows from the next tick on.
        if self._inbox or self._gone:
            self._serve_commands()
        if watched != self._reading:
            # Decisions record their reads only while a studio watches (with none the tick costs
            # what it costs without the library); switched between two ticks, as the engine wants.
            self._reading = watched
            engines.record_reads(watched)
        if not self._attached and not engines.paused:
            return
        if engines.steps:
            engines.steps -= 1
            if not engines.steps:
                engines.paused = True
                self._answer_step()
        while engines.paused and engines.pausable and not self._stopping:
            self._wakeup.wait(_POLL)
            self._wakeup.clear()
            if self._inbox or self._gone:
                self._serve_commands()
            if engines.steps or not self._attached:
                break

    def _publish_tick(self) -> None:
        engines = self.engines
        found = engines.check_breakpoints() if engines.breakpoints.armed else None
        if found and not (engines.pausable and self._holder is not None):
            engines.paused = False  # nobody may pause this host: report the hit, go on
        t = next((e.now for e in engines.engines if e is not None), 0)
        sample = engines.sample(t)
        data = encode_sample(sample)
        hits = b""
        if found:
            engines.record_hits(found, sample.seq, sample.t)
            hits = b"".join(encode_from_host(hit) for hit in engines.take_hits())
            engines.steps = 0
        with self._lock:
            self._last_sample, self._last_seq = data, sample.seq
            peers = self._attached
        for peer in peers:
            self._write(peer, data, droppable=True)
            if hits:
                self._write(peer, hits)

    def _serve_commands(self) -> None:
        engines = self.engines
        while self._gone:
            peer = self._gone.popleft()
            released = engines.release_owner(peer.name + "/", prefix=True)
            if self._holder is None and engines.paused:
                engines.paused = False
                engines.steps = 0
            if released:
                log.info("released %d forces and overrides of %s (%s)", released, peer.studio, peer.name)
        reload = False
        while self._inbox:
            peer, request = self._inbox.popleft()
            peer.queued -= 1
            body = request.body
            owner = f"{peer.name}/{request.owner or ''}"
            ok, result, error = True, None, None
            if body.op not in READ_ONLY_OPS and not self._may_control(peer):
                holder = self._holder
                ok, error = False, f"{self.name} is controlled by {holder.studio if holder else 'another studio'}"
            else:
                try:
                    result = engines.execute(body, owner)
                except CommandError as problem:
                    ok, error = False, str(problem)
                except Exception as problem:  # a bug in a command must not end the program: answer it
                    log.exception("attach: %s failed", body.op)
                    ok, error = False, f"internal error: {type(problem).__name__}: {problem}"
            if ok and body.op == "step":
                engines.stepper = (peer, request.ident)
                self._wakeup.set()
                continue
            if ok and (body.op == "reset" or (body.op == "load_ic" and result is None)):
                reload = True
                self._new_generation("reset" if body.op == "reset" else "reload")
            self._write(peer, encode_from_host(WorkerReply(request.ident, ok, result, error)))
        if reload:
            self._wakeup.set()

    def _new_generation(self, reason: HelloReason) -> None:
        engines = self.engines
        data = encode_generation(engines.generation(reason))
        engines.record_reads(self._reading)
        sample = encode_sample(engines.sample(next((e.now for e in engines.engines if e is not None), 0)))
        with self._lock:
            self._generation = data
            self._last_sample, self._last_seq = sample, engines.seq
            peers = self._attached
        for peer in peers:
            self._write(peer, data + sample)

    def _answer_step(self) -> None:
        stepper = self.engines.stepper
        self.engines.stepper = None
        if stepper is not None:
            peer, ident = stepper
            result = {"seq": self.engines.seq, "t": next((e.now for e in self.engines.engines if e is not None), 0)}
            self._write(peer, encode_from_host(WorkerReply(ident, True, result, None)))

    def _may_control(self, peer: _Peer) -> bool:
        with self._lock:
            if self._holder is None:
                self._holder = peer
                self._announce_control()
            return self._holder is peer

    # -- writing (both threads) ---------------------------------------------------------------------

    def _write(self, peer: _Peer, data: bytes, droppable: bool = False) -> None:
        """Send ``data`` now or queue it; a droppable tick is queued (dropped past the backlog cap).

        Ticks are only queued: the link's thread sends them every ``_FLUSH`` s while they stream,
        so a tick costs the program's thread no system call (it wakes the link's thread only when
        that one sleeps long). Everything else goes out at once unless bytes wait before it.
        """
        with peer.lock:
            if peer.closed:
                return
            if droppable or peer.out or peer.sending:
                out = peer.out
                if droppable and len(out) > self.backlog_bytes:
                    peer.dropped += 1
                    return
                out += data
                peer.sent += 1
                if droppable:
                    self._queued = time.monotonic()
                    if len(out) >= _SEND_BYTES and not peer.sending and not peer.blocked:
                        try:
                            written = peer.sock.send(out)
                        except BlockingIOError:
                            written, peer.blocked = 0, True
                        except OSError:
                            return  # the link's thread notices the closed socket
                        del out[:written]
                        peer.said = time.monotonic()
                if not self._streaming:
                    self._wake()
                return
            try:
                written = peer.sock.send(data)
            except BlockingIOError:
                written = 0
            except OSError:
                return  # the link's thread notices the closed socket
            peer.sent += 1
            peer.said = time.monotonic()
            if written < len(data):
                peer.out += data[written:]
                self._wake()

    def _wake(self) -> None:
        with contextlib.suppress(BlockingIOError, OSError):
            self._wake_w.send(b"x")

    # -- the link's thread -----------------------------------------------------------------------------

    def _serve(self) -> None:
        selector = self._selector
        selector.register(self._listener, selectors.EVENT_READ, "listen")
        selector.register(self._wake_r, selectors.EVENT_READ, "wake")
        while not self._stopping:
            # Streaming: flush often; idle: sleep long (set before looking, see _write).
            self._streaming = time.monotonic() - self._queued < _STREAMING
            if not self._streaming and any(p.out for p in self._attached):
                self._streaming = True
            for key, events in selector.select(_FLUSH if self._streaming else _POLL):
                if key.data == "listen":
                    self._accept()
                elif key.data == "wake":
                    with contextlib.suppress(BlockingIOError, OSError):
                        self._wake_r.recv(4096)
                else:
                    peer: _Peer = key.data
                    if events & selectors.EVENT_READ:
                        self._read(peer)
                    if events & selectors.EVENT_WRITE and not peer.closed:
                        self._flush(peer)
            for peer in self._attached:  # the ticks queued since the last look
                if peer.out and not peer.closed:
                    self._flush(peer)
            self._timers()
            self._watch_writes()
        deadline = time.monotonic() + 2.0
        for peer in list(self._peers.values()):
            self._drain(peer, deadline)
            self._close(peer, "the host stops")
        selector.close()
        self._listener.close()

    def _accept(self) -> None:
        while True:
            try:
                sock, _ = self._listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                return
            sock.setblocking(False)
            with contextlib.suppress(OSError):
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self._numbers += 1
            peer = _Peer(sock, f"p{self._numbers}", time.monotonic())
            if len(self._peers) >= MAX_PEERS:
                self._refuse(peer, f"{self.name} serves {MAX_PEERS} studios at most")
                continue
            peer.heard = peer.said = peer.opened
            self._peers[peer.name] = peer
            self._selector.register(sock, selectors.EVENT_READ, peer)

    def _refuse(self, peer: _Peer, reason: str) -> None:
        with contextlib.suppress(OSError):
            peer.sock.setblocking(True)
            peer.sock.settimeout(1.0)
            peer.sock.sendall(encode_from_host(Refused(reason)))
        self._close(peer, None)

    def _read(self, peer: _Peer) -> None:
        try:
            data = peer.sock.recv(1 << 16)
        except (BlockingIOError, InterruptedError):
            return
        except OSError:
            data = b""
        if not data:
            self._close(peer, "the studio closed the connection")
            return
        peer.heard = time.monotonic()
        try:
            messages = peer.reader.feed(data)
            for raw in messages:
                if peer.closed:
                    return
                self._receive(peer, decode_from_studio(raw))
        except WireError as error:
            if not peer.attached:
                self._refuse(peer, f"not the attach protocol: {error}")
            else:
                self._write(peer, encode_from_host(WorkerReply(None, False, None, f"protocol error: {error}")))
                self._close(peer, f"protocol error: {error}")

    def _receive(self, peer: _Peer, message: Any) -> None:
        if not peer.attached:
            if not isinstance(message, Attach):
                self._refuse(peer, "attach first")
                return
            self._attach(peer, message)
            return
        if isinstance(message, Heartbeat | Attach):
            return
        if isinstance(message, Control):
            with self._lock:
                if message.take and self._holder is None:
                    self._holder = peer
                elif not message.take and self._holder is peer:
                    self._holder = None
                self._announce_control()
            return
        if peer.queued >= MAX_QUEUED_REQUESTS:
            self._close(peer, f"more than {MAX_QUEUED_REQUESTS} commands waiting")
            return
        peer.queued += 1
        self._inbox.append((peer, message))
        self._wakeup.set()

    def _attach(self, peer: _Peer, hello: Attach) -> None:
        if hello.protocol != PROTOCOL:
            self._refuse(peer, f"this host speaks attach protocol {PROTOCOL}, the studio {hello.protocol}")
            return
        if self.token is not None and not token_matches([hello.token or ""], self.token):
            self._refuse(peer, "a valid token is required (xabsl attach HOST:PORT --token TOKEN)")
            return
        peer.studio = hello.studio
        engines = self.engines
        capabilities = {"pause": engines.pausable, "step": engines.pausable, "reload": True, "reset": True}
        with self._lock:
            if hello.control and self._holder is None:
                self._holder = peer
            welcome = Welcome(self.name, tuple(engines.names), capabilities, peer.name, self._holder_info(), PROTOCOL)
            # The last tick only when no tick ran since (it is the state the studio looks at).
            last = self._last_sample if self._last_seq == engines.seq else None
            initial = encode_from_host(welcome) + self._generation + (last or b"")
            self._write(peer, initial)
            peer.attached = True
            self._attached = (*self._attached, peer)
            self._announce_control()
        log.info("studio %s attached (%s)", hello.studio, peer.name)

    def _holder_info(self) -> dict[str, str] | None:
        holder = self._holder
        return {"studio": holder.studio, "peer": holder.name} if holder is not None else None

    def _announce_control(self) -> None:
        """Tell every attached studio who holds control (called with ``_lock`` held)."""
        data = encode_from_host(Control(holder=self._holder_info()))
        for peer in self._attached:
            self._write(peer, data)

    def _flush(self, peer: _Peer) -> None:
        """Send what waits for ``peer``, outside its lock (the program's thread queues meanwhile)."""
        while True:
            with peer.lock:
                if not peer.out or peer.closed or peer.sending:
                    return
                chunk, peer.out = peer.out, bytearray()
                peer.sending = True
            try:
                written = peer.sock.send(chunk)
            except BlockingIOError:
                written = 0
            except OSError:
                written = -1  # closed: the read side notices and drops the peer
            with peer.lock:
                peer.sending = False
                if written < 0:
                    return
                if written:
                    peer.said = time.monotonic()
                    peer.blocked = False
                if written < len(chunk):
                    peer.out[:0] = memoryview(chunk)[written:]
                    return

    def _drain(self, peer: _Peer, deadline: float) -> None:
        """Push what still waits for ``peer`` (stopping: its last ticks must arrive too), until ``deadline``."""
        with peer.lock, contextlib.suppress(OSError):
            while peer.out and time.monotonic() < deadline:
                peer.sock.settimeout(max(0.01, deadline - time.monotonic()))
                written = peer.sock.send(peer.out)
                del peer.out[:written]

    def _watch_writes(self) -> None:
        for peer in list(self._peers.values()):
            if peer.closed:
                continue
            wanted = selectors.EVENT_READ | (selectors.EVENT_WRITE if peer.out else 0)
            with contextlib.suppress(KeyError, ValueError):
                if self._selector.get_key(peer.sock).events != wanted:
                    self._selector.modify(peer.sock, wanted, peer)

    def _timers(self) -> None:
        now = time.monotonic()
        for peer in list(self._peers.values()):
            if not peer.attached:
                if now - peer.opened > HANDSHAKE_TIMEOUT:
                    self._refuse(peer, "no attach message in time")
                continue
            if now - peer.heard > HEARTBEAT_TIMEOUT:
                self._close(peer, f"no word from the studio for {HEARTBEAT_TIMEOUT:g} s")
                continue
            if now - peer.said > HEARTBEAT_SECONDS and not peer.out:
                self._write(peer, encode_from_host(Heartbeat()))

    def _close(self, peer: _Peer, why: str | None) -> None:
        with peer.lock:
            if peer.closed:
                return
            peer.closed = True
        with contextlib.suppress(KeyError, ValueError):
            self._selector.unregister(peer.sock)
        with contextlib.suppress(OSError):
            peer.sock.close()
        self._peers.pop(peer.name, None)
        if peer.attached:
            with self._lock:
                self._attached = tuple(p for p in self._attached if p is not peer)
                if self._holder is peer:
                    self._holder = None
                self._announce_control()
            self._gone.append(peer)
            self._wakeup.set()
            log.info("studio %s detached (%s): %s", peer.studio, peer.name, why)

    # -- lifetime ------------------------------------------------------------------------------------

    def stats(self) -> dict[str, Any]:
        """Ticks published and, per attached studio, messages sent, ticks dropped, bytes waiting."""
        return {
            "ticks": self.ticks,
            "studios": [
                {"peer": p.name, "studio": p.studio, "sent": p.sent, "dropped": p.dropped, "backlog": len(p.out)}
                for p in self._attached
            ],
            "control": self._holder_info(),
        }

    def close(self) -> None:
        """Stop serving: every studio is detached (its forces released at the next publish)."""
        self._stopping = True
        self._wakeup.set()
        self._wake()
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout=5.0)
        self._wake_r.close()
        self._wake_w.close()

    def __enter__(self) -> HostLink:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _sources(program: Program) -> dict[str, Any] | None:
    """The program's source files read now (studios record them, so that a fork can run them again).

    ``Program.files`` names them as the compiler did (relative to the working directory then),
    the agents file last; a program read from intermediate code names none. None: not readable.
    """
    if not program.files:
        return None
    try:
        return program_sources(program.files[-1], program.files)
    except (OSError, ValueError):
        return None


def _family(host: str) -> socket.AddressFamily:
    return socket.AF_INET6 if ":" in host else socket.AF_INET


def serve_engines(
    engines: Mapping[str, Engine],
    port: int = DEFAULT_PORT,
    host: str = "127.0.0.1",
    token: str | None = None,
    *,
    name: str | None = None,
    keys: Mapping[str, str] | None = None,
    pausable: bool = False,
    backlog_bytes: int = MAX_BACKLOG,
) -> HostLink:
    """Expose ``engines`` (robot name -> loaded engine) to studios on ``host:port``; call ``publish`` per tick.

    Args:
        engines: the robots of this program and their engines, in the order studios list them.
        port: the TCP port (0: a free one, see :attr:`HostLink.port`).
        host: the address to bind: loopback unless told otherwise; off loopback a token is
            required (one is generated and printed when none is given).
        token: what studios must present (``xabsl attach HOST:PORT --token TOKEN``).
        name: how studios show this host (default: the machine's name and the process id).
        keys: robot name -> behavior set name (default ``behavior``, then ``behavior2``...).
        pausable: let studios pause and step this program (``publish`` waits while paused).
        backlog_bytes: bytes that may wait for a studio that reads too slowly; past them its
            ticks are dropped (and counted) rather than the program waiting.

    Raises:
        TokenError: an empty token, or a short one off loopback.
        OSError: the port cannot be bound.
    """
    label = name or f"{socket.gethostname()}:{os.getpid()}"
    return HostLink(HostEngines(engines, keys, pausable), host, port, token, label, backlog_bytes)
