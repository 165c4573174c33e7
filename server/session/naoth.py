"""A studio session attached to NaoTH robots and simulators over their debug port (docs/naoth.md).

``xabsl attach naoth://HOST[:5401] --behavior AGENTS_FILE`` serves a :class:`NaothSession`: the
attached session of ``xabsl_studio.server.session.attached`` (its ring, frames, generations,
recording, history), with each host a NaoTH robot reached through
``xabsl_studio.server.protocol.naoth`` instead of a program running our attach library:

* **connect**: ``BehaviorStateComplete`` once, joined by name with the studio's compile of the
  same sources (``xabsl_studio.engine.naoth.join``); every difference is named in the host's
  ``refused``/``mismatches`` status and the studio's compile errors, the robot's agents come from
  ``behavior:list_agents``;
* **frames**: ``BehaviorStateSparse`` is asked again as soon as the previous answer came (one
  request in flight: as fast as the robot answers); each answer with a new frame number is one
  tick of the session whose host ``seq`` is the robot's frame number (an answer repeating the
  last frame, the robot's 30 Hz being slower than the questions, is dropped, and the next
  question waits :data:`REPEAT_PAUSE`), so frames the
  robot ran between two answers are counted as missed and show as gaps on the timeline;
* **reload of the behavior on the robot**: this studio's own reload asks no frame between
  ``behavior:reload`` and the new complete message (none is joined with the old tables); a robot
  serves one client at a time, so no other tool reloads while the studio is attached, and the
  complete message's frame number is checked every :data:`COMPLETE_EVERY` seconds all the same;
* **commands**: agent selection (``behavior:set_agent``), hot reload (our compiler's IC written
  with ``file::write`` to ``Config/behavior-ic.dat``, then ``behavior:reload``); forcing,
  overrides, pause, step, reset and breakpoints are refused with the reason (the robot has no
  command for them), and the host's ``capabilities`` say so;
* **heartbeat**: a bare ``-1`` every second;
* **sharing** (``--share PORT``): the robot's one debug slot served to other studios and
  RobotControl through this connection (``xabsl_studio.server.session.naothshare``).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import orjson

from xabsl_studio.engine.emit.ic import emit_ic
from xabsl_studio.engine.emit.json import program_to_json
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.lang import Compilation
from xabsl_studio.engine.naoth import messages as M
from xabsl_studio.engine.naoth.join import BehaviorJoin, JoinedFrame, infer_decisions
from xabsl_studio.engine.types import Value
from xabsl_studio.server.protocol.attach import HostGeneration, Welcome, WireError
from xabsl_studio.server.protocol.commands import SelectAgent, Status
from xabsl_studio.server.protocol.host import (
    NewGeneration,
    ReleaseOwner,
    Sample,
    SetBreakpoints,
    WorkerCommand,
)
from xabsl_studio.server.protocol.naoth import (
    HEARTBEAT,
    HEARTBEAT_SECONDS,
    REPLY_TIMEOUT,
    ReplyReader,
    encode_command,
    next_id,
)
from xabsl_studio.server.session.attached import AttachedExample, AttachedSession, HostConnection
from xabsl_studio.server.session.live import CommandError
from xabsl_studio.server.session.naothshare import SharedSlot

__all__ = ["CAPABILITIES", "COMPLETE_EVERY", "IC_PATH", "NaothHost", "NaothSession"]

log = logging.getLogger("xabsl.server")

#: Where NaoTH reads its behavior's intermediate code (relative to the robot's working folder).
IC_PATH = "Config/behavior-ic.dat"
#: Seconds between two checks whether the robot loaded its behavior again.
COMPLETE_EVERY = 2.0
#: Seconds to wait after an answer that repeated the last frame before asking again: a third of a
#: 30 Hz frame, so a new frame shows within 10 ms and an idle robot is not asked a thousand times
#: a second.
REPEAT_PAUSE = 0.01
#: What a NaoTH robot lets a studio do (its debug port has no command for the others).
CAPABILITIES = {
    "pause": False,
    "step": False,
    "reset": False,
    "force": False,
    "override": False,
    "breakpoints": False,
    "reload": True,
    "select_agent": True,
}
_UNAVAILABLE = (
    "a NaoTH robot cannot {what}: its debug port has no command for it (docs/naoth.md says what a robot "
    "would need); agent selection and upload + reload work"
)
_WHAT = {
    "pause": "pause",
    "resume": "pause or resume",
    "step": "step",
    "reset": "reset",
    "reset_agent": "reset an agent",
    "force_option": "force an option",
    "force_behavior": "force a basic behavior",
    "release": "release a forced option (nothing can be forced)",
    "override_input": "override an input symbol",
    "release_input": "release an override (nothing can be overridden)",
    "explain_recorded": "explain a past decision (it does not send what its decisions read)",
    "world_command": "take world commands",
}
_DECIMALS = 1000.0


@dataclass(eq=False)
class NaothHost(HostConnection):
    """One NaoTH robot: the attached host plus its join, its agents and the commands in flight."""

    join: BehaviorJoin | None = None
    agents: tuple[str, ...] = ()
    agent: str | None = None
    complete_frame: int | None = None
    mismatches: list[str] = field(default_factory=list)
    #: sparse frames whose actions matched nothing in the sources (counted, left out)
    unplaced: int = 0
    inferred: int = 0
    waiting: dict[int, asyncio.Future[bytes]] = field(default_factory=dict)
    next_ident: int = 0
    previous: JoinedFrame | None = None
    number: int = 0
    #: held by the frame loop for each question and by a reload for all of its steps, so no frame
    #: is asked between ``behavior:reload`` and the new tables
    busy: asyncio.Lock = field(default_factory=asyncio.Lock)

    def info(self, me: str | None) -> dict[str, Any]:
        """The host as the status shows it, with what the join found."""
        info = super().info(me)
        info.update(
            kind="naoth",
            agent=self.agent,
            agents=list(self.agents),
            mismatches=list(self.mismatches),
            unplaced=self.unplaced,
            decisions_inferred=self.inferred,
            capabilities=dict(CAPABILITIES),
        )
        return info


class NaothSession(AttachedSession):
    """A studio session on NaoTH robots (see the module docstring).

    Args:
        addresses: ``(host, port)`` of each robot, in the order they are listed.
        example: the behavior sets compiled here (exactly one: the sources the robots run).
    """

    def __init__(
        self,
        addresses: Sequence[tuple[str, int]],
        example: AttachedExample,
        share: int | None = None,
        **options: Any,
    ) -> None:
        super().__init__(addresses, example, **options)
        if share is not None and len(addresses) != 1:
            raise ValueError("--share serves one robot's slot: attach one robot")
        #: the robot's debug slot served to other clients (``--share PORT``), once attached
        self.share: SharedSlot | None = None
        self._share_port = share
        self.hosts = [NaothHost(h, p, f"naoth://{h}:{p}") for h, p in addresses]
        if len(self.programs) != 1:
            raise ValueError("a NaoTH session needs the sources the robots run (--behavior AGENTS_FILE)")
        self.key = next(iter(self.programs))

    async def start(self) -> None:
        """Connect to every robot; serve the shared slot (``--share``) on top."""
        await super().start()
        if self._share_port is not None:
            host = self.hosts[0]
            assert isinstance(host, NaothHost)
            self.share = SharedSlot(lambda name, args: self._forward(host, name, args), self._share_port)
            await self.share.start()
            log.info("the robot's debug port is shared on 127.0.0.1:%d", self.share.port)

    async def aclose(self) -> None:
        """Stop sharing, detach."""
        if self.share is not None:
            await self.share.close()
        await super().aclose()

    async def _forward(self, host: NaothHost, name: str, args: dict[str, bytes]) -> bytes:
        """A shared client's command on the robot (a reload re-reads the tables before the next frame)."""
        if name == "Cognition:behavior:reload":
            async with host.busy:
                answer = await self._command(host, name, dict(args))
                await self._load(host, "reload")
                return answer
        return await self._command(host, name, dict(args))

    def _program(self) -> Program:
        state = self.programs[self.key]
        program = state.running or (state.compilation.program if state.compilation is not None else None)
        if program is None:
            raise CommandError("the behavior does not compile: the robot's frames cannot be joined with it")
        return program

    # -- one robot --------------------------------------------------------------------------------------

    async def _attach(self, host: HostConnection) -> None:
        assert isinstance(host, NaothHost)
        async with asyncio.timeout(5.0):
            reader, writer = await asyncio.open_connection(host.host, host.port)
        host.writer = writer
        tasks = [asyncio.create_task(self._read(host, reader)), asyncio.create_task(self._beat(writer))]
        try:
            await self._load(host, "connect")
            checked = time.monotonic()
            while not self._closing:
                async with host.busy:
                    if time.monotonic() - checked > COMPLETE_EVERY:
                        checked = time.monotonic()
                        complete = await self._command(
                            host, "Cognition:representation:get", {"BehaviorStateComplete": b""}
                        )
                        message = M.parse("BehaviorStateComplete", complete)
                        if message.frameNumber != host.complete_frame:
                            await self._load(host, "reload", message)
                    data = await self._command(host, "Cognition:representation:get", {"BehaviorStateSparse": b""})
                    new = self._sparse(host, M.parse("BehaviorStateSparse", data))
                if not new:
                    await asyncio.sleep(REPEAT_PAUSE)
                if tasks[0].done():
                    tasks[0].result()  # the reader failed: its error ends this connection
        except M.DecodeError as error:
            raise WireError(f"the robot's answer is not a behavior message ({error})") from None
        except CommandError as error:  # the sources do not compile: nothing to join the frames with
            host.refused = str(error)
            raise OSError(str(error)) from None
        finally:
            for task in tasks:
                task.cancel()
            for future in host.waiting.values():
                future.cancel()  # its command's caller sees CancelledError; the connection is gone
            host.waiting.clear()
            writer.close()
            with contextlib.suppress(Exception):
                await writer.wait_closed()

    async def _read(self, host: NaothHost, reader: asyncio.StreamReader) -> None:
        replies = ReplyReader()
        try:
            while True:
                data = await reader.read(1 << 16)
                if not data:
                    raise ConnectionError("the robot closed the connection")
                host.heard = time.monotonic()
                for ident, payload in replies.feed(data):
                    future = host.waiting.pop(ident, None)
                    if future is not None and not future.done():
                        future.set_result(payload)
        except (OSError, WireError) as error:
            # the question waiting for an answer learns at once why none comes
            for future in host.waiting.values():
                if not future.done():
                    future.set_exception(error)
            raise

    async def _beat(self, writer: asyncio.StreamWriter) -> None:
        while True:
            await asyncio.sleep(HEARTBEAT_SECONDS)
            writer.write(HEARTBEAT)

    async def _command(self, host: NaothHost, name: str, args: dict[str, bytes | str] | None = None) -> bytes:
        """Send one command, wait for its answer (TimeoutError after :data:`REPLY_TIMEOUT`)."""
        writer, loop = host.writer, asyncio.get_running_loop()
        if writer is None:
            raise CommandError(f"robot {host.label} is not attached")
        host.next_ident = next_id(host.next_ident)
        ident = host.next_ident
        future: asyncio.Future[bytes] = loop.create_future()
        host.waiting[ident] = future
        writer.write(encode_command(ident, name, args))
        try:
            # asyncio.timeout, not wait_for: on Python 3.11 wait_for swallows a cancellation that
            # arrives as the answer does, and the studio's shutdown then waited on this loop forever
            async with asyncio.timeout(REPLY_TIMEOUT):
                return await future
        finally:
            host.waiting.pop(ident, None)

    async def _load(self, host: NaothHost, reason: str, complete: Any = None) -> None:
        """Read the robot's behavior (complete message, agents), join it, start a host generation."""
        if complete is None:
            data = await self._command(host, "Cognition:representation:get", {"BehaviorStateComplete": b""})
            complete = M.parse("BehaviorStateComplete", data)
        program = self._program()
        host.join = BehaviorJoin(program, complete)
        host.complete_frame = complete.frameNumber if complete.HasField("frameNumber") else None
        host.mismatches = host.join.mismatches
        if host.mismatches:
            log.warning(
                "robot %s runs a behavior other than %s:\n  %s",
                host.label,
                self.key,
                "\n  ".join(host.mismatches[:20]),
            )
        agents = (await self._command(host, "Cognition:behavior:list_agents")).decode("utf-8", "replace")
        host.agents = tuple(a for a in agents.splitlines() if a) or tuple(a for a, _ in host.join.agents)
        host.agent = (await self._command(host, "Cognition:behavior:get_agent")).decode("utf-8", "replace") or None
        host.previous = None  # frame numbers go on across a reload: a gap still counts
        host.number += 1
        name = host.label.removeprefix("naoth://")
        self._from_host(host, Welcome(name, (name,), dict(CAPABILITIES), name, None))
        inputs = tuple(s.index for s in program.inputs.values() if not s.params)
        outputs = tuple(s.index for s in program.outputs.values())
        structure = {
            "programs": {self.key: program_to_json(program)},
            "robots": [{"id": 0, "name": name, "team": None, "number": None, "program": self.key, "engine": True}],
        }
        error = "; ".join(host.mismatches[:5]) if host.mismatches else None
        generation = NewGeneration(
            host.number,
            "reset" if reason == "connect" else "reload",
            orjson.dumps(structure),
            b"{}",
            (inputs,),
            (outputs,),
            0,
            {self.key: f"the robot runs other sources: {error}" if error else None},
        )
        self._from_host(host, HostGeneration(generation, {self.key: emit_ic(program)}))

    def _sparse(self, host: NaothHost, sparse: Any) -> bool:
        """One answer as a session tick; False when it was no new frame (the caller waits a little)."""
        join = host.join
        if join is None or host.generation is None:
            return False
        number = sparse.frameNumber if sparse.HasField("frameNumber") else None
        if number is not None and number == host.seq:
            return False  # the robot has not run a frame since the last answer (it runs at 30 Hz)
        joined = join.frame(sparse)
        seq = number if number is not None else host.seq + 1
        if seq < host.seq:  # the robot restarted (frame numbers start again): its frames go on
            host.seq, host.previous = seq - 1, None
        consecutive = host.previous is not None and seq == host.seq + 1
        previous = host.previous.path if consecutive and host.previous is not None else None
        host.inferred += infer_decisions(join.program, joined.path, previous)
        host.previous = joined
        host.unplaced += joined.unplaced
        if joined.agent is not None:
            host.agent = joined.agent
        extras = b""
        if joined.error:
            extras = b"," + orjson.dumps({"fault": {"message": joined.error, "option": None, "state": None}})[1:-1]
        sample = Sample(
            seq,
            host.generation.generation.number,
            0,
            time.time() * 1000.0,
            False,
            1.0,
            (orjson.dumps(joined.path),),
            (extras,),
            (_display(joined.inputs),),
            (_display(joined.outputs),),
            b"{}",
            b"{}",
        )
        self._from_host(host, sample)
        return True

    # -- commands ---------------------------------------------------------------------------------------

    async def _send(self, command: WorkerCommand, owner: str | None) -> tuple[bool, Any, str | None]:
        """What a NaoTH robot can carry out (agent selection, reload), the reason for the rest."""
        if isinstance(command, SelectAgent):
            host, _ = self._host_of(command.robot)
            assert isinstance(host, NaothHost)
            answer = await self._command(host, "Cognition:behavior:set_agent", {"agent": command.agent})
            text = answer.decode("utf-8", "replace")
            if not text.startswith("resetted agent"):
                return False, None, f"robot {host.label}: {text}"
            host.agent = command.agent
            return True, None, None
        if isinstance(command, Status):
            return True, {}, None  # no simulation counters: the robots' are in ``attached``
        if isinstance(command, ReleaseOwner):
            return True, None, None
        if isinstance(command, SetBreakpoints):
            if command.points:
                return False, None, _UNAVAILABLE.format(what="stop at a breakpoint")
            return True, None, None
        op = getattr(command, "op", type(command).__name__)
        raise CommandError(_UNAVAILABLE.format(what=_WHAT.get(op, f"carry out {op!r}")))

    def release_owner(self, owner: str) -> None:
        """Nothing to release: a NaoTH robot cannot be forced or overridden."""

    def take_control(self, take: bool = True) -> None:
        """A NaoTH robot serves one client: attached is in control."""

    # -- hot reload ---------------------------------------------------------------------------------

    async def apply(self, key: str, compilation: Compilation) -> str | None:
        """Compiled clean: write its IC to every robot and reload it there; what they answered."""
        state = self.programs[key]
        state.compilation = compilation
        program = compilation.program
        if program is None:
            return "the behavior has errors; the robot runs on with the previous version"
        ic = emit_ic(program)
        problems: list[str] = []
        sent = 0
        state.running = program
        state.running_sources = compilation.sources
        state.running_json = program_to_json(program, compilation.source_text)
        state.partial = state.partial_json = None
        for host in self.hosts:
            if not host.connected or not isinstance(host, NaothHost):
                continue
            sent += 1
            async with host.busy:  # no frame is asked between the reload and the new tables
                content = ic.encode("latin-1")
                await self._command(host, "Cognition:file::write", {"path": IC_PATH, "content": content})
                answer = (await self._command(host, "Cognition:behavior:reload")).decode("utf-8", "replace")
                if "error" in answer.lower() or not answer.startswith("behavior reloaded"):
                    problems.append(f"{host.label}: {answer.strip()}")
                await self._load(host, "reload")
        if problems:
            state.error = "; ".join(problems)
            return state.error
        state.error = None
        if not sent:
            return "no robot is attached: nothing was reloaded"
        return None

    async def status(self) -> dict[str, Any]:
        """The attached session's status (each robot with its join's findings)."""
        return await super().status()


def _display(values: tuple[Value | None, ...]) -> tuple[Value | None, ...]:
    """Frames' display values: decimals to 3 digits (NaN and infinities unknown)."""
    out: list[Value | None] = []
    for value in values:
        if isinstance(value, float):
            try:
                value = round(value * _DECIMALS) / _DECIMALS
            except (ValueError, OverflowError):
                value = None
        out.append(value)
    return tuple(out)
