"""The behavioral diff: two profiles side by side, per option and state, with the change's significance.

``xabsl profile A.mcap --against B.mcap`` profiles both recordings (:func:`~.report.profile`) and
compares team sections (a program key's robots): two versions played on the same seeds, a fork
and its original, or the two sides of one match. Per option: the share of robot time it was
active, its activations per minute, their mean duration; per state the same within its option
(its share of the option's time: where the decisions differ); per option the transitions taken
per minute. Each change is A − B.

Significance (docs/compare.md): consecutive ticks are not independent trials, so a share is
counted over **windows** of robot time (``window_ms``, default one second): a share ``p`` of
``T`` ms of robot time is ``p·n`` successes of ``n = T / window`` trials. Each side gets its 95 %
Wilson score interval (the tournament's interval), the change Newcombe's interval built from the
two (:func:`~.stats.difference_interval`); a change whose interval excludes 0 is significant.
Rates (activations, transitions per minute) are compared by :func:`~.stats.rate_test`.

Rows are sorted by :func:`~.stats.change_key`: options (states, transitions) that ran on one side
only come first, then the largest change of share (rate for transitions).
"""

from __future__ import annotations

from typing import Any

from xabsl_studio.engine.profile.report import ProfileError
from xabsl_studio.engine.profile.stats import change_key, difference_interval, rate_test, wilson

__all__ = ["FORMAT", "WINDOW_MS", "compare_reports", "compare_sections", "pair_teams"]

#: ``format`` of the document.
FORMAT = "xabsl-profile-diff/1"
#: The default window of robot time counted as one trial of a share [ms].
WINDOW_MS = 1000.0
INTERVAL = "95 % Wilson score intervals over windows of robot time; the change: Newcombe's interval from them"


def pair_teams(
    a: dict[str, Any], b: dict[str, Any], team: str | None = None, against_team: str | None = None
) -> list[tuple[str, str]]:
    """Which team of report ``a`` is compared with which of ``b``.

    Named (``team``, ``against_team`` defaulting to ``team``): that pair. Else every program key
    both reports have, and, when each has exactly one key the other lacks, those two (a version
    recorded under another folder name against the original).

    Raises:
        ProfileError: a named team that is not in its report, or nothing to compare.
    """
    if team is not None or against_team is not None:
        first = team if team is not None else against_team
        second = against_team if against_team is not None else team
        assert first is not None and second is not None
        for name, report, flag in ((first, a, "--team"), (second, b, "--against-team")):
            if name not in report["teams"]:
                known = ", ".join(report["teams"]) or "none"
                raise ProfileError(f"{flag}: no team {name!r} in {report['recording']} (teams: {known})")
        return [(first, second)]
    pairs = [(key, key) for key in a["teams"] if key in b["teams"]]
    only_a = [k for k in a["teams"] if k not in b["teams"]]
    only_b = [k for k in b["teams"] if k not in a["teams"]]
    if len(only_a) == 1 and len(only_b) == 1:
        pairs.append((only_a[0], only_b[0]))
    if not pairs:
        raise ProfileError(
            f"no team to compare: {', '.join(a['teams']) or 'none'} against {', '.join(b['teams']) or 'none'}; "
            "name them with --team and --against-team"
        )
    return pairs


def _trials(ms: float, window_ms: float) -> int:
    """Windows of robot time in ``ms`` (at least one where there was any time)."""
    return max(1, round(ms / window_ms)) if ms > 0 else 0


def _share_row(
    share_a: float, share_b: float, ms_a: float, ms_b: float, window_ms: float
) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    """Both sides' share with its interval, and the change with Newcombe's interval."""
    n_a, n_b = _trials(ms_a, window_ms), _trials(ms_b, window_ms)
    k_a, k_b = round(share_a * n_a), round(share_b * n_b)
    low, high = difference_interval(k_a, n_a, k_b, n_b)
    side_a = {"share": round(share_a, 6), "share_ci95": [round(x, 6) for x in wilson(k_a, n_a)]}
    side_b = {"share": round(share_b, 6), "share_ci95": [round(x, 6) for x in wilson(k_b, n_b)]}
    change = {
        "share": round(share_a - share_b, 6),
        "share_ci95": [round(low, 6), round(high, 6)],
        "significant": low > 0 or high < 0,
    }
    return side_a, side_b, change


def _per_minute(count: int, ms: float) -> float:
    return round(count * 60000.0 / ms, 4) if ms > 0 else 0.0


def _only(in_a: bool, in_b: bool) -> str | None:
    return "a" if in_a and not in_b else "b" if in_b and not in_a else None


def _activity(
    entry_a: dict[str, Any] | None, entry_b: dict[str, Any] | None, ms_a: float, ms_b: float
) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    """Activations per minute of robot time and mean durations of both sides, and their changes."""
    act_a: int = entry_a["activations"] if entry_a else 0
    act_b: int = entry_b["activations"] if entry_b else 0
    mean_a: float | None = entry_a["mean_ms"] if entry_a else None
    mean_b: float | None = entry_b["mean_ms"] if entry_b else None
    rate_a, rate_b = _per_minute(act_a, ms_a), _per_minute(act_b, ms_b)
    side_a = {"activations": act_a, "per_minute": rate_a, "mean_ms": mean_a}
    side_b = {"activations": act_b, "per_minute": rate_b, "mean_ms": mean_b}
    change = {
        "per_minute": round(rate_a - rate_b, 4),
        "per_minute_significant": rate_test(act_a, ms_a, act_b, ms_b),
        "mean_ms": round(mean_a - mean_b, 3) if mean_a is not None and mean_b is not None else None,
    }
    return side_a, side_b, change


def _transitions(
    option_a: dict[str, Any] | None, option_b: dict[str, Any] | None, ms_a: float, ms_b: float
) -> list[dict[str, Any]]:
    """The transitions taken (by from and to state, over all leaves), per minute of robot time."""
    counts: list[dict[tuple[str, str], int]] = []
    for option in (option_a, option_b):
        found: dict[tuple[str, str], int] = {}
        for t in option["transitions"] if option else ():
            key = (t["from"], t["to"])
            found[key] = found.get(key, 0) + t["count"]
        counts.append(found)
    rows: list[dict[str, Any]] = []
    for key in sorted(counts[0].keys() | counts[1].keys()):
        k_a, k_b = counts[0].get(key, 0), counts[1].get(key, 0)
        rate_a, rate_b = _per_minute(k_a, ms_a), _per_minute(k_b, ms_b)
        rows.append(
            {
                "from": key[0],
                "to": key[1],
                "only_in": _only(k_a > 0, k_b > 0),
                "a": {"count": k_a, "per_minute": rate_a},
                "b": {"count": k_b, "per_minute": rate_b},
                "change": {"per_minute": round(rate_a - rate_b, 4), "significant": rate_test(k_a, ms_a, k_b, ms_b)},
            }
        )
    rows.sort(key=lambda r: change_key(r["only_in"] is not None, r["change"]["per_minute"], r["from"], r["to"]))
    return rows


def compare_sections(
    a: dict[str, Any], b: dict[str, Any], tick_ms_a: float, tick_ms_b: float, window_ms: float = WINDOW_MS
) -> list[dict[str, Any]]:
    """Per option of two profile sections (docs/profile.md ``SECTION``): the rows of the comparison."""
    ms_a, ms_b = a["ticks"] * tick_ms_a, b["ticks"] * tick_ms_b
    rows = []
    for name in sorted(a["options"].keys() | b["options"].keys()):
        option_a, option_b = a["options"].get(name), b["options"].get(name)
        share = _share_row(
            option_a["share"] if option_a else 0.0, option_b["share"] if option_b else 0.0, ms_a, ms_b, window_ms
        )
        activity = _activity(option_a, option_b, ms_a, ms_b)
        # a state's share is of its option's time: where the option's decisions differ
        in_a = option_a["active_ms"] if option_a else 0.0
        in_b = option_b["active_ms"] if option_b else 0.0
        states = []
        states_a = option_a["states"] if option_a else {}
        states_b = option_b["states"] if option_b else {}
        for state in sorted(states_a.keys() | states_b.keys()):
            sa, sb = states_a.get(state), states_b.get(state)
            state_share = _share_row(
                sa["active_ms"] / in_a if sa and in_a else 0.0,
                sb["active_ms"] / in_b if sb and in_b else 0.0,
                in_a,
                in_b,
                window_ms,
            )
            state_activity = _activity(sa, sb, ms_a, ms_b)
            states.append(
                {
                    "option": name,
                    "state": state,
                    "only_in": _only(sa is not None, sb is not None),
                    "a": {**state_share[0], **state_activity[0]},
                    "b": {**state_share[1], **state_activity[1]},
                    "change": {**state_share[2], **state_activity[2]},
                }
            )
        states.sort(key=lambda r: change_key(r["only_in"] is not None, r["change"]["share"], r["state"]))
        rows.append(
            {
                "option": name,
                "only_in": _only(option_a is not None, option_b is not None),
                "a": {**share[0], **activity[0]},
                "b": {**share[1], **activity[1]},
                "change": {**share[2], **activity[2]},
                "states": states,
                "transitions": _transitions(option_a, option_b, ms_a, ms_b),
            }
        )
    rows.sort(key=lambda r: change_key(r["only_in"] is not None, r["change"]["share"], r["option"]))
    return rows


def _side(report: dict[str, Any], team: str) -> dict[str, Any]:
    section = report["teams"][team]
    return {
        "recording": report["recording"],
        "seed": report["seed"],
        "team": team,
        "agents": section["agents"],
        "ticks": section["ticks"],
        "robot_seconds": round(section["ticks"] * report["tick_ms"] / 1000.0, 3),
    }


def compare_reports(
    a: dict[str, Any],
    b: dict[str, Any],
    team: str | None = None,
    against_team: str | None = None,
    window_ms: float = WINDOW_MS,
) -> dict[str, Any]:
    """The behavioral diff of two profile reports (docs/compare.md).

    Raises:
        ProfileError: a named team that is not there, nothing to compare, a bad window.
    """
    if not (isinstance(window_ms, int | float) and 0 < window_ms < float("inf")):
        raise ProfileError(f"the window must be a positive number of ms, got {window_ms!r}")
    comparisons = []
    for team_a, team_b in pair_teams(a, b, team, against_team):
        comparisons.append(
            {
                "a": _side(a, team_a),
                "b": _side(b, team_b),
                "options": compare_sections(
                    a["teams"][team_a], b["teams"][team_b], a["tick_ms"], b["tick_ms"], window_ms
                ),
            }
        )
    return {"format": FORMAT, "window_ms": window_ms, "interval": INTERVAL, "comparisons": comparisons}
