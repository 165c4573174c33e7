"""The behavioral diff (:mod:`xabsl_studio.engine.profile.against`) as rich tables and as one HTML page.

Both show the rows in the document's order (one-sided first, then by the size of the change): per
comparison the options, then the states with the largest changes of their share of the option's
time, then the transitions whose rate changed most. A significant change is marked ``*``.
"""

from __future__ import annotations

import html
from typing import Any

from rich.console import Console
from rich.table import Table

from xabsl_studio.engine.profile.stats import change_key

__all__ = ["html_report", "print_report", "states_of", "transitions_of"]

#: Rows of the state and transition tables printed (JSON and HTML have all).
TOP = 15


def _percent(x: float) -> str:
    return f"{100 * x:.1f} %"


def _points(change: dict[str, Any]) -> str:
    return f"{100 * change['share']:+.1f}" + (" *" if change["significant"] else "")


def _interval(change: dict[str, Any]) -> str:
    low, high = change["share_ci95"]
    return f"[{100 * low:+.1f}, {100 * high:+.1f}]"


def _only(row: dict[str, Any]) -> str:
    return f" (only {row['only_in'].upper()})" if row["only_in"] else ""


def _mean(x: float | None) -> str:
    return "-" if x is None else f"{x:.0f}"


def states_of(comparison: dict[str, Any]) -> list[dict[str, Any]]:
    """The state rows of the options both sides ran, in the order of the change (as each option's are).

    The states of an option that ran on one side only are in its row already (the document keeps them).
    """
    rows = [s for option in comparison["options"] if option["only_in"] is None for s in option["states"]]
    return sorted(
        rows, key=lambda r: change_key(r["only_in"] is not None, r["change"]["share"], r["option"], r["state"])
    )


def transitions_of(comparison: dict[str, Any]) -> list[dict[str, Any]]:
    """Every transition row with its option, in the order of the change of rate."""
    rows = [{"option": o["option"], **t} for o in comparison["options"] for t in o["transitions"]]
    return sorted(
        rows,
        key=lambda r: change_key(r["only_in"] is not None, r["change"]["per_minute"], r["option"], r["from"], r["to"]),
    )


def _title(comparison: dict[str, Any]) -> str:
    a, b = comparison["a"], comparison["b"]
    return f"A {a['recording']} [{a['team']}]  vs  B {b['recording']} [{b['team']}]"


def print_report(document: dict[str, Any], console: Console | None = None) -> None:
    """Print every comparison of the document as tables."""
    if console is None:
        console = Console(highlight=False)
        if not console.is_terminal:  # a file or a pipe: wide enough that rows do not wrap
            console = Console(highlight=False, width=160)
    for comparison in document["comparisons"]:
        a, b = comparison["a"], comparison["b"]
        console.print(_title(comparison), style="bold", markup=False)
        console.print(
            f"robot time: A {a['robot_seconds']:.0f} s ({len(a['agents'])} robots), "
            f"B {b['robot_seconds']:.0f} s ({len(b['agents'])} robots); change = A - B in points, "
            f"* significant ({document['interval']}, windows of {document['window_ms']:.0f} ms)",
            markup=False,
        )
        options = Table(
            title="options: share of robot time (one side only first, then by the change)", title_justify="left"
        )
        for name in ("option", "A", "B", "change", "95 % interval", "act/min A", "B", "mean ms A", "B"):
            options.add_column(name, justify="left" if name == "option" else "right")
        for row in comparison["options"]:
            options.add_row(
                row["option"] + _only(row),
                _percent(row["a"]["share"]),
                _percent(row["b"]["share"]),
                _points(row["change"]),
                _interval(row["change"]),
                f"{row['a']['per_minute']:.2f}",
                f"{row['b']['per_minute']:.2f}" + (" *" if row["change"]["per_minute_significant"] else ""),
                _mean(row["a"]["mean_ms"]),
                _mean(row["b"]["mean_ms"]),
            )
        console.print(options)
        states = Table(title="states: share of their option's time (largest changes)", title_justify="left")
        for name in ("option/state", "A", "B", "change", "95 % interval", "act/min A", "B"):
            states.add_column(name, justify="left" if name == "option/state" else "right")
        for row in states_of(comparison)[:TOP]:
            states.add_row(
                f"{row['option']}/{row['state']}" + _only(row),
                _percent(row["a"]["share"]),
                _percent(row["b"]["share"]),
                _points(row["change"]),
                _interval(row["change"]),
                f"{row['a']['per_minute']:.2f}",
                f"{row['b']['per_minute']:.2f}" + (" *" if row["change"]["per_minute_significant"] else ""),
            )
        console.print(states)
        transitions = Table(title="transitions taken per minute of robot time (largest changes)", title_justify="left")
        for name in ("option: from -> to", "A", "B", "change"):
            transitions.add_column(name, justify="left" if name.startswith("option") else "right")
        for row in transitions_of(comparison)[:TOP]:
            transitions.add_row(
                f"{row['option']}: {row['from']} -> {row['to']}" + _only(row),
                f"{row['a']['per_minute']:.2f}",
                f"{row['b']['per_minute']:.2f}",
                f"{row['change']['per_minute']:+.2f}" + (" *" if row["change"]["significant"] else ""),
            )
        console.print(transitions)


# -- HTML ------------------------------------------------------------------------------------------

_STYLE = """
body { font: 14px/1.4 system-ui, sans-serif; margin: 2em; color: #222; }
table { border-collapse: collapse; margin: 1em 0 2em; }
th, td { padding: 2px 10px; border-bottom: 1px solid #ddd; text-align: right; }
th:first-child, td:first-child { text-align: left; }
caption { text-align: left; font-weight: bold; padding: 4px 0; }
.bar { display: inline-block; height: 9px; background: #3b6fd6; vertical-align: middle; }
.bar.b { background: #d64a3b; }
.sig { font-weight: bold; }
"""


def _bar(share: float, side: str) -> str:
    return f'<span class="bar {side}" style="width:{max(1, round(120 * share))}px"></span> {_percent(share)}'


def _table(caption: str, header: list[str], rows: list[list[str]]) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{cell}</td>" for cell in row) + "</tr>" for row in rows)
    return f"<table><caption>{html.escape(caption)}</caption><tr>{head}</tr>{body}</table>"


def _change_cell(change: dict[str, Any]) -> str:
    text = html.escape(_points(change))
    return f"<span class='sig'>{text}</span>" if change["significant"] else text


def html_report(document: dict[str, Any]) -> str:
    """The document as one self-contained HTML page (inline CSS, no script)."""
    e = html.escape
    titles = [_title(c) for c in document["comparisons"]]
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>{e(titles[0] if titles else '')}</title>"]
    parts.append(f"<style>{_STYLE}</style></head><body>")
    parts.append(
        f"<p>change = A − B in points of share; <b>bold</b> and * significant: {e(document['interval'])}, "
        f"windows of {document['window_ms']:.0f} ms of robot time.</p>"
    )
    for title, comparison in zip(titles, document["comparisons"], strict=True):
        parts.append(f"<h1>{e(title)}</h1>")
        parts.append(
            _table(
                "options: share of robot time",
                ["option", "A", "B", "change", "95 % interval", "activations/min A", "B", "mean ms A", "B"],
                [
                    [
                        e(row["option"] + _only(row)),
                        _bar(row["a"]["share"], "a"),
                        _bar(row["b"]["share"], "b"),
                        _change_cell(row["change"]),
                        e(_interval(row["change"])),
                        f"{row['a']['per_minute']:.2f}",
                        f"{row['b']['per_minute']:.2f}",
                        _mean(row["a"]["mean_ms"]),
                        _mean(row["b"]["mean_ms"]),
                    ]
                    for row in comparison["options"]
                ],
            )
        )
        parts.append(
            _table(
                "states: share of their option's time",
                ["option/state", "A", "B", "change", "95 % interval", "activations/min A", "B"],
                [
                    [
                        e(f"{row['option']}/{row['state']}" + _only(row)),
                        _bar(row["a"]["share"], "a"),
                        _bar(row["b"]["share"], "b"),
                        _change_cell(row["change"]),
                        e(_interval(row["change"])),
                        f"{row['a']['per_minute']:.2f}",
                        f"{row['b']['per_minute']:.2f}",
                    ]
                    for row in states_of(comparison)
                ],
            )
        )
        parts.append(
            _table(
                "transitions taken per minute of robot time",
                ["option: from → to", "A", "B", "change"],
                [
                    [
                        e(f"{row['option']}: {row['from']} → {row['to']}" + _only(row)),
                        f"{row['a']['per_minute']:.2f}",
                        f"{row['b']['per_minute']:.2f}",
                        f"{row['change']['per_minute']:+.2f}" + (" *" if row["change"]["significant"] else ""),
                    ]
                    for row in transitions_of(comparison)
                ],
            )
        )
    parts.append("</body></html>\n")
    return "".join(parts)
