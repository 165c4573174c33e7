"""The studio <-> host protocol: what a studio session and the program that runs the engines say.

The host is the studio's own simulation process (``xabsl_studio.server.simulation``), where these
plain slotted dataclasses are pickled over ``xabsl_studio.server.protocol.channel`` and the
per-tick :class:`Sample` is built without any validation (it is the hot path); or a program that
runs its engines itself and attaches to studios over the network (docs/attach.md), where the same
messages travel as JSON (``xabsl_studio.server.protocol.attach``: never a pickle from a network
peer). docs/protocol.md ("Studio and host") documents them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

if TYPE_CHECKING:
    from xabsl_studio.engine.ir.model import Program
    from xabsl_studio.engine.runtime.breakpoints import Breakpoint
from xabsl_studio.server.protocol.commands import (
    Pause,
    Reset,
    Resume,
    RobotCommand,
    Seek,
    Speed,
    Status,
    Step,
    WorldCommand,
)
from xabsl_studio.server.protocol.types import HelloReason, WireValue


@dataclass(frozen=True, slots=True)
class Sample:
    """One tick as the simulation sends it (built every tick, never validated).

    Per robot (world order): the path as JSON bytes, the extras (fault, force, overrides:
    ``b',"fault":...'`` or ``b''``), the input and output values aligned with the generation's
    symbol ids; then the dynamic scene and the world status as JSON bytes; last, per robot,
    what its decisions read in the tick as JSON bytes (``Engine.reads()``, docs/recordings.md
    ``reads``; ``b''``: none), from which the server's ring explains any past tick.
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
    reads: tuple[bytes, ...] = ()


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
    #: per behavior set: enum name -> host value -> element (what the raw enum values of ``reads`` mean)
    enums: dict[str, dict[str, dict[int, str]]] = field(default_factory=dict)
    #: the samples' input and output values are raw (exact decimals, enums as host values): the
    #: server converts them for display (``xabsl_studio.server.protocol.display.SampleDisplay``);
    #: False: they are display values already (a NaoTH robot, a replay)
    raw_values: bool = False


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
class LoadIntermediateCode:
    """Hot-swap behavior set ``key`` from its intermediate code (an attached host: docs/attach.md).

    The studio compiles and emits the IC (``xabsl_studio.engine.emit.ic``); the host reads it
    (``xabsl_studio.engine.ir.ic_reader``) and reloads its engines between two ticks. The answer's
    result is None when swapped, else why the running behavior was kept (as for :class:`Apply`).
    """

    key: str
    ic: str
    op: Literal["load_ic"] = "load_ic"


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
    ``(seq, t, decided_in, leaf, active state, reads)``, ``reads`` being what the robot's
    decisions read in that tick as the ring holds it (the sample's JSON bytes; ``b''``: none).
    """

    robot: int
    option: str
    generation: int
    ticks: tuple[tuple[Any, ...], ...]
    op: Literal["explain_recorded"] = "explain_recorded"
    #: a state (id or name) to say "why not" of, for the explained tick (the first of ``ticks``)
    why_not: int | str | None = None


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
    | LoadIntermediateCode
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
