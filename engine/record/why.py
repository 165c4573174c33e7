"""Why and why not at a tick of a recording, headless: the recorded reads through the engine's debugger.

A recording holds per tick and agent the activation path (each option's decided-in state and
leaf) and what the decisions read (``AgentTick.reads``), and per program generation its
intermediate code. :func:`recorded_decision` rebuilds the generation's program, finds the
option's node on the path and gives the decision's values
(:class:`~xabsl_studio.engine.runtime.debug.ReadValues`); :func:`explain_at` and
:func:`why_not_at` answer "why" and "why not" from them, exactly as the studio's replay does.
Conditions carry the texts they were written with (the recorded description's), as the IC has
none. A recording without reads gives unknown values (None), never values guessed.

Used by ``xabsl diverge`` (the why of the first differing decision) and ``xabsl mcp``.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from xabsl_studio.engine.errors import DebugError
from xabsl_studio.engine.ir.model import Option, Program, State
from xabsl_studio.engine.record.reader import AgentTick, Recording, RecordingError
from xabsl_studio.engine.runtime.debug import (
    Condition,
    Explanation,
    ReadValues,
    decision_reads,
    explain_decision,
    render,
)
from xabsl_studio.engine.runtime.whynot import Route, WhyNot, explain_why_not

__all__ = ["RecordedDecision", "explain_at", "recorded_decision", "seq_at", "why_not_at"]


@dataclass(frozen=True, slots=True)
class RecordedDecision:
    """One option's decision in one recorded tick, with what it read."""

    agent: AgentTick
    seq: int
    t: int
    program: Program
    option: Option
    state: State
    leaf: int
    values: ReadValues
    #: False: the recording holds no reads (values unknown)
    exact: bool

    def described(self, conditions: Sequence[Condition]) -> tuple[Condition, ...]:
        """``conditions`` (one path down the decided-in state's tree) with the texts they were written with."""
        node: dict[str, Any] = self.agent.program.option(self.option.index)["states"][self.state.index]["decision"]
        out = []
        for condition in conditions:
            if "if" not in node:
                out.append(condition)
                continue
            out.append(dataclasses.replace(condition, text=node["if"]))
            node = node["then"] if condition.branch else node["else"]
        return tuple(out)


def seq_at(recording: Recording, seconds: float) -> int:
    """The tick at behavior time ``seconds`` (the frames' ``t``; a fork's first tick is at its fork time).

    Raises:
        RecordingError: outside the recording.
    """
    start = recording.tick(recording.first).t / 1000
    seq = recording.first + round((seconds - start) * recording.behavior_hz)
    if not recording.first <= seq < recording.end:
        end = start + (recording.end - recording.first) / recording.behavior_hz
        raise RecordingError(f"{seconds:g} s is outside {recording.path} ({start:g} .. {end:g} s)")
    return seq


def recorded_decision(recording: Recording, agent: str, seq: int, option: str | int) -> RecordedDecision:
    """Option ``option``'s (name or IR id) decision of ``agent`` at tick ``seq``.

    Raises:
        RecordingError: no such agent, tick or option, the option did not decide in that tick, or
            the recording holds no intermediate code.
    """
    if agent not in recording.agents:
        raise RecordingError(f"no agent {agent!r} in {recording.path} (agents: {', '.join(recording.agents)})")
    if not recording.first <= seq < recording.end:
        raise RecordingError(f"tick {seq} is outside {recording.path} ({recording.first}..{recording.end - 1})")
    view = recording.tick(seq)
    tick = view.agents.get(agent)
    if tick is None:
        raise RecordingError(f"{agent} has no tick {seq} in {recording.path}")
    program = tick.program.program()
    if program is None:
        raise RecordingError(f"{recording.path} holds no intermediate code (an older recording): no why")
    if isinstance(option, int):
        found = next((o for o in program.options.values() if o.index == option), None)
    else:
        found = program.options.get(option)
    if found is None:
        raise RecordingError(f"{agent}'s behavior has no option {option!r}")
    node = next((n for n in tick.path if n[0] == 0 and n[2] == found.index), None)
    if node is None:
        ran = ", ".join(tick.option_names())
        raise RecordingError(f"option {found.name} did not run in tick {seq} of {agent} (ran: {ran})")
    decided_in, leaf = int(node[6]), int(node[7])
    if leaf < 0 or not 0 <= decided_in < len(found.states):
        raise RecordingError(f"option {found.name} decided nothing in tick {seq} of {agent}")
    description = tick.program.description
    values = ReadValues(
        program,
        found,
        decision_reads(tick.reads, found.index) if tick.reads is not None else None,
        tick.program.read_enums(),
        {s["name"]: s["id"] for s in description["inputs"]},
        {s["name"]: s["id"] for s in description["outputs"]},
    )
    return RecordedDecision(
        tick, seq, view.t, program, found, found.states[decided_in], leaf, values, tick.reads is not None
    )


def explain_at(decision: RecordedDecision) -> Explanation:
    """Why the recorded decision took its leaf, from what it read."""
    text = functools.partial(render, option=decision.option.name)
    try:
        explanation = explain_decision(decision.option, decision.state, decision.leaf, decision.values, text)
    except KeyError:
        raise RecordingError(
            f"state {decision.option.name}.{decision.state.name} has no leaf {decision.leaf}"
        ) from None
    return dataclasses.replace(explanation, conditions=decision.described(explanation.conditions))


def why_not_at(decision: RecordedDecision, target: str) -> WhyNot:
    """Why the recorded decision did not go to state ``target``, from what it read.

    Raises:
        RecordingError: the option has no state ``target``.
    """
    text = functools.partial(render, option=decision.option.name)
    try:
        answer = explain_why_not(decision.option, decision.state, decision.leaf, target, decision.values, text)
    except DebugError as error:
        raise RecordingError(str(error)) from None
    routes = tuple(
        Route(r.leaf, r.stay, decision.described(r.conditions), r.blocked_at, r.leaves_taken_path_at)
        for r in answer.routes
    )
    return dataclasses.replace(answer, routes=routes)
