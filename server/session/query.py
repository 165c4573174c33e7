"""The ``query`` command of a session: the intervals where a condition holds in its recorded ticks.

* :class:`RecordingQueries` answers over a recording (a replay): it keeps one
  :class:`~xabsl_studio.engine.query.QueryIndex` of the file, so a query reads from the file only
  the columns no earlier query read (docs/queries.md);
* :func:`answer_history` answers over the ticks of a live or attached session's ring buffer: the
  frames it holds are decoded (``frames.recorded_ticks``) into the reader's tick views, with each
  generation's program description, display values (decimals to 3 digits, enums as element
  indices) and the exact ``reads`` the simulation sent, and queried in memory
  (:func:`~xabsl_studio.engine.query.query_ticks`).

Both run in a worker thread so the event loop keeps serving frames meanwhile. Robots are the
protocol's ids; the engine's errors become the command's refusal, with line and column of the
condition.
"""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Iterator
from typing import Any

import orjson

from xabsl_studio.engine.errors import QueryError
from xabsl_studio.engine.query import QueryIndex, QueryResult, query_ticks
from xabsl_studio.engine.record import AgentTick, Recording, RecordingError, TickView
from xabsl_studio.engine.record.columns import Selection
from xabsl_studio.engine.record.reader import ProgramView
from xabsl_studio.server.protocol.commands import Query
from xabsl_studio.server.session import frames
from xabsl_studio.server.session.frames import Generation, Ring
from xabsl_studio.server.simulation.engines import CommandError

__all__ = ["RecordingQueries", "answer_history", "answer_json", "history_views"]

#: The precision of a frame's decimal values (display values, docs/protocol.md).
FRAME_DECIMALS = 3


def answer_json(result: QueryResult, ids: dict[str, int]) -> dict[str, Any]:
    """The reply's result (``QueryAnswer``): intervals with robot ids and names."""
    return {
        "condition": result.condition,
        "intervals": [
            {
                "robot": ids[i.robot],
                "name": i.robot,
                "first_seq": i.first_seq,
                "last_seq": i.last_seq,
                "first_t": i.first_t_ms,
                "last_t": i.last_t_ms,
            }
            for i in result.intervals
        ],
        "ticks": result.ticks,
        "matched": result.matched,
        "unknown": result.unknown,
        "skipped": dict(result.skipped),
    }


class RecordingQueries:
    """Queries over one recording file (see the module docstring)."""

    def __init__(self, path: str, robots: list[dict[str, Any]]) -> None:
        self.path = path
        #: robot name -> protocol id, for the XABSL robots of the recording
        self.ids = {r["name"]: i for i, r in enumerate(robots) if r.get("program") is not None}
        self._index: QueryIndex | None = None
        self._lock = threading.Lock()

    def _query(self, condition: str, robot: str | None) -> QueryResult:
        with self._lock:  # one reader of the file at a time; the index grows under it
            if self._index is None:
                with Recording(self.path) as recording:
                    self._index = QueryIndex.from_recording(recording, selection=Selection.nothing())
            return self._index.query(condition, robot)

    async def answer(self, command: Query) -> dict[str, Any]:
        """The ``query`` command's result.

        Raises:
            CommandError: a bad condition (``condition: line:col: message``), an unknown robot, a
                file that cannot be read any more.
        """
        robot = None
        if command.robot is not None:
            robot = next((name for name, i in self.ids.items() if i == command.robot), None)
            if robot is None:
                raise CommandError(f"no XABSL robot {command.robot} in this recording")
        try:
            result = await asyncio.to_thread(self._query, command.condition, robot)
        except QueryError as error:
            raise CommandError(f"condition: {error}") from None
        except (RecordingError, OSError) as error:
            raise CommandError(f"cannot read {self.path}: {error}") from None
        return answer_json(result, self.ids)


def _program_view(gen: Generation, key: str) -> ProgramView:
    """What the query engine reads of generation ``gen``'s behavior ``key``: description and enum tables."""
    description = gen.structure["programs"][key]
    display = {e["name"]: {str(i): element for i, element in enumerate(e["elements"])} for e in description["enums"]}
    reads = {name: {str(v): e for v, e in table.items()} for name, table in gen.enums.get(key, {}).items()}
    return ProgramView(key, gen.number, 0, description, {"enums": display, "read_enums": reads or display})


def history_views(ring: Ring) -> Iterator[TickView]:
    """The ring's ticks as tick views, oldest first (the robots that run an XABSL engine)."""
    runs = frames.runs(ring, -(2**62), 2**62)
    for run in runs:
        gen = run[0].gen
        robots = gen.structure["robots"]
        views: dict[str, ProgramView] = {}
        names: dict[str, tuple[dict[int, str], dict[int, str]]] = {}
        for key, description in gen.structure["programs"].items():
            views[key] = _program_view(gen, key)
            names[key] = (
                {int(s["id"]): s["name"] for s in description["inputs"] if not s.get("params")},
                {int(s["id"]): s["name"] for s in description["outputs"]},
            )
        for entry, states in frames.recorded_ticks(ring, run[-1].seq):
            agents: dict[str, AgentTick] = {}
            for robot, state in enumerate(states):
                key = robots[robot].get("program") if robot < len(robots) else None
                if key is None or key not in views:
                    continue
                input_names, output_names = names[key]
                inputs = {input_names[int(i)]: v for i, v in state.get("inputs", {}).items() if int(i) in input_names}
                outputs = {
                    output_names[int(i)]: v for i, v in state.get("outputs", {}).items() if int(i) in output_names
                }
                raw = entry.reads[robot] if robot < len(entry.reads) else b""
                name = robots[robot]["name"]
                agents[name] = AgentTick(
                    name,
                    views[key],
                    gen.number,
                    entry.seq,
                    state.get("path", []),
                    (),
                    (),
                    inputs,
                    outputs,
                    None,
                    orjson.loads(raw) if raw else None,
                )
            yield TickView(entry.seq, entry.t, agents)


def _history_query(ring: Ring, condition: str, robot: int | None) -> tuple[QueryResult, dict[str, int]]:
    views = list(history_views(ring))
    ids: dict[str, int] = {}
    for run in frames.runs(ring, -(2**62), 2**62):
        for i, r in enumerate(run[0].gen.structure["robots"]):
            if r.get("program") is not None:
                ids[r["name"]] = i
    if not views:
        raise CommandError("the history holds no tick yet")
    name = None
    if robot is not None:
        name = next((n for n, i in ids.items() if i == robot), None)
        if name is None:
            raise CommandError(f"no XABSL robot {robot} in this session")
    return query_ticks(views, condition, name, decimals=FRAME_DECIMALS), ids


async def answer_history(ring: Ring, command: Query) -> dict[str, Any]:
    """The ``query`` command's result over a session's ring buffer (see the module docstring).

    Raises:
        CommandError: a bad condition (``condition: line:col: message``), an unknown robot, an
            empty history.
    """
    try:
        result, ids = await asyncio.to_thread(_history_query, ring, command.condition, command.robot)
    except QueryError as error:
        raise CommandError(f"condition: {error}") from None
    return answer_json(result, ids)
