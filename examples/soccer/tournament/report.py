"""A tournament's report: results with confidence intervals, statistics, activation differences.

:func:`summarize` turns the match results (:func:`~.match.play`) into one JSON-ready dict,
:func:`print_report` prints it (rich tables), :func:`html_report` renders it as one
self-contained HTML file (inline CSS, no scripts, no external files).

Statistics:

* wins, draws and losses of HOME; the 95 % confidence intervals are **Wilson score intervals**
  on the win rate and on the loss rate (binomial, matches independent; draws are neither);
* goal difference, total and per match;
* per version, the mean per match of the team statistics ``xabsl run --json`` reports (goals,
  shots, passes, kicks, possession);
* activations: per option, the share of robot ticks it was active, per version, and the
  difference; per state, the share of its option's ticks spent in it and how often it was
  entered per match. Options (and states) that only one version runs come first (they are the
  biggest change there is), then the rest by the size of the difference; the terminal's top rows
  and the HTML tables follow that one order. These say which options run more or less and where
  the decisions differ.
"""

from __future__ import annotations

import html
import math
import os
import urllib.parse
from collections.abc import Sequence
from typing import Any

from xabsl_studio.examples.soccer.tournament.match import SIDES

#: z for a two-sided 95 % interval.
Z95 = 1.959963984540054
TEAM_STATS = ("goals", "shots", "passes", "kicks", "possession")
#: rows of the activation tables printed (JSON and HTML have all)
TOP = 12


def wilson(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval of a binomial proportion ``successes / n`` ((0, 1) when n is 0)."""
    if n == 0:
        return (0.0, 1.0)
    p = successes / n
    denominator = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denominator
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4 * n * n)) / denominator
    return (max(0.0, centre - half), min(1.0, centre + half))


def _outcome(result: dict[str, Any]) -> str:
    home, away = result["score"]["home"], result["score"]["away"]
    return "win" if home > away else "loss" if home < away else "draw"


def summarize(
    results: Sequence[dict[str, Any]],
    *,
    home: str,
    away: str,
    planned: int,
    wall_seconds: float,
    jobs: int,
    backend: str,
    interrupted: bool = False,
) -> dict[str, Any]:
    """The report of a tournament as JSON-ready data (see the module docstring)."""
    results = sorted(results, key=lambda r: r["index"])
    played = [r for r in results if r["ok"]]
    failed = [
        {"index": r["index"], "seed": r["seed"], "home_colour": r["home_colour"], "error": r["error"]}
        for r in results
        if not r["ok"]
    ]
    n = len(played)
    outcomes = [_outcome(r) for r in played]
    wins, draws, losses = (outcomes.count(k) for k in ("win", "draw", "loss"))
    goals = {side: sum(r["score"][side] for r in played) for side in SIDES}
    cpu = sum(r["cpu_seconds"] for r in played)
    sim = sum(r["sim_seconds"] for r in played)
    return {
        "home": home,
        "away": away,
        "planned": planned,
        "played": n,
        "interrupted": interrupted,
        "results": {
            "wins": wins,
            "draws": draws,
            "losses": losses,
            "win_rate": round(wins / n, 4) if n else None,
            "win_rate_ci95": [round(x, 4) for x in wilson(wins, n)],
            "loss_rate": round(losses / n, 4) if n else None,
            "loss_rate_ci95": [round(x, 4) for x in wilson(losses, n)],
            "interval": "Wilson score interval, 95 %",
        },
        "goals": {
            **goals,
            "difference": goals["home"] - goals["away"],
            "difference_per_match": round((goals["home"] - goals["away"]) / n, 3) if n else None,
        },
        "teams": {
            side: {key: round(sum(r["teams"][side][key] for r in played) / n, 3) if n else None for key in TEAM_STATS}
            for side in SIDES
        },
        "activations": _option_differences(played),
        "states": _state_differences(played),
        "failed": failed,
        "faults": [{"index": r["index"], "seed": r["seed"], "fault": f} for r in played for f in r["faults"]],
        "matches": [
            {
                "index": r["index"],
                "seed": r["seed"],
                "home_colour": r["home_colour"],
                **(
                    {"score": r["score"], "result": _outcome(r), "trace_hash": r["trace_hash"]}
                    if r["ok"]
                    else {"error": r["error"]}
                ),
                **({"recording": r["recording"]} if "recording" in r else {}),
            }
            for r in results
        ],
        "throughput": {
            "backend": backend,
            "jobs": jobs,
            "wall_seconds": round(wall_seconds, 3),
            "cpu_seconds": round(cpu, 3),
            "matches_per_hour": round(3600.0 * n / wall_seconds, 1) if wall_seconds > 0 else None,
            "matches_per_core_hour": round(3600.0 * n / cpu, 1) if cpu > 0 else None,
            "real_time_factor_per_core": round(sim / cpu, 1) if cpu > 0 else None,
        },
    }


def _sum(played: Sequence[dict[str, Any]], key: str, side: str) -> dict[str, Any]:
    total: dict[str, Any] = {}
    for r in played:
        for name, value in r[key][side].items():
            if isinstance(value, list):
                had = total.setdefault(name, [0] * len(value))
                total[name] = [a + b for a, b in zip(had, value, strict=True)]
            else:
                total[name] = total.get(name, 0) + value
    return total


def _option_differences(played: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per option: share of robot ticks active per version, sorted by the size of the difference."""
    rows = []
    ticks = {side: sum(r["robot_ticks"][side] for r in played) or 1 for side in SIDES}
    counts = {side: _sum(played, "activations", side) for side in SIDES}
    for option in sorted(counts["home"].keys() | counts["away"].keys()):
        share = {side: counts[side].get(option, 0) / ticks[side] for side in SIDES}
        rows.append(
            {
                "option": option,
                "home": round(share["home"], 5),
                "away": round(share["away"], 5),
                "difference": round(share["home"] - share["away"], 5),
                "only_in": _only_in(option, counts),
            }
        )
    rows.sort(key=_by_change)
    return rows


def _by_change(row: dict[str, Any]) -> tuple[bool, float, str, str]:
    """The report's order: what only one version runs first, then the largest differences."""
    return (row["only_in"] is None, -abs(row["difference"]), row["option"], row.get("state", ""))


def _only_in(name: str, counts: dict[str, dict[str, Any]]) -> str | None:
    present = [side for side in SIDES if name in counts[side]]
    return present[0] if len(present) == 1 else None


def _state_differences(played: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per option state: share of the option's ticks and entries per match, per version."""
    n = len(played) or 1
    states = {side: _sum(played, "states", side) for side in SIDES}
    option_ticks: dict[str, dict[str, int]] = {side: {} for side in SIDES}
    for side in SIDES:
        for key, (ticks, _entries) in states[side].items():
            option = key.split("/", 1)[0]
            option_ticks[side][option] = option_ticks[side].get(option, 0) + ticks
    rows = []
    for key in sorted(states["home"].keys() | states["away"].keys()):
        option, state = key.split("/", 1)
        share, entries = {}, {}
        for side in SIDES:
            ticks, entered = states[side].get(key, (0, 0))
            share[side] = ticks / option_ticks[side][option] if option_ticks[side].get(option) else 0.0
            entries[side] = entered / n
        rows.append(
            {
                "option": option,
                "state": state,
                "home": round(share["home"], 5),
                "away": round(share["away"], 5),
                "difference": round(share["home"] - share["away"], 5),
                "home_entries_per_match": round(entries["home"], 2),
                "away_entries_per_match": round(entries["away"], 2),
                "only_in": _only_in(key, states),
            }
        )
    rows.sort(key=_by_change)
    return rows


# -- text ------------------------------------------------------------------------------------------


def _percent(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.1f} %"


def _interval(ci: Sequence[float]) -> str:
    return f"[{100 * ci[0]:.1f}, {100 * ci[1]:.1f}] %"


def headline(summary: dict[str, Any]) -> list[str]:
    """The result lines shared by the printed and the HTML report."""
    r, g, t = summary["results"], summary["goals"], summary["throughput"]
    lines = [
        f"HOME {summary['home']}  vs  AWAY {summary['away']}",
        f"{summary['played']} of {summary['planned']} matches played"
        + (", interrupted" if summary["interrupted"] else "")
        + (f", {len(summary['failed'])} failed" if summary["failed"] else ""),
        f"HOME: {r['wins']} wins, {r['draws']} draws, {r['losses']} losses; "
        f"win rate {_percent(r['win_rate'])} (95 % Wilson {_interval(r['win_rate_ci95'])}), "
        f"loss rate {_percent(r['loss_rate'])} (95 % Wilson {_interval(r['loss_rate_ci95'])})",
        f"goals {g['home']} : {g['away']}, difference {g['difference']:+d}"
        + (f" ({g['difference_per_match']:+.2f} per match)" if g["difference_per_match"] is not None else ""),
        f"{t['backend']}, {t['jobs']} jobs: {t['wall_seconds']:.1f} s wall, "
        f"{t['matches_per_hour'] or 0:.0f} matches per hour, "
        f"{t['matches_per_core_hour'] or 0:.0f} matches per core-hour (worker CPU time), "
        f"{t['real_time_factor_per_core'] or 0:.0f}x real time per core",
    ]
    return lines


def print_report(summary: dict[str, Any]) -> None:
    """Print the report as text and tables (rich) on stdout."""
    from rich.console import Console
    from rich.table import Table

    console = Console(highlight=False)
    if not console.is_terminal:  # a file or a pipe: wide enough that rows do not wrap
        console = Console(highlight=False, width=160)
    lines = headline(summary)
    console.print(lines[0], style="bold", markup=False)
    for line in lines[1:]:
        console.print(line, markup=False)
    for failure in summary["failed"]:
        console.print(
            f"FAILED match {failure['index']} (seed {failure['seed']}, HOME {failure['home_colour']}): "
            f"{failure['error']}",
            markup=False,
        )
    for fault in summary["faults"]:
        console.print(f"fault in match {fault['index']} (seed {fault['seed']}): {fault['fault']}", markup=False)
    recorded = [m for m in summary["matches"] if "recording" in m]
    if recorded:
        folder = os.path.dirname(recorded[0]["recording"])
        console.print(f"{len(recorded)} matches recorded in {folder}", markup=False)
        # the odd ones first: failed matches, then the losses of HOME
        odd = [m for m in recorded if "error" in m] + [m for m in recorded if m.get("result") == "loss"]
        for m in odd[:5]:
            why = "failed" if "error" in m else "HOME lost"
            console.print(f"  match {m['index']} ({why}): xabsl serve --replay {m['recording']}", markup=False)

    teams = Table(title="per match (mean)", title_justify="left")
    teams.add_column("version")
    for key in TEAM_STATS:
        teams.add_column(key, justify="right")
    for side in SIDES:
        stats = summary["teams"][side]
        teams.add_row(
            side.upper(),
            *(
                _percent(stats[k]) if k == "possession" else "-" if stats[k] is None else f"{stats[k]:.2f}"
                for k in TEAM_STATS
            ),
        )
    console.print(teams)

    options = Table(title="options: share of robot ticks active (largest differences)", title_justify="left")
    for name in ("option", "HOME", "AWAY", "difference"):
        options.add_column(name, justify="left" if name == "option" else "right")
    for row in summary["activations"][:TOP]:
        options.add_row(
            row["option"] + _only_note(row),
            _percent(row["home"]),
            _percent(row["away"]),
            f"{100 * row['difference']:+.1f}",
        )
    console.print(options)

    states = Table(title="decisions: share of the option's ticks per state (largest differences)", title_justify="left")
    for name in ("option/state", "HOME", "AWAY", "difference", "entered/match H", "A"):
        states.add_column(name, justify="left" if name == "option/state" else "right")
    for row in summary["states"][:TOP]:
        states.add_row(
            f"{row['option']}/{row['state']}" + _only_note(row),
            _percent(row["home"]),
            _percent(row["away"]),
            f"{100 * row['difference']:+.1f}",
            f"{row['home_entries_per_match']:.1f}",
            f"{row['away_entries_per_match']:.1f}",
        )
    console.print(states)


def _only_note(row: dict[str, Any]) -> str:
    return f" (only {row['only_in'].upper()})" if row["only_in"] else ""


# -- HTML ------------------------------------------------------------------------------------------

_STYLE = """
body { font: 14px/1.4 system-ui, sans-serif; margin: 2em; color: #222; }
table { border-collapse: collapse; margin: 1em 0 2em; }
th, td { padding: 2px 10px; border-bottom: 1px solid #ddd; text-align: right; }
th:first-child, td:first-child { text-align: left; }
caption { text-align: left; font-weight: bold; padding: 4px 0; }
.bar { display: inline-block; height: 9px; background: #3b6fd6; vertical-align: middle; }
.bar.away { background: #d64a3b; }
.failed { color: #b00; }
"""


def _table(caption: str, header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{cell}</td>" for cell in row) + "</tr>" for row in rows)
    return f"<table><caption>{html.escape(caption)}</caption><tr>{head}</tr>{body}</table>"


def _bar(share: float, side: str) -> str:
    return f'<span class="bar {side}" style="width:{max(1, round(120 * share))}px"></span> {_percent(share)}'


def _recording_link(path: str | None, base: str | None) -> str:
    """A link to a match's recording, relative to the report's folder when it is below it."""
    if path is None:
        return ""
    href = path
    if base is not None:
        relative = os.path.relpath(path, base)
        if not relative.startswith(".."):
            href = relative
    name, e = os.path.basename(path), html.escape
    return f"<a href='{e(urllib.parse.quote(href))}' title='xabsl serve --replay {e(path)}'>{e(name)}</a>"


def html_report(summary: dict[str, Any], base: str | None = None) -> str:
    """The report as one self-contained HTML page (``base``: the page's folder, for links to recordings)."""
    e = html.escape
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>{e(headline(summary)[0])}</title>"]
    parts.append(f"<style>{_STYLE}</style></head><body>")
    lines = headline(summary)
    parts.append(f"<h1>{e(lines[0])}</h1>" + "".join(f"<p>{e(line)}</p>" for line in lines[1:]))
    for failure in summary["failed"]:
        parts.append(
            f"<p class='failed'>FAILED match {failure['index']} (seed {failure['seed']}, "
            f"HOME {e(failure['home_colour'])}): {e(failure['error'])}</p>"
        )
    teams = summary["teams"]
    parts.append(
        _table(
            "per match (mean)",
            ["version", *TEAM_STATS],
            [
                [
                    side.upper(),
                    *(
                        _percent(teams[side][k])
                        if k == "possession"
                        else "-"
                        if teams[side][k] is None
                        else f"{teams[side][k]:.2f}"
                        for k in TEAM_STATS
                    ),
                ]
                for side in SIDES
            ],
        )
    )
    parts.append(
        _table(
            "options: share of robot ticks active",
            ["option", "HOME", "AWAY", "difference"],
            [
                [
                    e(row["option"] + _only_note(row)),
                    _bar(row["home"], "home"),
                    _bar(row["away"], "away"),
                    f"{100 * row['difference']:+.2f}",
                ]
                for row in summary["activations"]
            ],
        )
    )
    parts.append(
        _table(
            "decisions: share of the option's ticks per state, entries per match",
            ["option/state", "HOME", "AWAY", "difference", "entered/match HOME", "AWAY"],
            [
                [
                    e(f"{row['option']}/{row['state']}" + _only_note(row)),
                    _bar(row["home"], "home"),
                    _bar(row["away"], "away"),
                    f"{100 * row['difference']:+.2f}",
                    f"{row['home_entries_per_match']:.1f}",
                    f"{row['away_entries_per_match']:.1f}",
                ]
                for row in summary["states"]
            ],
        )
    )
    parts.append(
        _table(
            "matches",
            ["match", "seed", "HOME plays", "score (HOME : AWAY)", "result", "trace hash", "recording"],
            [
                [
                    str(m["index"]),
                    str(m["seed"]),
                    e(m["home_colour"]),
                    f"{m['score']['home']} : {m['score']['away']}"
                    if "score" in m
                    else "<span class='failed'>failed</span>",
                    e(m.get("result", m.get("error", ""))),
                    f"<code>{e(m.get('trace_hash', ''))}</code>",
                    _recording_link(m.get("recording"), base),
                ]
                for m in summary["matches"]
            ],
        )
    )
    parts.append("</body></html>\n")
    return "".join(parts)
