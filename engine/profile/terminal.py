"""The profile report as rich tables in a terminal (``xabsl profile`` without ``--json``)."""

from __future__ import annotations

from typing import Any

from rich.console import Console
from rich.table import Table

__all__ = ["print_report"]


def _options_table(title: str, section: dict[str, Any]) -> Table:
    table = Table(title=title, title_justify="left", show_lines=False)
    for column in ("option / state", "share", "activations", "mean ms", "longest ms", "at tick"):
        table.add_column(column, justify="left" if column == "option / state" else "right")
    for name, option in section["options"].items():
        table.add_row(
            f"[bold]{name}[/]",
            f"{100 * option['share']:.1f} %",
            str(option["activations"]),
            f"{option['mean_ms']:.0f}",
            f"{option['longest_ms']:.0f}",
            str(option["longest_at_seq"]),
        )
        for state, s in option["states"].items():
            table.add_row(
                f"  {state}",
                f"{100 * s['share']:.1f} %",
                str(s["activations"]),
                f"{s['mean_ms']:.0f}",
                f"{s['longest_ms']:.0f}",
                str(s["longest_at_seq"]),
            )
    return table


def _transitions_table(section: dict[str, Any]) -> Table:
    table = Table(title="transitions (from -> to, leaf)", title_justify="left")
    for column in ("option", "from", "to", "leaf", "count"):
        table.add_column(column, justify="right" if column in ("leaf", "count") else "left")
    for name, option in section["options"].items():
        for t in option["transitions"]:
            table.add_row(name, t["from"], t["to"], str(t["leaf"]), str(t["count"]))
    return table


def _coverage_line(section: dict[str, Any]) -> str:
    c = section["coverage"]
    return "coverage: " + ", ".join(
        f"{part} {c[part]['reached']}/{c[part]['total']} ({c[part]['percent']:.1f} %)"
        for part in ("options", "states", "transitions", "leaves")
    )


def print_report(report: dict[str, Any], console: Console | None = None, details: bool = True) -> None:
    """Print ``report`` (:func:`xabsl_studio.engine.profile.profile`): per team and agent tables, coverage."""
    console = console or Console()
    console.print(
        f"[bold]{report['recording']}[/]: {report['ticks']} ticks ({report['duration_ms'] / 1000:.1f} s), "
        f"{len(report['agents'])} agents; {report['cpu_note']}"
    )
    for key, team in report["teams"].items():
        console.print(_options_table(f"team {key} ({', '.join(team['agents'])})", team))
        console.print(_transitions_table(team))
        console.print(_coverage_line(team))
        never = team["coverage"]
        if never["options"]["never"]:
            console.print("  never active: " + ", ".join(never["options"]["never"]))
        if never["states"]["never"]:
            console.print("  never entered: " + ", ".join(never["states"]["never"]))
    if details:
        for name, agent in report["agents"].items():
            console.print(_options_table(f"agent {name} ({agent['program']})", agent))
            console.print(_coverage_line(agent) + f"; {agent['oscillations']} oscillations")
    oscillations = report["oscillations"]
    table = Table(
        title=f"oscillations (re-entered within {report['oscillation_ms']:g} ms): {len(oscillations)}",
        title_justify="left",
    )
    for column in ("agent", "kind", "option", "state", "via", "left tick", "back tick", "t ms", "away ms"):
        table.add_column(column)
    for o in oscillations[:200]:
        table.add_row(
            o["agent"],
            o["kind"],
            o["option"],
            o["state"] or "",
            " -> ".join(o["via"]),
            str(o["left_seq"]),
            str(o["reentered_seq"]),
            str(o["left_t"]),
            f"{o['away_ms']:.0f}",
        )
    console.print(table)
    if len(oscillations) > 200:
        console.print(f"... and {len(oscillations) - 200} more (--json has them all)")
