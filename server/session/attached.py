"""An attached session: the live session's ring, frames, generations and commands, on hosts elsewhere.

``xabsl attach HOST:PORT ...`` serves an :class:`AttachedSession` exactly as ``xabsl serve``
serves a :class:`~xabsl_studio.server.session.live.Session` (it is one): only the simulation
process and its pipe are replaced, by one :class:`HostConnection` per host (a program that runs
its own engines through ``xabsl_studio.attach``; docs/attach.md), speaking the JSON wire of
``xabsl_studio.server.protocol.attach``.

* **robots**: the session lists the robots of every host in the order the hosts were named;
  global robot ids map to (host, the host's own robot id) for every command;
* **ticks**: every sample a host sends becomes one tick of the session (its own ``seq`` and
  clock, ms since the session started), carrying that host's robots as sampled and the other
  hosts' robots as they last were; none is skipped (a gap in a host's seqs is counted and shown);
* **generations**: a host's new generation (start, reload, reset) or a host coming or going
  makes a new session generation; robots of a host that went away stay listed, marked gone,
  with unknown values, and the host is reconnected until it answers again;
* **hot reload**: the studio compiles (``--behavior PATH``) and sends the intermediate code;
  each host answers with what it did;
* **control**: whether this studio holds each host's control (who does, else) is in the
  status, so the studio can show it.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
import os
import socket
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import orjson

from xabsl_studio.engine.emit.ic import emit_ic
from xabsl_studio.engine.host import BehaviorSource, World
from xabsl_studio.engine.ir.ic_reader import read_ic
from xabsl_studio.engine.ir.model import Enumeration, Program
from xabsl_studio.engine.lang import Compilation
from xabsl_studio.engine.runtime.debug import ReadValues, decision_reads, explain_decision, render
from xabsl_studio.server.protocol.attach import (
    HEARTBEAT_SECONDS,
    HEARTBEAT_TIMEOUT,
    MAX_HOST_MESSAGE,
    PROTOCOL,
    Attach,
    Control,
    Heartbeat,
    HostGeneration,
    Refused,
    Welcome,
    WireError,
    decode_from_host,
    encode_attach,
    encode_from_studio,
)
from xabsl_studio.server.protocol.commands import AttachHost, Explain, Pause, Reset, Resume, RobotCommand, Status, Step
from xabsl_studio.server.protocol.display import SampleDisplay
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
from xabsl_studio.server.protocol.types import HelloReason, WireValue
from xabsl_studio.server.session.live import RING_SECONDS, CommandError, ProgramState, Session
from xabsl_studio.server.simulation.explain import explanation_result, source_texts, tree_result

__all__ = ["AttachedExample", "AttachedSession", "HostConnection", "parse_address"]

log = logging.getLogger("xabsl.server")

#: Seconds between two tries to reach a host that is not there (doubling up to the second value).
RECONNECT_SECONDS = (0.5, 5.0)
#: Seconds ``start`` waits for the named hosts before serving without those still missing.
START_WAIT = 10.0
#: Seconds ``attach_host`` waits for the new host before answering (it keeps trying after).
CONNECT_WAIT = 5.0
#: Hosts one session attaches at most.
MAX_HOSTS = 64


async def _read_within(reader: asyncio.StreamReader, size: int, seconds: float) -> bytes:
    """``size`` bytes, or TimeoutError when the host said nothing for ``seconds``.

    After the loop itself stood still (a long compile, a page loading) the deadline has passed
    although the host's bytes wait in the socket: one short second try reads them, so only a
    host that is really silent counts as gone.
    """
    try:
        async with asyncio.timeout(seconds):
            return await reader.readexactly(size)
    except TimeoutError:
        async with asyncio.timeout(0.5):
            return await reader.readexactly(size)


def _explainers(message: HostGeneration) -> tuple[dict[str, HostProgram], tuple[HostProgram | None, ...]]:
    """A host generation's programs by key and, per robot, the one its engine runs (None: no engine)."""
    structure = orjson.loads(message.generation.structure)
    programs: dict[str, HostProgram] = {}
    for key, ic in message.ics.items():
        programs[key] = HostProgram.of(ic, structure["programs"].get(key), message.generation.enums.get(key, {}))
    return programs, tuple(
        programs.get(robot["program"]) if robot.get("engine") and robot.get("program") else None
        for robot in structure["robots"]
    )


def parse_address(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (``[::1]:7410`` for IPv6) -> (host, port).

    Raises:
        ValueError: not an address with a port in 1..65535.
    """
    host, sep, port = text.rpartition(":")
    host = host.strip("[]")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ValueError(f"{text!r} is not HOST:PORT")
    return host, int(port)


@dataclass(slots=True)
class AttachedExample:
    """What ``Session`` needs of an example, for hosts that bring their own world and engines."""

    name: str
    root: Path
    sources: Sequence[BehaviorSource] = ()
    preload: Sequence[str] = ()
    behavior_hz: int = 100
    physics_hz: int = 100

    def build_world(self, seed: int) -> World:
        """Never called: an attached session has no world of its own."""
        raise CommandError("an attached session runs no world of its own")

    def program_key(self, agent: Any) -> str | None:
        """No robot of its own."""
        return None

    def make_controller(self, agent: Any, program: Any) -> Any:
        """Never called: the hosts own their engines."""
        raise CommandError("an attached session makes no controllers")


@dataclass(frozen=True, slots=True)
class HostProgram:
    """What a host runs for one behavior set, as the studio explains its decisions from the reads.

    ``program`` is read back from the host's intermediate code (None: the studio cannot read it);
    reads name symbols by the host's ids, which its description gives by name.
    """

    program: Program | None
    input_ids: dict[str, int]
    output_ids: dict[str, int]
    #: enum name -> host value -> qualified element (the raw enum values of reads)
    enums: dict[str, dict[int, str]]
    #: option id -> the option's description (its conditions' source texts)
    options: dict[int, dict[str, Any]]

    #: the program with its symbols in the host's order (the order of its samples' values): what
    #: recordings are written with (None: the IC does not read, or lacks symbols the host samples)
    recorded: Program | None = None

    @classmethod
    def of(cls, ic: str, description: dict[str, Any] | None, enums: dict[str, dict[int, str]]) -> HostProgram:
        """The host program of a generation's IC and description (read once per host generation)."""
        try:
            program: Program | None = read_ic(ic)
        except Exception:  # a host's IC the studio cannot read: "why" is unknown, the rest works
            program = None
        described = description or {}
        inputs = {str(x["name"]): int(x["id"]) for x in described.get("inputs", ()) if isinstance(x, dict)}
        outputs = {str(x["name"]): int(x["id"]) for x in described.get("outputs", ()) if isinstance(x, dict)}
        return cls(
            program,
            inputs,
            outputs,
            enums,
            {int(o["id"]): o for o in described.get("options", ()) if isinstance(o, dict)},
            _in_host_order(program, inputs, outputs, described.get("enums", ())) if program is not None else None,
        )


def _in_host_order(
    program: Program, inputs: dict[str, int], outputs: dict[str, int], enums: Sequence[Any]
) -> Program | None:
    """``program`` (read from IC) with the host's symbol order and the host's whole enumerations.

    A host samples its symbols in its own program's order, and enum values as indices into its
    enumerations' elements; the IC lists symbols in the order they are used and keeps only the
    elements something uses, so tables built from it would put values under other names. None
    when the names differ (nothing to align).
    """
    if set(program.inputs) != set(inputs) or set(program.outputs) != set(outputs):
        return None
    whole = dict(program.enums)
    for enum in enums:
        if isinstance(enum, dict) and isinstance(enum.get("name"), str) and isinstance(enum.get("elements"), list):
            name = enum["name"]
            known = whole.get(name) or Enumeration(name, ())
            whole[name] = dataclasses.replace(known, elements=tuple(str(e) for e in enum["elements"]))
    return dataclasses.replace(
        program,
        inputs={name: program.inputs[name] for name in sorted(inputs, key=inputs.__getitem__)},
        outputs={name: program.outputs[name] for name in sorted(outputs, key=outputs.__getitem__)},
        enums=whole,
    )


@dataclass(eq=False)
class HostConnection:
    """One host: its address, what it said last, its robots' place in the session."""

    host: str
    port: int
    label: str
    welcome: Welcome | None = None
    generation: HostGeneration | None = None
    #: the host's last sample, with display values
    last: Sample | None = None
    #: turns the host's raw samples into display values (None: they come with them, a NaoTH robot)
    display: SampleDisplay | None = None
    connected: bool = False
    #: the host was reached once and is gone now (its robots stay, marked)
    gone: bool = False
    refused: str | None = None
    control: dict[str, str] | None = None
    peer: str | None = None
    #: seqs of this host: received, missed (gaps), the last
    received: int = 0
    missed: int = 0
    seq: int = -1
    writer: asyncio.StreamWriter | None = None
    heard: float = 0.0
    pending: dict[int, asyncio.Future[tuple[bool, Any, str | None]]] = field(default_factory=dict)
    task: asyncio.Task[None] | None = None
    #: where this host's robots start among the session's
    offset: int = 0
    robots: tuple[str, ...] = ()
    #: per robot of the host's generation: what its engine runs (None: no engine)
    explainers: tuple[HostProgram | None, ...] = ()
    #: per behavior key of the host: what it runs
    programs: dict[str, HostProgram] = field(default_factory=dict)
    #: the token this host requires (None: the session's)
    token: str | None = None

    def info(self, me: str | None) -> dict[str, Any]:
        """The host as the status shows it."""
        holder = self.control
        return {
            "address": f"{self.host}:{self.port}",
            "name": self.welcome.host if self.welcome is not None else self.label,
            "connected": self.connected,
            "gone": self.gone,
            "refused": self.refused,
            "robots": list(self.robots),
            "control": holder,
            "controlled_here": holder is not None and holder.get("peer") == me,
            "capabilities": self.welcome.capabilities if self.welcome is not None else {},
            "received": self.received,
            "missed": self.missed,
            "seq": self.seq,
        }


class AttachedSession(Session):
    """A studio session on running hosts (see the module docstring).

    Args:
        addresses: ``(host, port)`` of each host, in the order their robots are listed.
        example: the behavior sets compiled here (``--behavior``), or none.
        token: the hosts' token.
        studio: how hosts show this studio.
        control: ask each host for control when attaching (else watch until a command takes it).
        allow_connect: let the studio's users attach more hosts (``attach_host``, Connect…).
    """

    def __init__(
        self,
        addresses: Sequence[tuple[str, int]],
        example: AttachedExample,
        token: str | None = None,
        studio: str | None = None,
        control: bool = True,
        ring_seconds: float = RING_SECONDS,
        state_dir: Path | None = None,
        allow_connect: bool = True,
    ) -> None:
        super().__init__(example, behavior_hz=example.behavior_hz, ring_seconds=ring_seconds, state_dir=state_dir)
        self.hosts = [HostConnection(h, p, f"{h}:{p}") for h, p in addresses]
        self.allow_connect = allow_connect
        self.token = token
        self.studio = studio or f"studio@{socket.gethostname()}:{os.getpid()}"
        self.want_control = control
        self._seq = 0
        self._generation_number = 0
        self._t0 = time.monotonic()
        self._t = 0
        #: per session generation: per robot, the program its host ran (explain of any tick in the ring)
        self._explainers: dict[int, tuple[HostProgram | None, ...]] = {}
        self._closing = False

    # -- lifetime ---------------------------------------------------------------------------------------

    @property
    def running(self) -> bool:
        """Whether any host is attached now."""
        return any(h.connected for h in self.hosts)

    async def start(self) -> None:
        """Connect to every host; returns once each answered or :data:`START_WAIT` passed."""
        self._loop = asyncio.get_running_loop()
        self._restart_lock = asyncio.Lock()
        self._started = self._loop.create_future()
        for host in self.hosts:
            host.task = asyncio.create_task(self._run_host(host))
        deadline = time.monotonic() + START_WAIT
        while time.monotonic() < deadline and not all(h.generation or h.refused for h in self.hosts):
            await asyncio.sleep(0.05)
        if self.generation is None:
            self._publish_generation("connect")

    async def aclose(self) -> None:
        """Detach from every host (forces and overrides of this studio are released there)."""
        self._closing = True
        for host in self.hosts:
            if host.task is not None:
                host.task.cancel()
                with contextlib.suppress(asyncio.CancelledError, Exception):
                    await host.task
        if self.live_recorder is not None:
            self.live_recorder.close()

    def stop(self) -> None:
        """Nothing runs in another process of the studio's."""
        self._stopping = True

    # -- one host ---------------------------------------------------------------------------------------

    async def _run_host(self, host: HostConnection) -> None:
        delay = RECONNECT_SECONDS[0]
        while not self._closing:
            try:
                await self._attach(host)
                delay = RECONNECT_SECONDS[0]
            except asyncio.CancelledError:
                raise
            except (OSError, WireError, asyncio.IncompleteReadError, TimeoutError) as error:
                if host.connected or host.generation is not None:
                    log.warning("host %s: %s", host.label, error)
            finally:
                self._lost(host)
            if host.refused is not None and "token" in host.refused:
                return  # a wrong token stays wrong: say so, do not hammer the host
            await asyncio.sleep(delay)
            delay = min(delay * 2, RECONNECT_SECONDS[1])

    async def _attach(self, host: HostConnection) -> None:
        # asyncio.timeout, not wait_for: on Python 3.11 wait_for swallows a cancellation that
        # arrives as the read completes (a host sends 100 times a second), and aclose would hang.
        async with asyncio.timeout(5.0):
            reader, writer = await asyncio.open_connection(host.host, host.port)
        host.writer = writer
        token = host.token if host.token is not None else self.token
        writer.write(encode_attach(Attach(token, self.studio, self.want_control, PROTOCOL)))
        await writer.drain()
        beat = asyncio.create_task(self._heartbeat(host, writer))
        try:
            while not self._closing:
                header = await _read_within(reader, 4, HEARTBEAT_TIMEOUT)
                size = int.from_bytes(header, "big")
                if size > MAX_HOST_MESSAGE:
                    raise WireError(f"the host sent a message of {size} bytes")
                async with asyncio.timeout(HEARTBEAT_TIMEOUT + 30.0):
                    data = await reader.readexactly(size)
                host.heard = time.monotonic()
                self._from_host(host, decode_from_host(data))
        finally:
            beat.cancel()
            writer.close()
            with contextlib.suppress(Exception):
                await writer.wait_closed()

    async def _heartbeat(self, host: HostConnection, writer: asyncio.StreamWriter) -> None:
        data = encode_from_studio(Heartbeat())
        while True:
            await asyncio.sleep(HEARTBEAT_SECONDS)
            writer.write(data)

    def _lost(self, host: HostConnection) -> None:
        was = host.connected
        host.connected = False
        host.writer = None
        for future in host.pending.values():
            if not future.done():
                future.set_exception(CommandError(f"host {host.label} went away"))
        host.pending.clear()
        if was:
            host.gone = True
            host.last = None
            if not self._closing:
                self._publish_generation("host_gone")

    def _from_host(self, host: HostConnection, message: Any) -> None:
        if isinstance(message, Sample):
            if host.generation is None or message.gen != host.generation.generation.number:
                return
            if host.seq >= 0 and message.seq > host.seq + 1:
                host.missed += message.seq - host.seq - 1
                log.warning("host %s: ticks %d..%d did not arrive", host.label, host.seq + 1, message.seq - 1)
            host.seq = message.seq
            host.received += 1
            # Converted here, per host: the session's robots may come from hosts of both kinds.
            host.last = host.display.convert(message) if host.display is not None else message
            self._tick(host)
        elif isinstance(message, HostGeneration):
            first = host.generation is None or not host.connected
            back = host.gone
            host.generation = message
            host.connected, host.gone = True, False
            host.last = None
            gen = message.generation
            host.display = (
                SampleDisplay(orjson.loads(gen.structure), gen.enums, gen.input_ids, gen.output_ids)
                if gen.raw_values
                else None
            )
            host.programs, host.explainers = _explainers(message)
            self._adopt_programs(host, message)
            reason: HelloReason = "reset" if first or message.generation.reason == "reset" else "reload"
            if back:
                reason = "host_back"  # the timeline marks where a host came back
            self._publish_generation("connect" if self._generation_number == 0 else reason)
        elif isinstance(message, WorkerReply):
            future = host.pending.pop(message.ident, None) if message.ident is not None else None
            if future is not None and not future.done():
                future.set_result((message.ok, message.result, message.error))
        elif isinstance(message, Hit):
            self.receive([dataclasses.replace(message, robot=message.robot + host.offset, seq=self._seq)])
        elif isinstance(message, Control):
            host.control = message.holder
        elif isinstance(message, Welcome):
            host.welcome, host.peer, host.control, host.refused = message, message.peer, message.control, None
            host.robots = message.robots
        elif isinstance(message, Refused):
            host.refused = message.reason
            log.error("host %s refused this studio: %s", host.label, message.reason)
            raise OSError(f"refused: {message.reason}")

    def _adopt_programs(self, host: HostConnection, message: HostGeneration) -> None:
        """Programs the studio does not compile itself are the host's (read back from its IC)."""
        described = orjson.loads(message.generation.structure)["programs"]
        for key, ic in message.ics.items():
            mine = self._key(key)
            state = self.programs.get(mine)
            if state is not None and state.source.agents_file.is_file():
                continue
            try:
                program = read_ic(ic)
            except Exception:  # a host's IC the studio cannot read: it shows the description alone
                program = None
            if state is None:
                folder = Path(f"{host.label} (on the host)")
                state = self.programs[mine] = ProgramState(BehaviorSource(mine, folder, folder / key, ()))
                self.breakpoints.setdefault(mine, {})
            state.running = program
            state.running_json = described.get(key)

    def _key(self, host_key: str) -> str:
        """The session's name of a host's behavior set: the studio's one when it compiles a single one."""
        compiled = [k for k, s in self.programs.items() if s.source.agents_file.is_file()]
        if host_key in compiled:
            return host_key
        return compiled[0] if len(compiled) == 1 else host_key

    # -- the session's generations and ticks ----------------------------------------------------------

    def _publish_generation(self, reason: HelloReason) -> None:
        programs: dict[str, Any] = {}
        robots: list[dict[str, Any]] = []
        input_ids: list[tuple[int, ...]] = []
        output_ids: list[tuple[int, ...]] = []
        errors: dict[str, str | None] = {}
        enums: dict[str, dict[str, dict[int, str]]] = {}
        explainers: list[HostProgram | None] = []
        recorded: dict[str, Program] = {}
        sources: dict[str, dict[str, Any]] = {}
        self._generation_number += 1
        for host in self.hosts:
            host.offset = len(robots)
            gen = host.generation
            if gen is None:
                continue
            explainers.extend(host.explainers)
            structure = orjson.loads(gen.generation.structure)
            for key, description in structure["programs"].items():
                programs.setdefault(self._key(key), description)
            for key, error in gen.generation.errors.items():
                errors[self._key(key)] = error
            for key, tables in gen.generation.enums.items():
                enums.setdefault(self._key(key), tables)
            for key, running in host.programs.items():
                # Recordings are written with what the hosts run, in their symbol order.
                if running.recorded is not None:
                    recorded.setdefault(self._key(key), running.recorded)
                if key in gen.sources:
                    sources.setdefault(self._key(key), gen.sources[key])
            for robot, ins, outs in zip(
                structure["robots"], gen.generation.input_ids, gen.generation.output_ids, strict=True
            ):
                name = robot["name"] if len(self.hosts) == 1 else f"{robot['name']}"
                program = robot.get("program")
                robots.append(
                    {
                        "id": len(robots),
                        "name": name,
                        "team": robot.get("team"),
                        "number": robot.get("number"),
                        "program": self._key(program) if program is not None else None,
                        "engine": bool(robot.get("engine")) and not host.gone,
                        "host": host.info(None)["name"],
                        "gone": host.gone,
                    }
                )
                input_ids.append(tuple(ins))
                output_ids.append(tuple(outs))
        self._explainers[self._generation_number] = tuple(explainers)
        for old in [n for n in self._explainers if n <= self._generation_number - 16]:
            del self._explainers[old]
        structure = {"programs": programs, "robots": robots}
        scene = {"attached": [h.info(None) for h in self.hosts]}
        message = NewGeneration(
            self._generation_number,
            reason,
            orjson.dumps(structure),
            orjson.dumps(scene),
            tuple(input_ids),
            tuple(output_ids),
            0,
            errors,
            enums=enums,  # the hosts' samples have display values already (see _from_host)
        )
        if self.live_recorder is not None:
            self.live_recorder.sources.update(sources)
        self._incoming.update(recorded)
        try:
            self.receive([message])
        finally:
            for key in recorded:
                self._incoming.pop(key, None)
        self._tick(None)

    def _tick(self, source: HostConnection | None) -> None:
        """One session tick: ``source``'s new sample, every other host's robots as they last were."""
        gen = self.generation
        if gen is None:
            return
        paths: list[bytes] = []
        extras: list[bytes] = []
        inputs: list[tuple[WireValue, ...]] = []
        outputs: list[tuple[WireValue, ...]] = []
        reads: list[bytes] = []
        paused = False
        for host in self.hosts:
            if host.generation is None:
                continue
            count = len(host.generation.generation.input_ids)
            last = host.last
            if last is None or len(last.paths) != count:
                for i in range(count):
                    at = host.offset + i
                    paths.append(b"[]")
                    extras.append(b"")
                    inputs.append((None,) * len(gen.input_ids[at]) if at < len(gen.input_ids) else ())
                    outputs.append((None,) * len(gen.output_ids[at]) if at < len(gen.output_ids) else ())
                    reads.append(b"")
                continue
            paused = paused or last.paused
            paths.extend(last.paths)
            extras.extend(last.extras)
            inputs.extend(last.inputs)
            outputs.extend(last.outputs)
            # What each decision read in the host's tick, as the host's engine recorded it (b"": unknown).
            reads.extend(last.reads if len(last.reads) == count else (b"",) * count)
        if len(paths) != len(gen.input_ids) or not paths:
            return  # a host changed its robots (its new generation follows), or none is known yet
        self._seq += 1
        self._t = max(self._t, round((time.monotonic() - self._t0) * 1000))
        status = {"attached": [h.info(h.peer) for h in self.hosts], "connect": self.allow_connect}
        sample = Sample(
            self._seq,
            gen.number,
            self._t,
            time.time() * 1000.0,
            paused,
            1.0,
            tuple(paths),
            tuple(extras),
            tuple(inputs),
            tuple(outputs),
            b"{}",
            orjson.dumps(status),
            tuple(reads),
        )
        self.receive([sample])
        if self._started is not None and not self._started.done():
            self._started.set_result(None)

    # -- commands ---------------------------------------------------------------------------------------

    async def _send(self, command: WorkerCommand, owner: str | None) -> tuple[bool, Any, str | None]:
        """Route a command to the host of its robot, or to every host (pause, resume, step, reset, status)."""
        robot = getattr(command, "robot", None)
        if isinstance(command, ExplainRecorded):
            return True, self._explain_recorded(command), None
        if robot is not None and isinstance(command, RobotCommand):
            host, local = self._host_of(robot)
            return await self._ask(host, dataclasses.replace(command, robot=local), owner)
        if isinstance(command, Pause | Resume | Step | Reset | Status | ReleaseOwner):
            return await self._everywhere(command, owner)
        if isinstance(command, SetBreakpoints):
            return await self._breakpoints(command)
        raise CommandError(f"an attached session does not carry out {command.op!r}")

    def _host_of(self, robot: int) -> tuple[HostConnection, int]:
        for host in self.hosts:
            if host.generation is not None and host.offset <= robot < host.offset + len(
                host.generation.generation.input_ids
            ):
                if not host.connected:
                    raise CommandError(f"robot {robot} is on host {host.label}, which is gone (it reattaches)")
                return host, robot - host.offset
        raise CommandError(f"robot must be a robot id of an attached host (0..{self._robot_count() - 1})")

    def _robot_count(self) -> int:
        gen = self.generation
        return len(gen.input_ids) if gen is not None else 0

    async def _ask(
        self, host: HostConnection, command: WorkerCommand, owner: str | None
    ) -> tuple[bool, Any, str | None]:
        writer, loop = host.writer, self._loop
        if writer is None or loop is None or not host.connected:
            raise CommandError(f"host {host.label} is not attached")
        ident = next(self._ids)
        future: asyncio.Future[tuple[bool, Any, str | None]] = loop.create_future()
        host.pending[ident] = future
        writer.write(encode_from_studio(WorkerRequest(ident, command, owner)))
        return await future

    async def _everywhere(self, command: WorkerCommand, owner: str | None) -> tuple[bool, Any, str | None]:
        attached = [h for h in self.hosts if h.connected]
        if not attached:
            raise CommandError("no host is attached (they reattach when they come back)")
        answers = await asyncio.gather(*(self._ask(h, command, owner) for h in attached), return_exceptions=True)
        results: list[Any] = []
        problems: list[str] = []
        for host, answer in zip(attached, answers, strict=True):
            if isinstance(answer, BaseException):
                problems.append(f"{host.label}: {answer}")
                continue
            ok, result, error = answer
            results.append(result)
            if not ok:
                problems.append(f"{host.label}: {error}")
        if problems:
            return False, None, "; ".join(problems)
        return True, results[0], None

    async def _breakpoints(self, command: SetBreakpoints) -> tuple[bool, Any, str | None]:
        for host in self.hosts:
            if not host.connected or host.generation is None:
                continue
            count = len(host.generation.generation.input_ids)
            for key in host.generation.ics:
                if self._key(key) != command.key:
                    continue
                points = tuple(
                    dataclasses.replace(p, robot=None if p.robot is None else p.robot - host.offset)
                    for p in command.points
                    if p.robot is None or host.offset <= p.robot < host.offset + count
                )
                ok, _, error = await self._ask(host, SetBreakpoints(key, points), None)
                if not ok:
                    return ok, None, error
        return True, None, None

    def release_owner(self, owner: str) -> None:
        """Release what client ``owner`` forced and overrode on every host (it disconnected)."""
        for host in self.hosts:
            if host.connected and host.writer is not None:
                host.writer.write(encode_from_studio(WorkerRequest(None, ReleaseOwner(), owner)))

    def take_control(self, take: bool = True) -> None:
        """Ask every host for control (or give it back)."""
        for host in self.hosts:
            if host.connected and host.writer is not None:
                host.writer.write(encode_from_studio(Control(take=take)))

    # -- Connect… ----------------------------------------------------------------------------------------

    async def attach_host(self, command: AttachHost) -> dict[str, Any]:
        """Attach one more host (its robots are listed after the others'); the host as the status shows it.

        Answers once the host sent its first generation, refused, or :data:`CONNECT_WAIT` passed
        (it is then retried as any host that is not there).

        Raises:
            CommandError: this studio does not allow it, or the address is not HOST:PORT.
        """
        if not self.allow_connect:
            raise CommandError("this studio does not attach more hosts (xabsl attach --no-connect)")
        try:
            address, port = parse_address(command.address)
        except ValueError as error:
            raise CommandError(str(error)) from None
        host = next((h for h in self.hosts if (h.host, h.port) == (address, port)), None)
        if host is None:
            if len(self.hosts) >= MAX_HOSTS:
                raise CommandError(f"a studio attaches {MAX_HOSTS} hosts at most")
            host = HostConnection(address, port, f"{address}:{port}", token=command.token)
            self.hosts.append(host)
            host.task = asyncio.create_task(self._run_host(host))
        elif host.refused is not None and (host.task is None or host.task.done()):
            host.token, host.refused = command.token, None  # a new token: try again
            host.task = asyncio.create_task(self._run_host(host))
        deadline = time.monotonic() + CONNECT_WAIT
        while time.monotonic() < deadline and not (host.connected or host.refused):
            await asyncio.sleep(0.05)
        return host.info(host.peer)

    # -- why -----------------------------------------------------------------------------------------------

    async def explain(self, command: Explain, owner: str | None) -> Any:
        """``explain``, always from the ring: the live one is the latest tick's, what its decision read.

        The host is never asked again: the values are those the host's engine recorded in that
        tick (``Engine.reads()``, sent with every sample), so "why" works on a host that is gone,
        and a value the decision did not read is unknown (``?``).
        """
        if command.seq is not None:
            return await super().explain(command, owner)
        latest = self.ring.latest
        if latest is None:
            raise CommandError("no tick has arrived from the hosts yet")
        result = await super().explain(dataclasses.replace(command, seq=latest.seq), owner)
        result["recorded"] = False  # the last tick's decision: the live why of the studio
        return result

    def _explain_recorded(self, command: ExplainRecorded) -> list[dict[str, Any]]:
        """Decisions of past ticks explained here, from the reads the ring kept and the host's program."""
        explainers = self._explainers.get(command.generation)
        if explainers is None:
            raise CommandError("that tick is older than the versions of the behavior this studio keeps")
        if not 0 <= command.robot < len(explainers) or explainers[command.robot] is None:
            raise CommandError(f"robot {command.robot} ran no XABSL engine in that tick")
        running = explainers[command.robot]
        assert running is not None
        program = running.program
        if program is None:
            raise CommandError("the host's intermediate code does not read here: its decisions cannot be explained")
        ir_option = program.options.get(command.option)
        if ir_option is None:
            raise CommandError(f"unknown option {command.option!r}")
        results = []
        for seq, t, decided, leaf, _, reads in command.ticks:
            if not 0 <= decided < len(ir_option.states):
                raise CommandError(f"option {ir_option.name} has no state {decided}")
            state = ir_option.states[decided]
            read = decision_reads(orjson.loads(reads), ir_option.index) if reads else None
            values = ReadValues(program, ir_option, read, running.enums, running.input_ids, running.output_ids)
            try:
                explanation = explain_decision(ir_option, state, leaf, values, lambda c: render(c, ir_option.name))
            except KeyError:
                raise CommandError(f"state {ir_option.name}.{state.name} has no leaf {leaf}") from None
            result = explanation_result(ir_option, explanation)
            tree = tree_result(ir_option, state.name, leaf, values)
            described = running.options.get(ir_option.index)
            if described is not None and decided < len(described.get("states", ())):
                source_texts(result, tree, described["states"][decided]["decision"])
            result.update(seq=seq, t=t, recorded=True, tree=tree)
            results.append(result)
        return results

    # -- hot reload ----------------------------------------------------------------------------------------

    async def apply(self, key: str, compilation: Compilation) -> str | None:
        """Compiled clean: send its intermediate code to every host that runs ``key``; what they did."""
        state = self.programs[key]
        state.compilation = compilation
        program = compilation.program
        if program is None:
            return "the behavior has errors; the running version is kept"
        ic = emit_ic(program)
        problems: list[str] = []
        sent = 0
        for host in self.hosts:
            if not host.connected or host.generation is None:
                continue
            for host_key in host.generation.ics:
                if self._key(host_key) != key:
                    continue
                sent += 1
                ok, result, error = await self._ask(host, LoadIntermediateCode(host_key, ic), None)
                if not ok:
                    problems.append(f"{host.label}: {error}")
                elif result is not None:
                    problems.append(f"{host.label}: {result}")
        if problems:
            state.error = "; ".join(problems)
            return state.error
        state.error = None
        # What the hosts run now is the IC read back against the previous version (its symbol
        # order, which their samples follow): the same reading here keeps recordings aligned.
        previous = state.running
        try:
            state.running = read_ic(ic, previous) if previous is not None else program
        except Exception:  # the studio's own IC always reads; keep the compiled program otherwise
            state.running = program
        state.running_sources = compilation.sources
        state.partial = state.partial_json = None
        if not sent:
            return None if self.running else "no host is attached: nothing was reloaded"
        return None

    # -- status --------------------------------------------------------------------------------------------

    async def status(self) -> dict[str, Any]:
        """The live session's status, with each host (attached, gone, control, seqs received and missed)."""
        result = await super().status()
        result["attached"] = [h.info(h.peer) for h in self.hosts]
        result["simulation"] = {"running": self.running, "pid": None, "restarts": 0, "crash": None, "pipe": {}}
        return result
