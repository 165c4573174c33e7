"""Reading a recording's columns: one pass over its tick messages, or parallel passes over tick ranges.

A cold query's time is the pass over the file (decompressing, parsing each robot's ``xabsl.AgentTick``
JSON, checking it, collecting the columns); evaluating the columns takes milliseconds. A large
recording is therefore cut into tick ranges that start on key frames (every ``key_every`` ticks:
a range needs nothing of the ticks before it), read by forked worker processes at once, and the
parts are joined in order (:func:`join_columns`): the same columns a single pass gives, array for
array (tests/query/test_scan.py).

Enum elements are numbered by a :class:`~xabsl_studio.engine.record.columns.Codes` that every part
must share. The codes are seeded from the recording's programs before the workers fork, so each
worker numbers every element the same way; a part that met an element outside the programs
(a foreign or damaged recording) would number it on its own, so then the file is read again in
one pass instead.

Workers are forked (no imports, nothing to send but the tick range), which is only safe in a
process that runs no other thread: a caller with threads (the studio, the MCP server) reads in one
pass.
"""

from __future__ import annotations

import dataclasses
import itertools
import multiprocessing
import os
import threading
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import numpy as np

from xabsl_studio.engine.lang import no_cycle_collection
from xabsl_studio.engine.record import stored
from xabsl_studio.engine.record.columns import (
    CallTable,
    Codes,
    ColumnsBuilder,
    Floats,
    Mask,
    NodeTable,
    RobotColumns,
    RobotEvents,
    Selection,
)
from xabsl_studio.engine.record.columns import seed_codes as seed_program_codes
from xabsl_studio.engine.record.mcapread import Malformed
from xabsl_studio.engine.record.reader import ProgramView, Recording, RecordingError

__all__ = ["join_columns", "read_columns", "seed_codes"]

#: Fewer agent ticks than this are read in one pass (forking would cost more than it saves).
PARALLEL_FROM = 40_000
#: Most worker processes of one read.
MAX_WORKERS = 8


def seed_codes(recording: Recording, codes: Codes) -> None:
    """Number every enum element of the recording's programs, in file order (see the module docstring)."""
    seed_program_codes(recording.programs.values(), codes)


def _one_pass(
    recording: Recording,
    robots: list[str],
    codes: Codes,
    selection: Selection | None,
    start: int = 0,
    stop: int | None = None,
) -> dict[str, RobotColumns]:
    builders = {name: ColumnsBuilder(name, recording.program, codes, selection) for name in robots}
    with no_cycle_collection():  # hundreds of thousands of lists that all live to the end
        for name, message in recording.agent_messages(start, stop, agents=robots):
            builders[name].message(message)
        return {name: b.finish() for name, b in builders.items()}


def _workers(agent_ticks: int) -> int:
    """How many processes to read with: 1 unless the recording is large, there are cores, forking is safe."""
    if agent_ticks < PARALLEL_FROM or threading.active_count() > 1:
        return 1
    if "fork" not in multiprocessing.get_all_start_methods():
        return 1
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, min(cores, MAX_WORKERS, agent_ticks // (PARALLEL_FROM // 2)))


# What a forked worker reads: set in the parent just before the pool forks (inherited, not sent).
_TASK: tuple[Recording, list[str], Codes, Selection | None] | None = None


def _read_range(bounds: tuple[int, int]) -> tuple[dict[str, RobotColumns], int]:
    """In a worker: the columns of ticks ``bounds`` and how many codes the worker's Codes holds after."""
    assert _TASK is not None
    recording, robots, codes, selection = _TASK
    with Recording(recording.path) as own:  # its own file handle: the parent's is shared with the other workers
        columns = _one_pass(own, robots, codes, selection, *bounds)
    for part in columns.values():
        part.programs = {}  # the parent has them: no need to send the descriptions back
    return columns, len(codes.by_name)


def read_columns(
    recording: Recording,
    robots: list[str],
    codes: Codes,
    selection: Selection | None,
    workers: int | None = None,
) -> dict[str, RobotColumns]:
    """The columns of ``robots`` in ``recording`` (all ticks), in parallel when that pays.

    ``codes`` should hold the recording's elements (:func:`seed_codes`) for the parallel read;
    ``workers``: how many processes (None: by the recording's size, the cores, the threads running).
    """
    global _TASK
    found = stored_columns(recording, robots, codes, selection)
    if found is not None:
        return found
    start, end, every = recording.first, recording.end, max(1, recording.key_every)
    if workers is None:
        workers = _workers((end - start) * len(robots))
    if workers <= 1 or end - start <= every:
        return _one_pass(recording, robots, codes, selection)
    # ranges on key frame ticks (every `every` ticks), as even as that allows
    step = -(-(end - start) // workers)
    cuts = sorted({start, end, *(max(start, min(end, _key_tick(start + i * step, every))) for i in range(1, workers))})
    bounds = [(a, b) for a, b in itertools.pairwise(cuts) if a < b]
    known = len(codes.by_name)
    _TASK = (recording, robots, codes, selection)
    try:
        with ProcessPoolExecutor(len(bounds), mp_context=multiprocessing.get_context("fork")) as pool:
            parts = list(pool.map(_read_range, bounds))
    finally:
        _TASK = None
    if any(count != known for _, count in parts):  # an element outside the programs: numbered per part
        return _one_pass(recording, robots, codes, selection)
    joined = {name: join_columns([columns[name] for columns, _ in parts]) for name in robots}
    for name, columns in joined.items():
        columns.programs = {int(g): recording.program(name, int(g)) for g in np.unique(columns.gen).tolist()}
    return joined


def stored_columns(
    recording: Recording, robots: list[str], codes: Codes, selection: Selection | None
) -> dict[str, RobotColumns] | None:
    """The columns of ``robots`` from the recording's stored columns (None: it has none fit to use).

    Used only when the parts cover every tick of the recording and every tick message the
    statistics count of each robot, and number enum elements as ``codes`` does (see
    ``xabsl_studio.engine.record.stored``). Keeps every path node and, of the values and the input
    functions' calls, what ``selection`` names.

    Raises:
        RecordingError: a damaged attachment (its CRC, its layout or its arrays).
    """
    indexes = recording.attachments(stored.NAME, stored.MEDIA_TYPE)
    if not indexes:
        return None
    keep = Selection() if selection is None else Selection(symbols=selection.symbols, functions=selection.functions)
    parts = []
    for index in indexes:
        try:
            parts.append(stored.decode_part(recording.attachment(index), keep.symbols, keep.functions))
        except Malformed as error:
            reason = f"damaged attachment {index.name!r} at byte {index.offset}: {error}"
            raise RecordingError(f"{recording.path}: {reason}", path=recording.path, reason=reason) from None
    parts.sort(key=lambda p: p.start)
    bounds = [recording.first, *(b for p in parts for b in (p.start, p.stop)), recording.end]
    if any(a != b for a, b in zip(bounds[::2], bounds[1::2], strict=True)):
        return None  # a part missing (a recovered file), or ticks the parts do not hold
    written = max((p.codes for p in parts), key=len)
    mine = list(codes.by_name)
    if any(p.codes != written[: len(p.codes)] for p in parts) or written[: len(mine)] != mine[: len(written)]:
        return None  # elements numbered otherwise than the programs number them: scan
    for robot in robots:
        if sum(len(p.robots[robot]) for p in parts if robot in p.robots) != recording.tick_messages(robot):
            return None
    for element in written[len(mine) :]:
        codes.code(element)
    result: dict[str, RobotColumns] = {}
    for robot in robots:
        pieces = [_kept(p.robots[robot], keep).columns({}, keep) for p in parts if robot in p.robots]
        if not pieces:
            result[robot] = ColumnsBuilder(robot, recording.program, codes, keep).finish()
            continue
        joined = join_columns(pieces)
        joined.programs = {int(g): recording.program(robot, int(g)) for g in np.unique(joined.gen).tolist()}
        result[robot] = joined
    return result


def _kept(events: RobotEvents, keep: Selection) -> RobotEvents:
    """A robot's stored ticks as decoded for ``keep`` (its values and calls only): the functions it names."""
    return events if keep.functions is None else dataclasses.replace(events, functions=keep.functions)


def _key_tick(seq: int, every: int) -> int:
    """The key frame tick at or before ``seq``."""
    return seq - seq % every


def join_columns(parts: list[RobotColumns]) -> RobotColumns:
    """One robot's columns of consecutive tick ranges, each starting on a key frame, as one.

    A name a part lacks is unknown in that part's ticks (its key frame did not hold it).
    """
    first = parts[0]
    if len(parts) == 1:
        return first
    offsets = np.cumsum([0, *(len(p) for p in parts)])
    values: dict[str, tuple[Floats, Mask]] = {}
    for name in dict.fromkeys(n for p in parts for n in p.values):
        arrays: list[Floats] = []
        masks: list[Mask] = []
        for part in parts:
            found = part.values.get(name)
            if found is None:
                arrays.append(np.full(len(part), np.nan))
                masks.append(np.zeros(len(part), dtype=np.bool_))
            else:
                arrays.append(found[0])
                masks.append(found[1])
        values[name] = (np.concatenate(arrays), np.concatenate(masks))
    calls: dict[str, CallTable] = {}
    for name in dict.fromkeys(n for p in parts for n in p.calls):
        tables = [
            (offset, p.calls[name]) for offset, p in zip(offsets.tolist(), parts, strict=False) if name in p.calls
        ]
        calls[name] = CallTable(
            np.concatenate([t.row + offset for offset, t in tables]),
            [args for _, t in tables for args in t.args],
            np.concatenate([t.result for _, t in tables]),
            np.concatenate([t.known for _, t in tables]),
        )
    programs: dict[int, ProgramView] = {}
    for part in parts:
        programs.update(part.programs)
    return RobotColumns(
        first.robot,
        np.concatenate([p.seq for p in parts]),
        np.concatenate([p.t for p in parts]),
        np.concatenate([p.gen for p in parts]),
        programs,
        values,
        _join_nodes([p.nodes for p in parts], offsets.tolist()),
        calls=calls,
        functions=first.functions,
        selection=first.selection,
        has_reads=all(p.has_reads for p in parts),
    )


def _join_nodes(tables: list[NodeTable], row_offsets: list[int]) -> NodeTable:
    param_offsets = np.cumsum([0, *(len(t.params) for t in tables)]).tolist()

    def cat(field: str) -> Any:
        return np.concatenate([getattr(t, field) for t in tables])

    return NodeTable(
        np.concatenate([t.row + offset for t, offset in zip(tables, row_offsets, strict=False)]),
        cat("kind"),
        cat("ident"),
        cat("state"),
        cat("decided"),
        cat("leaf"),
        cat("option_time"),
        cat("state_time"),
        np.concatenate([t.param_start + offset for t, offset in zip(tables, param_offsets, strict=False)]),
        cat("param_count"),
        cat("params"),
        cat("params_known"),
    )
