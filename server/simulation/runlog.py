"""The run log of the simulation process: what a run depends on since its world was built (``fork``).

A run of the studio is a pure function of the world's seed, the programs its engines started
with, and the commands that changed it, each at a known point between two ticks: the loop is
tick-based, so pausing, stepping and the speed only change *when* ticks run, never what they
compute. :class:`RunLog` keeps exactly that for one run (from a ``reset``, the start, or a
fork), so that ``xabsl_studio.server.simulation.worker`` can rebuild the world from the seed and re-simulate it to any
tick of the live history with the same commands and behavior versions (no world snapshots: a
copied pymunk space does not continue bit-exactly).

Positions: every sample the run produced has a seq; most come from a tick, a few from a command
(a hot reload, a world command while paused) or from the build itself. The log stores, in a
run-local numbering ``v`` (``seq = v + offset`` for the run's own samples), the samples that did
not come from a tick (*anchors*, with the ticks run so far), so ``ticks_at(v)`` is exact without
storing anything per tick, and every command with the sample it followed (``at``) and the ticks
run when it applied. A fork's log starts with its parent's commands before the fork point and a
:class:`Switch` to the programs in force; its own samples continue at a later seq (``offset``).

Bounds: a log is kept while any of its samples is still in the server's ring (older logs are
dropped, and a fork before them is refused); a log that would hold more than
:data:`MAX_EVENTS` commands stops recording, and forks after that point are refused.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass
from typing import Any

from xabsl_studio.engine.ir.model import Program

__all__ = ["LOGGED_OPS", "MAX_EVENTS", "LoggedCommand", "RunLog", "Switch"]

#: Ops that change what the world or the engines compute (logged when they succeed).
#: ``world_command`` without a name only lists the commands; ``apply`` counts when it swapped.
LOGGED_OPS = frozenset(
    {
        "select_agent",
        "force_option",
        "force_behavior",
        "release",
        "override_input",
        "release_input",
        "reset_agent",
        "world_command",
        "apply",
        "release_owner",
    }
)

#: Commands one run's log holds at most (a slider dragged for an hour); later ones are not kept.
MAX_EVENTS = 100_000

#: Per behavior key: the running program and its program JSON (None: none compiled clean yet).
Programs = dict[str, tuple[Program, dict[str, Any]] | None]


@dataclass(frozen=True, slots=True)
class Switch:
    """A fork's switch to the programs in force when it was made (engines reload, states kept)."""

    programs: Programs


@dataclass(frozen=True, slots=True)
class LoggedCommand:
    """One command that changed the run: after sample ``at`` (run-local), with ``ticks`` ticks run."""

    at: int
    ticks: int
    command: Any  # a worker command of ``xabsl_studio.server.protocol.host``, or a Switch
    owner: str | None


class RunLog:
    """Seed, starting programs and commands of one run (see the module docstring).

    Args:
        seed: the world's seed.
        programs: the programs the engines were built with.
        start: the seq of the run's first sample (the build's, or the fork's).
        offset: ``seq - v`` for the run's own samples.
    """

    __slots__ = (
        "_anchor_ticks",
        "_anchor_v",
        "end",
        "events",
        "full_at",
        "offset",
        "problem",
        "programs",
        "seed",
        "start",
    )

    def __init__(self, seed: int, programs: Programs, start: int, offset: int = 0) -> None:
        self.seed = seed
        self.programs = dict(programs)
        self.start = start
        self.offset = offset
        #: the seq of the next run's first sample (None: this is the running one)
        self.end: int | None = None
        self.events: list[LoggedCommand] = []
        #: the run-local sample from which commands were no longer kept (None: complete)
        self.full_at: int | None = None
        #: why this run cannot be replayed at all (a world that did not start from ``build_world(seed)``)
        self.problem: str | None = None
        # Samples that did not come from a tick: run-local seq and the ticks run by then.
        self._anchor_v: list[int] = [start - offset]
        self._anchor_ticks: list[int] = [0]

    def covers(self, seq: int) -> bool:
        """Whether sample ``seq`` belongs to this run's own part."""
        return self.start <= seq and (self.end is None or seq < self.end)

    def record(self, seq_before: int, ticks: int, command: Any, owner: str | None, samples: int) -> None:
        """``command`` changed the run after sample ``seq_before`` with ``ticks`` ticks run; it made ``samples``."""
        at = seq_before - self.offset
        if self.full_at is not None:
            return
        if len(self.events) >= MAX_EVENTS:
            self.full_at = at
            return
        self.events.append(LoggedCommand(at, ticks, command, owner))
        for k in range(1, samples + 1):  # samples of a command are not ticks
            self._anchor_v.append(at + k)
            self._anchor_ticks.append(ticks)

    def is_anchor(self, v: int) -> bool:
        """Whether run-local sample ``v`` did not come from a tick (the build, a command, a fork)."""
        i = bisect.bisect_right(self._anchor_v, v) - 1
        return i >= 0 and self._anchor_v[i] == v

    def ticks_at(self, v: int) -> int:
        """The ticks the run had run when run-local sample ``v`` was taken."""
        i = bisect.bisect_right(self._anchor_v, v) - 1
        if i < 0:
            raise ValueError(f"sample {v} is before the run")
        return self._anchor_ticks[i] + (v - self._anchor_v[i])

    def child(self, v: int, ticks: int, switch: Switch, start: int) -> RunLog:
        """The log of a fork at run-local sample ``v`` (``ticks`` ticks replayed), whose first sample is ``start``.

        It holds this run's commands before ``v``, then ``switch``; the fork's first sample takes
        the place of sample ``v`` in the run-local numbering.
        """
        log = RunLog(self.seed, self.programs, start, offset=start - v)
        log.events = [e for e in self.events if e.at < v]
        log.events.append(LoggedCommand(v - 1, ticks, switch, None))
        keep = bisect.bisect_left(self._anchor_v, v)
        log._anchor_v = [*self._anchor_v[:keep], v]
        log._anchor_ticks = [*self._anchor_ticks[:keep], ticks]
        return log
