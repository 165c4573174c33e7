"""The ``query`` command of a session: the intervals where a condition holds in its recorded ticks.

:class:`RecordingQueries` answers over a recording (a replay): it keeps one
:class:`~xabsl_studio.engine.query.QueryIndex` of the file, so a query reads from the file only
the columns no earlier query read (docs/queries.md), and runs in a worker thread so the event
loop keeps serving frames meanwhile. Robots are the protocol's ids (their order in the
recording's header); the engine's errors become the command's refusal, with line and column of
the condition.
"""

from __future__ import annotations

import asyncio
import threading
from typing import Any

from xabsl_studio.engine.errors import QueryError
from xabsl_studio.engine.query import QueryIndex, QueryResult
from xabsl_studio.engine.query.columns import Selection
from xabsl_studio.engine.record import Recording, RecordingError
from xabsl_studio.server.protocol.commands import Query
from xabsl_studio.server.simulation.engines import CommandError

__all__ = ["RecordingQueries", "answer_json"]

_NOTHING = Selection(frozenset(), frozenset(), frozenset(), frozenset())


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
                    self._index = QueryIndex.from_recording(recording, selection=_NOTHING)
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
