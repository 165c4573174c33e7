"""Queries over the past: every tick of a run in which an XABSL condition holds.

A query is a breakpoint condition (:mod:`xabsl_studio.engine.lang.condition`: symbols, constants,
enumerations, comparisons, ``&&``, ``||``, input functions with their recorded results) that may
also name what the activation path says (``striker.state == shoot``, ``kick.active``,
``go_to_position.x > 1000``; :mod:`xabsl_studio.engine.query.language`). It is evaluated over every
tick of a recording, or of tick views such as the live history, for one robot or all, and answers
the intervals of consecutive ticks in which it is true. What the recording does not hold is
unknown and never matches. docs/queries.md is the user's description.

    from xabsl_studio.engine.query import query_recording
    result = query_recording(Path("match.mcap"), "striker.state == shoot && ball.distance > 500")
    for interval in result.intervals: ...
"""

from __future__ import annotations

from xabsl_studio.engine.errors import QueryError
from xabsl_studio.engine.query.index import QueryConditionError, QueryIndex, query_recording, query_ticks
from xabsl_studio.engine.query.result import Interval, QueryResult
from xabsl_studio.engine.record.columns import Selection

__all__ = [
    "Interval",
    "QueryConditionError",
    "QueryError",
    "QueryIndex",
    "QueryResult",
    "Selection",
    "query_recording",
    "query_ticks",
]
