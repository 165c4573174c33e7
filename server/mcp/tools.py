"""What ``xabsl mcp`` answers, as plain functions: compile, activation, why, why not, divergence, profile, query.

Each tool takes paths and names as an assistant gives them and returns JSON data with a
``text`` field an assistant can quote as it is. Nothing here knows the Model Context Protocol
(:mod:`xabsl_studio.server.mcp.server` registers these functions as tools), so every answer is
the engine's own: compile diagnostics from ``engine.lang``, why and why not from the recorded
reads (``engine.record.why``: the values the decision saw; unknown is ``?``), divergence from
``engine.compare.diverge``, the profile from ``engine.profile``, queries from ``engine.query``.

Files are read only below the roots the server was started with (:class:`Roots`; default: the
working directory), and every answer is bounded (:data:`MAX_ITEMS` entries of any list).
A problem is a :class:`ToolProblem` whose message says what is wrong, never a traceback.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from xabsl_studio.engine.compare.diverge import diverge, path_lines
from xabsl_studio.engine.errors import XabslError
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.profile import ProfileError, profile
from xabsl_studio.engine.record.reader import Recording, RecordingError
from xabsl_studio.engine.record.why import RecordedDecision, explain_at, recorded_decision, seq_at, why_not_at
from xabsl_studio.engine.runtime.debug import Condition, Explanation, show_value
from xabsl_studio.engine.runtime.whynot import WhyNot

__all__ = [
    "MAX_ITEMS",
    "Roots",
    "ToolProblem",
    "activation",
    "compile_behavior",
    "divergence",
    "profile_summary",
    "query",
    "why",
    "why_not",
]

#: the longest list an answer carries (diagnostics, options, matches); the rest is counted
MAX_ITEMS = 200


class ToolProblem(XabslError):
    """A tool cannot answer: a bad path, no such robot, option, state or tick; the message says which."""


@dataclass(frozen=True, slots=True)
class Roots:
    """The folders whose files the tools may read (resolved; symlinks followed)."""

    folders: tuple[Path, ...]

    @classmethod
    def of(cls, folders: Sequence[str | os.PathLike[str]]) -> Roots:
        """Roots from paths (default: the working directory)."""
        return cls(tuple(Path(f).resolve() for f in folders) or (Path.cwd().resolve(),))

    def file(self, path: str, what: str) -> Path:
        """``path`` (relative to the first root) as a file below a root.

        Raises:
            ToolProblem: outside every root, or no such file.
        """
        resolved = (self.folders[0] / path).resolve()
        if not any(resolved.is_relative_to(root) for root in self.folders):
            shown = ", ".join(str(r) for r in self.folders)
            raise ToolProblem(f"{path} is outside the folders this server reads ({shown})")
        if not resolved.is_file():
            raise ToolProblem(f"no such {what}: {path}")
        return resolved


def compile_behavior(roots: Roots, agents_file: str) -> dict[str, Any]:
    """Compile a behavior set: ``ok``, the error and warning counts, each diagnostic at ``file:line:col``."""
    path = roots.file(agents_file, "agents file")
    compilation = compile_file(str(path), base=str(path.parent))
    diagnostics = compilation.diagnostics
    errors = sum(1 for d in diagnostics if d.severity.value == "error")
    lines = [d.format(str(path.parent / d.file) if d.file else None) for d in diagnostics[:MAX_ITEMS]]
    ok = compilation.program is not None
    head = f"{agents_file}: {'compiles' if ok else 'does not compile'}: {errors} errors, "
    head += f"{len(diagnostics) - errors} warnings"
    return {
        "ok": ok,
        "errors": errors,
        "warnings": len(diagnostics) - errors,
        "options": len(compilation.option_names),
        "diagnostics": [d.as_dict() for d in diagnostics[:MAX_ITEMS]],
        "more": max(0, len(diagnostics) - MAX_ITEMS),
        "text": "\n".join([head, *lines]),
    }


def activation(
    roots: Roots, recording: str, robot: str, time_s: float | None = None, seq: int | None = None
) -> dict[str, Any]:
    """The activation path of ``robot`` at a tick: options with their states, basic behaviors, by depth."""
    with _open(roots, recording) as rec:
        at = _tick(rec, time_s, seq)
        if robot not in rec.agents:
            raise ToolProblem(f"no robot {robot!r} in {recording} (robots: {', '.join(rec.agents)})")
        view = rec.tick(at)
        agent = view.agents.get(robot)
        if agent is None:
            raise ToolProblem(f"{robot} has no tick {at} in {recording}")
        lines = path_lines(agent.program.description, agent.path)
        return {
            "robot": robot,
            "seq": at,
            "t_ms": view.t,
            "path": list(lines),
            "text": f"{robot} at tick {at} ({view.t / 1000:g} s):\n" + "\n".join(lines),
        }


def why(
    roots: Roots, recording: str, robot: str, option: str, time_s: float | None = None, seq: int | None = None
) -> dict[str, Any]:
    """Why ``option`` of ``robot`` took its leaf at a tick, from the values its decision read then."""
    decision = _decision(roots, recording, robot, option, time_s, seq)
    explanation = explain_at(decision)
    head = f"{robot} at tick {decision.seq} ({decision.t / 1000:g} s)"
    return {
        **_where(decision),
        "decided_in": explanation.decided_in,
        "leaf": explanation.leaf,
        "target": explanation.target,
        "stay": explanation.stay,
        "conditions": [_condition(c) for c in explanation.conditions],
        "text": f"{head}: {_why_text(explanation)}" + _inexact(decision),
    }


def why_not(
    roots: Roots,
    recording: str,
    robot: str,
    option: str,
    state: str,
    time_s: float | None = None,
    seq: int | None = None,
) -> dict[str, Any]:
    """Why ``option`` of ``robot`` did not go to ``state`` at a tick: each route there and what blocked it."""
    decision = _decision(roots, recording, robot, option, time_s, seq)
    try:
        answer = why_not_at(decision, state)
    except RecordingError as error:
        raise ToolProblem(str(error)) from None
    return {
        **_where(decision),
        "decided_in": answer.decided_in,
        "went_to": answer.went_to,
        "went": answer.went,
        "routes": [
            {
                "leaf": r.leaf,
                "stay": r.stay,
                "blocked_at": r.blocked_at,
                "parts_at": r.leaves_taken_path_at,
                "conditions": [_condition(c) for c in r.conditions],
            }
            for r in answer.routes
        ],
        "text": f"{robot} at tick {decision.seq} ({decision.t / 1000:g} s): {_why_not_text(answer)}"
        + _inexact(decision),
    }


def divergence(roots: Roots, a: str, b: str, robots: list[str] | None = None) -> dict[str, Any]:
    """The first tick each robot acts differently in recordings ``a`` and ``b``, both paths and both whys."""
    with _open(roots, a) as ra, _open(roots, b) as rb:
        try:
            report = diverge(ra, rb, robots)
        except RecordingError as error:
            raise ToolProblem(str(error)) from None
    return {**report.to_json(), "text": "\n".join(report.lines())}


def profile_summary(roots: Roots, recording: str, robots: list[str] | None = None, top: int = 10) -> dict[str, Any]:
    """Per robot its ``top`` options by share of time (with their states), coverage and oscillations."""
    top = max(1, min(top, MAX_ITEMS))
    with _open(roots, recording) as rec:
        try:
            report = profile(rec, robots, 1000.0)
        except ProfileError as error:
            raise ToolProblem(str(error)) from None
    agents: dict[str, Any] = {}
    lines = [f"{recording}: {report['ticks']} ticks, {report['duration_ms'] / 1000:g} s"]
    for name, section in report["agents"].items():
        ranked = sorted(section["options"].items(), key=lambda item: -item[1]["share"])[:top]
        coverage = section["coverage"]
        agents[name] = {
            "program": section["program"],
            "options": [
                {
                    "option": option,
                    "share": data["share"],
                    "activations": data["activations"],
                    "mean_ms": data["mean_ms"],
                    "states": {s: d["share"] for s, d in data.get("states", {}).items()},
                }
                for option, data in ranked
            ],
            "coverage": {
                k: {"percent": v.get("percent"), "never": v.get("never", [])[:MAX_ITEMS]} for k, v in coverage.items()
            },
            "oscillations": section["oscillations"],
        }
        shares = ", ".join(f"{option} {data['share'] * 100:.0f}%" for option, data in ranked)
        percent = coverage.get("options", {}).get("percent")
        lines.append(f"{name}: {shares}; options reached {percent}%; {section['oscillations']} oscillations")
    oscillations = report.get("oscillations", [])
    return {
        "ticks": report["ticks"],
        "duration_ms": report["duration_ms"],
        "agents": agents,
        "oscillations": oscillations[:MAX_ITEMS],
        "text": "\n".join(lines),
    }


def query(roots: Roots, recording: str, condition: str, robot: str | None = None) -> dict[str, Any]:
    """The tick intervals of ``recording`` where ``condition`` holds (``xabsl query``'s answer)."""
    # the query engine is imported when asked for only (it is its own module, engine.query)
    from xabsl_studio.engine.query import query_recording

    path = roots.file(recording, "recording")
    try:
        result = query_recording(path, condition, robot=robot)
    except XabslError as error:
        raise ToolProblem(str(error)) from None
    answer: dict[str, Any] = result.to_json()
    return answer


# -- helpers ----------------------------------------------------------------------------------------


def _open(roots: Roots, recording: str) -> Recording:
    path = roots.file(recording, "recording")
    try:
        return Recording(path)
    except RecordingError as error:
        raise ToolProblem(str(error)) from None


def _tick(recording: Recording, time_s: float | None, seq: int | None) -> int:
    if (time_s is None) == (seq is None):
        raise ToolProblem("give the tick as time_s (seconds, as the studio's timeline shows) or seq, one of them")
    if time_s is not None and not math.isfinite(time_s):
        raise ToolProblem(f"time_s must be a finite number of seconds, got {time_s}")
    try:
        if time_s is not None:
            return seq_at(recording, time_s)
    except RecordingError as error:
        raise ToolProblem(str(error)) from None
    assert seq is not None
    if not recording.first <= seq < recording.end:
        raise ToolProblem(f"tick {seq} is outside {recording.path} ({recording.first}..{recording.end - 1})")
    return seq


def _decision(
    roots: Roots, recording: str, robot: str, option: str, time_s: float | None, seq: int | None
) -> RecordedDecision:
    with _open(roots, recording) as rec:
        at = _tick(rec, time_s, seq)
        try:
            return recorded_decision(rec, robot, at, option)
        except RecordingError as error:
            raise ToolProblem(str(error)) from None


def _where(decision: RecordedDecision) -> dict[str, Any]:
    return {
        "robot": decision.agent.name,
        "seq": decision.seq,
        "t_ms": decision.t,
        "option": decision.option.name,
        "exact": decision.exact,
    }


def _inexact(decision: RecordedDecision) -> str:
    return "" if decision.exact else "\n(this recording holds no reads: values are unknown, ?)"


def _shown(value: object) -> str:
    return "?" if value is None else show_value(value)  # type: ignore[arg-type]


def _condition(c: Condition) -> dict[str, Any]:
    return {
        "text": c.text or c.source,
        "value": c.value if c.value is None or isinstance(c.value, bool | int | float) else str(c.value),
        "branch": c.branch,
        "comparisons": [str(k) for k in c.comparisons],
    }


def _why_text(explanation: Explanation) -> str:
    went = "stayed in" if explanation.stay else "went to"
    lines = [f"{explanation.option} in {explanation.decided_in} {went} {explanation.target} (leaf {explanation.leaf})"]
    for c in explanation.conditions:
        lines.append(f"  {'if' if c.branch else 'else of'} ({c.text or c.source}) = {_shown(c.value)}")
        lines.extend(f"    {k}" for k in c.comparisons)
    return "\n".join(lines)


def _why_not_text(answer: WhyNot) -> str:
    went = "stayed in" if answer.went_to == answer.decided_in else "went to"
    head = f"{answer.option} in {answer.decided_in} {went} {answer.went_to}, not {answer.target}"
    if answer.went:
        head = f"{answer.option} in {answer.decided_in} {went} {answer.target}: the decision did go there"
    if not answer.routes:
        return f"{head}: no transition of {answer.decided_in} leads to {answer.target}"
    lines = [head]
    for route in answer.routes:
        blocker = route.blocker
        if blocker is None:
            lines.append(
                f"  leaf {route.leaf}: nothing known blocks it"
                + (" (the leaf taken)" if route.leaves_taken_path_at is None else "")
            )
        else:
            needed, was = ("true" if blocker.branch else "false"), _shown(blocker.value)
            lines.append(
                f"  leaf {route.leaf}: blocked by ({blocker.text or blocker.source}), needs {needed}, was {was}"
            )
        for i, c in enumerate(route.conditions):
            mark = "✗" if i == route.blocked_at else " "
            lines.append(
                f"   {mark} ({c.text or c.source}) needs {'true' if c.branch else 'false'}, is {_shown(c.value)}"
            )
            lines.extend(f"        {k}" for k in c.comparisons)
    return "\n".join(lines)
