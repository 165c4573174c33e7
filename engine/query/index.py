"""Queries over recorded ticks: the columns of a recording or of tick views, asked many questions.

:class:`QueryIndex` holds the columns (:mod:`xabsl_studio.engine.record.columns`) of some robots'
ticks and answers :meth:`QueryIndex.query`: check the condition against each program generation
the robots ran (:func:`~xabsl_studio.engine.query.language.compile_query`), evaluate it over every
tick at once (:mod:`xabsl_studio.engine.query.evaluate`) and cut the ticks where it is true into
intervals of consecutive ticks.

* :meth:`QueryIndex.from_recording` reads a recording's agents' tick messages, keeping what a
  :class:`~xabsl_studio.engine.record.columns.Selection` names (default: everything); a later query
  that needs a name the columns lack reads the file again for it (and keeps what it had).
* :meth:`QueryIndex.from_ticks` takes decoded tick views (the live history, an attached
  session's, a part of a recording) and keeps every input function's calls.

:func:`query_recording` and :func:`query_ticks` are the one-shot forms.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterable
from pathlib import Path

import numpy as np

from xabsl_studio.engine.errors import QueryError
from xabsl_studio.engine.lang.condition import CONDITION_FILE
from xabsl_studio.engine.lang.diagnostics import Diagnostic
from xabsl_studio.engine.query.evaluate import evaluate
from xabsl_studio.engine.query.language import CompiledQuery, compile_query
from xabsl_studio.engine.query.result import Interval, QueryResult
from xabsl_studio.engine.query.scan import read_columns, seed_codes
from xabsl_studio.engine.record.columns import Codes, ColumnsBuilder, RobotColumns, Selection
from xabsl_studio.engine.record.reader import ProgramView, Recording, TickView

__all__ = ["QueryConditionError", "QueryIndex", "query_recording", "query_ticks"]


class QueryConditionError(QueryError, ValueError):
    """A condition that does not parse or check; ``line`` and ``col`` (1-based) locate the first error.

    ``diagnostics`` holds every error, with spans in the condition's text (file ``<condition>``).
    """

    def __init__(self, condition: str, diagnostics: list[Diagnostic]) -> None:
        self.condition = condition
        self.diagnostics = [d for d in diagnostics if d.is_error]
        first = self.diagnostics[0].span if self.diagnostics else None
        self.line = first.line if first else 1
        self.col = first.col if first else 1
        self.end_line = first.end_line if first else self.line
        self.end_col = first.end_col if first else self.col
        message = "; ".join(
            f"{d.span.line}:{d.span.col}: {d.message}" if d.span else d.message for d in self.diagnostics
        )
        super().__init__(message or "the condition cannot be evaluated")

    def format(self) -> str:
        """``<condition>:line:col: message`` per error, then the condition with a caret under the first."""
        lines = [f"{CONDITION_FILE}:{d.span.line}:{d.span.col}: {d.message}" for d in self.diagnostics if d.span]
        text_lines = self.condition.splitlines() or [""]
        if 1 <= self.line <= len(text_lines):
            lines.append("  " + text_lines[self.line - 1])
            lines.append("  " + " " * (self.col - 1) + "^")
        return "\n".join(lines)


class QueryIndex:
    """The columns of some robots' ticks (see the module docstring); query it any number of times."""

    def __init__(
        self,
        robots: dict[str, RobotColumns],
        codes: Codes,
        decimals: int | None,
        recording: str | None = None,
    ) -> None:
        self.robots = robots
        self.codes = codes
        self.decimals = decimals
        #: the recording the columns came from (read again for input functions), None for views
        self.recording = recording
        self._compiled: dict[tuple[str, int, str], CompiledQuery] = {}

    @classmethod
    def from_recording(
        cls, recording: Recording, robots: list[str] | None = None, selection: Selection | None = None
    ) -> QueryIndex:
        """Read ``robots`` (default: every XABSL agent) of an open recording into columns.

        ``selection`` names what to read (default: everything; a query reads what is missing).

        Raises:
            RecordingError: a robot the recording does not have.
        """
        codes = Codes()
        seed_codes(recording, codes)
        columns = read_columns(recording, recording.agents if robots is None else robots, codes, selection)
        decimals = recording.header.get("decimals")
        return cls(columns, codes, None if decimals is None else int(decimals), recording.path)

    @classmethod
    def from_ticks(
        cls, ticks: Iterable[TickView], decimals: int | None = None, selection: Selection | None = None
    ) -> QueryIndex:
        """Columns of decoded tick views, in order (every robot that appears in them).

        ``decimals`` is the precision of their plain values (None: exact); ``selection`` what to
        keep (default: everything; views are not read again, so a later query must need no more).
        """
        codes = Codes()
        builders: dict[str, ColumnsBuilder] = {}
        programs: dict[tuple[str, int], ProgramView] = {}

        def program(robot: str, gen: int) -> ProgramView:
            return programs[(robot, gen)]

        for view in ticks:
            for name, agent in view.agents.items():
                programs[(name, agent.gen)] = agent.program
                builder = builders.get(name)
                if builder is None:
                    builder = builders[name] = ColumnsBuilder(name, program, codes, selection)
                builder.view(view.seq, view.t, agent)
        return cls({name: b.finish() for name, b in builders.items()}, codes, decimals)

    # -- querying -------------------------------------------------------------------------------

    def compile(self, condition: str, robot: str, gen: int) -> CompiledQuery:
        """``condition`` checked against the program ``robot`` ran in generation ``gen`` (cached)."""
        view = self.robots[robot].programs[gen]
        key = (view.key, view.gen, condition)
        compiled = self._compiled.get(key)
        if compiled is None:
            compiled = self._compiled[key] = compile_query(view.description, condition)
        return compiled

    def query(self, condition: str, robot: str | None = None) -> QueryResult:
        """The intervals where ``condition`` is true, for ``robot`` (None: every robot).

        Raises:
            QueryConditionError: a syntax error, or a condition that checks against none of the
                robots' behaviors (line and column of the first error).
            QueryError: a robot the ticks do not have.
        """
        if robot is not None and robot not in self.robots:
            raise QueryError(f"no robot {robot!r} in the ticks (robots: {', '.join(self.robots) or 'none'})")
        names = [robot] if robot is not None else list(self.robots)
        compiled: dict[str, dict[int, CompiledQuery]] = {}
        skipped: dict[str, str] = {}
        failure: CompiledQuery | None = None
        for name in names:
            columns = self.robots[name]
            per_gen: dict[int, CompiledQuery] = {}
            for gen in sorted(columns.programs):
                query = self.compile(condition, name, gen)
                if not query.ok:
                    if any(d.code == "syntax-error" for d in query.errors()):
                        raise QueryConditionError(condition, query.diagnostics)
                    failure = failure or query
                    continue
                per_gen[gen] = query
            if per_gen or not columns.programs:
                compiled[name] = per_gen
            elif failure is not None:
                skipped[name] = f"{columns.programs[max(columns.programs)].key}: {_message(failure)}"
        if not compiled and failure is not None:
            raise QueryConditionError(condition, failure.diagnostics)
        self._complete(compiled)
        intervals: list[Interval] = []
        ticks = matched = unknown = 0
        for name, per_gen in compiled.items():
            columns = self.robots[name]
            true = np.zeros(len(columns), dtype=np.bool_)
            known = np.zeros(len(columns), dtype=np.bool_)
            for gen, query in per_gen.items():
                value, is_known = evaluate(columns, gen, query, self.codes, self.decimals)
                rows = columns.gen == gen
                true[rows] = (value & is_known)[rows]
                known[rows] = is_known[rows]
            evaluated = np.isin(columns.gen, list(per_gen))
            ticks += int(evaluated.sum())
            matched += int(true.sum())
            unknown += int((evaluated & ~known).sum())
            intervals.extend(_intervals(name, columns, true))
        intervals.sort(key=lambda i: (i.first_seq, names.index(i.robot)))
        return QueryResult(condition, list(compiled), intervals, ticks, matched, unknown, skipped)

    def _complete(self, compiled: dict[str, dict[int, CompiledQuery]]) -> None:
        """Read again what the columns lack of the names the queries need (a pass over the recording)."""
        if self.recording is None:
            return
        missing: dict[str, Selection] = {}
        for name, per_gen in compiled.items():
            needed = Selection.nothing()
            for query in per_gen.values():
                needed = needed.union(needs(query))
            have = self.robots[name].selection
            if not have.covers(needed):
                missing[name] = have.union(needed)
        if not missing:
            return
        with Recording(self.recording) as recording:
            for name, selection in missing.items():
                self.robots.update(read_columns(recording, [name], self.codes, selection))


def needs(query: CompiledQuery) -> Selection:
    """What the columns must hold to evaluate ``query``."""
    options = {p.target for p in query.predicates.values() if not p.kind.startswith("behavior")}
    behaviors = {p.target for p in query.predicates.values() if p.kind.startswith("behavior")}
    return Selection(frozenset(query.symbols), frozenset(options), frozenset(behaviors), query.functions)


def _message(query: CompiledQuery) -> str:
    """The first error, ``line:col: message`` (why a robot was not evaluated)."""
    first = query.errors()[0]
    return f"{first.span.line}:{first.span.col}: {first.message}" if first.span else first.message


def _intervals(robot: str, columns: RobotColumns, true: np.ndarray) -> list[Interval]:
    """Runs of matching ticks with consecutive seqs."""
    rows = np.flatnonzero(true)
    if not len(rows):
        return []
    seq = columns.seq[rows]
    # a run breaks where the next matching row is not the next tick
    breaks = np.flatnonzero(np.diff(seq) != 1)
    starts = np.concatenate(([0], breaks + 1))
    ends = np.concatenate((breaks, [len(rows) - 1]))
    t = columns.t[rows]
    return [
        Interval(robot, int(seq[s]), int(seq[e]), int(t[s]), int(t[e]))
        for s, e in zip(starts.tolist(), ends.tolist(), strict=True)
    ]


def query_recording(path: Path | str | os.PathLike[str], condition: str, robot: str | None = None) -> QueryResult:
    """Every interval of ticks of the recording at ``path`` in which ``condition`` is true.

    The condition is checked before the file's ticks are read, so a bad one fails fast.

    Raises:
        QueryConditionError: the condition has errors (line and column of the first).
        QueryError: ``robot`` is not a robot of the recording.
        RecordingError: the file is not a readable recording.
    """
    with Recording(path) as recording:
        if robot is not None and robot not in recording.agents:
            raise QueryError(
                f"no robot {robot!r} in {recording.path} (robots: {', '.join(recording.agents) or 'none'})"
            )
        robots = recording.agents if robot is None else [robot]
        selection, keys = _precheck(recording, robots, condition)
        # robots whose behavior the condition does not check against are skipped unread
        read = [name for name in robots if recording.program_key(name) in keys]
        index = QueryIndex.from_recording(recording, read, selection)
        unread = {name: recording.program(name, 0) for name in robots if name not in read}
    result = index.query(condition, robot)
    skipped = dict(result.skipped)
    for name, view in unread.items():
        skipped[name] = f"{view.key}: {_message(compile_query(view.description, condition))}"
    return dataclasses.replace(result, skipped=dict(sorted(skipped.items())))


def _precheck(recording: Recording, robots: list[str], condition: str) -> tuple[Selection, set[str]]:
    """Check the condition against the robots' programs before reading ticks (see :func:`selection_for`)."""
    keys = {recording.program_key(name) for name in robots}
    return selection_for([v for (key, _gen), v in recording.programs.items() if key in keys], condition)


def selection_for(views: Iterable[ProgramView], condition: str) -> tuple[Selection, set[str]]:
    """What the columns must hold for ``condition`` over ticks of these program generations.

    Returns the selection and the program keys it checks against in some generation.

    Raises:
        QueryConditionError: a syntax error, or errors against every program.
    """
    selection = Selection.nothing()
    failure: CompiledQuery | None = None
    checked: set[str] = set()
    for view in views:
        query = compile_query(view.description, condition)
        if query.ok:
            checked.add(view.key)
            selection = selection.union(needs(query))
        else:
            if any(d.code == "syntax-error" for d in query.errors()):
                raise QueryConditionError(condition, query.diagnostics)
            failure = failure or query
    if not checked and failure is not None:
        raise QueryConditionError(condition, failure.diagnostics)
    return selection, checked


def query_ticks(
    ticks: Iterable[TickView], condition: str, robot: str | None = None, *, decimals: int | None = None
) -> QueryResult:
    """Every interval of the given tick views (in order) in which ``condition`` is true.

    ``decimals``: the precision of the views' plain values, at which input functions' arguments are
    compared (None: exact). Only the names the condition uses are read from the views.

    Raises:
        QueryConditionError: the condition has errors (line and column of the first).
        QueryError: ``robot`` appears in none of the ticks.
    """
    views = list(ticks)
    programs = {(a.program.key, a.program.gen): a.program for v in views for a in v.agents.values()}
    selection, _keys = selection_for(programs.values(), condition)
    return QueryIndex.from_ticks(views, decimals, selection).query(condition, robot)
