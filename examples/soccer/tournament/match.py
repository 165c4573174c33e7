"""The match plan of a tournament and one match of it, as plain data a worker process returns.

Colours: match ``k`` uses seed ``seed + k // 2``; in even matches the HOME version plays blue
(team 0: it kicks off the first half), in odd ones red, so every seed is played once each way
round and neither version keeps the kick-off or a field side (sides also swap at half time).

A match is a pure function of its :class:`MatchSpec` and the two programs: whichever process,
pool size or cluster plays it, the score, statistics and ``trace_hash`` are the same.
"""

from __future__ import annotations

import os
import time
import traceback
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Any

from xabsl_studio.engine.errors import HostError
from xabsl_studio.engine.host import DEFAULT_BEHAVIOR_HZ
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.examples.soccer.run import play_match

#: The keys of a result's per-side dicts: the two versions, not the colours.
SIDES = ("home", "away")


@dataclass(frozen=True, slots=True)
class MatchSpec:
    """One planned match: its number, seed, who plays blue, its length and wall-time limit."""

    index: int
    seed: int
    #: True: the HOME version plays blue (team 0); False: it plays red
    home_blue: bool
    half_duration_s: float
    players: int = 5
    timeout_s: float = 600.0
    #: the MCAP file to record the match into (None: not recorded)
    record: str | None = None

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        return asdict(self)


def plan(
    n: int,
    seed: int,
    duration_s: float,
    *,
    players: int = 5,
    timeout_s: float = 600.0,
    record_dir: str | os.PathLike[str] | None = None,
) -> list[MatchSpec]:
    """``n`` matches: seeds ``seed, seed, seed + 1, seed + 1, ...``, colours alternating.

    With ``record_dir`` each match is recorded there (:func:`recording_name`).
    """
    specs = []
    for k in range(n):
        home_blue, match_seed = k % 2 == 0, seed + k // 2
        record = None if record_dir is None else os.path.join(record_dir, recording_name(k, match_seed, home_blue))
        specs.append(MatchSpec(k, match_seed, home_blue, duration_s / 2.0, players, timeout_s, record))
    return specs


def recording_name(index: int, seed: int, home_blue: bool) -> str:
    """``match-003-seed2-home-red.mcap``: the file a recorded match is kept in."""
    return f"match-{index:03d}-seed{seed}-home-{'blue' if home_blue else 'red'}.mcap"


class MatchTimeout(HostError):
    """A match ran longer (wall clock) than its ``timeout_s``."""


class MatchInterrupted(HostError):
    """The tournament was stopped (Ctrl+C) while this match ran."""


def play(
    spec: MatchSpec,
    home: Program,
    away: Program,
    stop: Callable[[], bool] | None = None,
    sources: tuple[dict[str, Any] | None, dict[str, Any] | None] = (None, None),
) -> dict[str, Any]:
    """Play ``spec`` and return its result as JSON-ready data; never raises for a failed match.

    A result has ``index``, ``seed``, ``home_colour`` and ``ok``. A played match (``ok`` true)
    adds, keyed by version (``home``/``away``, not colour): ``score``, ``teams`` (the statistics
    of ``xabsl run --json``), ``activations`` (option -> robot ticks active), ``states``
    (``"option/state"`` -> ``[robot ticks, entries]``), ``robot_ticks``; and ``trace_hash``,
    ``sim_seconds``, ``cpu_seconds``, ``faults``. A failed one adds ``error`` instead.

    Args:
        spec: the match.
        home: the HOME version's program.
        away: the AWAY version's program.
        stop: polled every simulated second; True ends the match as interrupted.
        sources: HOME's and AWAY's source files (``xabsl_studio.engine.record.sources``), kept in
            a recording so that it can be forked (``xabsl serve --replay``, Run from here).
    """
    result: dict[str, Any] = {
        "index": spec.index,
        "seed": spec.seed,
        "home_colour": "blue" if spec.home_blue else "red",
    }
    blue, red = (home, away) if spec.home_blue else (away, home)
    keys, blue_red_sources = (("home", "away"), sources) if spec.home_blue else (("away", "home"), sources[::-1])
    deadline = time.perf_counter() + spec.timeout_s

    def check(_time_ms: int, _game: Any) -> None:
        if time.perf_counter() > deadline:
            raise MatchTimeout(f"timed out after {spec.timeout_s:g} s (wall clock)")
        if stop is not None and stop():
            raise MatchInterrupted("interrupted")

    cpu = time.process_time()
    try:
        report = play_match(
            spec.seed,
            blue,
            red,
            players=spec.players,
            half_duration_s=spec.half_duration_s,
            progress=check,
            record=spec.record,
            record_keys=keys,
            record_sources=(blue_red_sources[0], blue_red_sources[1]),
        )
    except MatchInterrupted:
        result.update(ok=False, interrupted=True, error="interrupted")
        return _with_recording(result, spec)
    except Exception as error:  # a failing match is reported with its seed, never dropped
        last = traceback.extract_tb(error.__traceback__)[-1:] if error.__traceback__ else []
        where = f" ({last[0].filename}:{last[0].lineno})" if last and not isinstance(error, MatchTimeout) else ""
        result.update(ok=False, error=f"{type(error).__name__}: {error}{where}")
        return _with_recording(result, spec)
    # Colour order (team 0 = blue) to version order.
    order = (0, 1) if spec.home_blue else (1, 0)
    data = report.as_dict()
    colour_keys = ("home", "away")  # play_match's keys: home = blue = team 0
    ticks = round(report.sim_seconds * DEFAULT_BEHAVIOR_HZ) * spec.players
    result.update(
        ok=True,
        score={side: report.score[team] for side, team in zip(SIDES, order, strict=True)},
        teams={side: data["teams"][colour_keys[team]] for side, team in zip(SIDES, order, strict=True)},
        activations={side: report.activations[team] for side, team in zip(SIDES, order, strict=True)},
        states={
            side: _state_names(program, report.states[team])
            for side, team, program in zip(SIDES, order, (home, away), strict=True)
        },
        robot_ticks={"home": ticks, "away": ticks},
        trace_hash=report.trace_hash,
        sim_seconds=round(report.sim_seconds, 3),
        cpu_seconds=round(time.process_time() - cpu, 3),
        faults=report.faults,
    )
    return _with_recording(result, spec)


def _with_recording(result: dict[str, Any], spec: MatchSpec) -> dict[str, Any]:
    """``result`` with the match's recording, when one was written."""
    if spec.record is not None and os.path.isfile(spec.record):
        result["recording"] = spec.record
    return result


def _state_names(program: Program, counts: dict[tuple[str, int], tuple[int, int]]) -> dict[str, list[int]]:
    """``(option, state index)`` keys as ``"option/state"`` names, sorted."""
    named = {f"{option}/{program.options[option].states[index].name}": list(c) for (option, index), c in counts.items()}
    return dict(sorted(named.items()))
