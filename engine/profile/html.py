"""The profile report as one self-contained HTML file (inline CSS, JS and SVG; no network).

Per team (program key): coverage figures, the option graph coloured by coverage (never-active
options grey and dashed, the others green by their share of time), each option's state machine
with transition counts (never-taken transitions dashed), the option and state table; per agent
the per-option activity over time (one row per option, a bar per activation); the oscillation
list. Graphs are laid out by Graphviz ``dot`` (as ``xabsl_studio.engine.docs`` does); without it the report
says so and keeps everything else.
"""

from __future__ import annotations

import html
import re
from typing import Any

from xabsl_studio.engine.emit.dot import GraphvizMissing, quote

__all__ = ["html_report"]

_STYLE = """
body{font:14px/1.4 system-ui,Helvetica,Arial,sans-serif;margin:0;color:#222;background:#fafafa}
header{background:#23395d;color:#fff;padding:10px 18px}header h1{font-size:18px;margin:0}
main{padding:10px 18px}section{background:#fff;border:1px solid #ddd;border-radius:6px;padding:8px 14px;margin:12px 0}
table{border-collapse:collapse;margin:6px 0}td,th{padding:2px 8px;border-bottom:1px solid #eee;text-align:right}
td:first-child,th:first-child{text-align:left}tr.state td:first-child{padding-left:22px;color:#555}
.never{color:#999}.bar{fill:#3b7dd8}.row:hover{fill:#eef3fb}.graph svg{max-width:100%;height:auto}
details{margin:4px 0}summary{cursor:pointer;font-weight:600}.note{color:#a55}
.cov{display:inline-block;margin-right:16px}.cov b{font-size:18px}
"""

_SCRIPT = """
document.querySelectorAll('select[data-agents]').forEach(function(sel){
  function show(){document.querySelectorAll('.activity').forEach(function(el){
    el.style.display = el.dataset.agent === sel.value ? '' : 'none';});}
  sel.addEventListener('change', show); show();
});
"""

_WIDTH = 960
_ROW = 14
_LABEL = 170


def _e(text: object) -> str:
    return html.escape(str(text), quote=True)


def _colour(share: float) -> str:
    """Green by share of time: light for rarely active, darker for often."""
    level = max(0.0, min(1.0, share)) ** 0.5
    r, g, b = (int(232 - 150 * level), int(245 - 70 * level), int(233 - 150 * level))
    return f"#{r:02x}{g:02x}{b:02x}"


def _option_graph_dot(description: dict[str, Any], team: dict[str, Any]) -> str:
    lines = ["digraph option_graph {", '  graph [rankdir=LR, fontname="Helvetica", bgcolor="transparent"];']
    lines.append('  node [fontname="Helvetica", fontsize=11]; edge [arrowsize=0.7];')
    stats = team["options"]
    behaviors = description["behaviors"]
    used: set[int] = set()
    for option in description["options"]:
        name = option["name"]
        s = stats.get(name)
        if s is None:
            style, fill, tip = '"rounded,filled,dashed"', "#eeeeee", f"{name}: never active"
        else:
            style, fill = '"rounded,filled"', _colour(s["share"])
            tip = f"{name}: {100 * s['share']:.1f} % of the time, {s['activations']} activations"
        lines.append(
            f"  {quote('o:' + name)} [id={quote('option_' + str(option['id']))}, label={quote(name)}, shape=box, "
            f"style={style}, fillcolor={quote(fill)}, fontcolor={quote('#222' if s else '#888')}, "
            f"tooltip={quote(tip)}];"
        )
        called: list[tuple[str, str]] = []
        for state in option["states"]:
            for action in state["actions"]:
                kind = {"option": "o", "behavior": "b"}.get(action["type"])
                if kind and (kind, action["name"]) not in called:
                    called.append((kind, action["name"]))
        for kind, callee in called:
            if kind == "b":
                used.update(b["id"] for b in behaviors if b["name"] == callee)
            edge_style = "solid" if s is not None and (kind == "b" or callee in stats) else "dashed"
            lines.append(f"  {quote('o:' + name)} -> {quote(kind + ':' + callee)} [style={edge_style}];")
    for behavior in behaviors:
        if behavior["id"] in used:
            lines.append(
                f"  {quote('b:' + behavior['name'])} [id={quote('behavior_' + str(behavior['id']))}, "
                f'label={quote(behavior["name"])}, shape=ellipse, style=filled, fillcolor="#f4f4f4"];'
            )
    lines.append("}")
    return "\n".join(lines) + "\n"


def _state_machine_dot(option: dict[str, Any], stats: dict[str, Any] | None) -> str:
    name = option["name"]
    states = stats["states"] if stats else {}
    counts = {(t["from"], t["leaf"]): t["count"] for t in (stats["transitions"] if stats else [])}
    lines = [f"digraph {quote('option ' + name)} {{", '  graph [rankdir=LR, bgcolor="transparent"];']
    lines.append('  node [fontname="Helvetica", fontsize=12]; edge [fontname="Helvetica", fontsize=9];')
    for state in option["states"]:
        s = states.get(state["name"])
        fill = _colour(s["share"]) if s else "#eeeeee"
        tip = (
            f"{state['name']}: {100 * s['share']:.1f} %, {s['activations']} activations, mean {s['mean_ms']:.0f} ms"
            if s
            else f"{state['name']}: never active"
        )
        shape = "doublecircle" if state["target"] else "box"
        lines.append(
            f"  {quote('s:' + state['name'])} [id={quote('state_' + str(state['id']))}, label={quote(state['name'])}, "
            f'shape={shape}, style="{"rounded," if shape == "box" else ""}filled{"" if s else ",dashed"}", '
            f"fillcolor={quote(fill)}, tooltip={quote(tip)}];"
        )
    ids = {s["name"]: s["id"] for s in option["states"]}
    for t in option["transitions"]:
        if t["stay"] or t["to"] == t["from"] or t["to"] not in ids:
            continue
        n = counts.get((t["from"], t["leaf"]), 0)
        style = 'color="#2a6f2a", penwidth=1.6' if n else 'style=dashed, color="#aaaaaa", fontcolor="#999999"'
        edge_id = quote(f"leaf_{ids[t['from']]}_{t['leaf']}")
        label = quote(f"leaf {t['leaf']}: {n}")
        lines.append(f"  {quote('s:' + t['from'])} -> {quote('s:' + t['to'])} [id={edge_id}, label={label}, {style}];")
    lines.append("}")
    return "\n".join(lines) + "\n"


_SCRIPT_TAG = re.compile(r"<script", re.IGNORECASE)


def _inline_svg(svg: str) -> str:
    start = svg.find("<svg")
    svg = svg[start:] if start >= 0 else svg
    # Graphviz writes xlink:href only for URLs (none here); drop its comments for a smaller file
    svg = re.sub(r"<!--.*?-->", "", svg, flags=re.DOTALL)
    return _SCRIPT_TAG.sub("&lt;script", svg)


def _activity_svg(report: dict[str, Any], agent: str) -> str:
    activity = report["activity"][agent]
    ticks = max(1, report["ticks"])
    span = _WIDTH - _LABEL
    rows = [name for name in report["agents"][agent]["options"]]
    height = _ROW * len(rows) + 24
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{_WIDTH}" height="{height}" '
        f'viewBox="0 0 {_WIDTH} {height}" font-size="11" font-family="Helvetica,Arial,sans-serif">'
    ]
    for i, name in enumerate(rows):
        y = i * _ROW
        parts.append(f'<rect class="row" x="0" y="{y}" width="{_WIDTH}" height="{_ROW}" fill="transparent"/>')
        parts.append(f'<text x="4" y="{y + 11}">{_e(name)}</text>')
        # intervals merged to pixel columns: a 10-minute match has thousands of short activations
        last_end = -1.0
        merged: list[list[float]] = []
        for start, stop in activity.get(name, []):
            x0 = _LABEL + span * start / ticks
            x1 = max(x0 + 0.6, _LABEL + span * stop / ticks)
            if merged and x0 <= last_end + 0.5:
                merged[-1][1] = max(merged[-1][1], x1)
                merged[-1][2] += 1
            else:
                merged.append([x0, x1, 1, start, stop])
            last_end = merged[-1][1]
        for x0, x1, n, start, _stop in merged:
            parts.append(
                f'<rect class="bar" x="{x0:.1f}" y="{y + 2}" width="{x1 - x0:.1f}" height="{_ROW - 4}">'
                f"<title>{_e(name)}: {int(n)} activation(s) from tick {int(start)}</title></rect>"
            )
    seconds = report["duration_ms"] / 1000
    for k in range(11):
        x = _LABEL + span * k / 10
        parts.append(f'<line x1="{x:.1f}" y1="0" x2="{x:.1f}" y2="{height - 20}" stroke="#ddd"/>')
        parts.append(f'<text x="{x:.1f}" y="{height - 6}" text-anchor="middle">{seconds * k / 10:.0f} s</text>')
    parts.append("</svg>")
    return "".join(parts)


def _coverage_html(coverage: dict[str, Any]) -> str:
    return "".join(
        f'<span class="cov">{part}: <b>{coverage[part]["percent"]:.1f} %</b> '
        f"({coverage[part]['reached']}/{coverage[part]['total']})</span>"
        for part in ("options", "states", "transitions", "leaves")
    )


def _options_html(section: dict[str, Any], description: dict[str, Any]) -> str:
    rows = ["<table><tr><th>option / state</th><th>share</th><th>activations</th><th>mean ms</th>"]
    rows.append("<th>longest ms</th><th>at tick</th></tr>")
    for option in description["options"]:
        s = section["options"].get(option["name"])
        if s is None:
            rows.append(f'<tr class="never"><td>{_e(option["name"])}</td><td colspan="5">never active</td></tr>')
            continue
        rows.append(
            f"<tr><td><b>{_e(option['name'])}</b></td><td>{100 * s['share']:.1f} %</td><td>{s['activations']}</td>"
            f"<td>{s['mean_ms']:.0f}</td><td>{s['longest_ms']:.0f}</td><td>{s['longest_at_seq']}</td></tr>"
        )
        for state in option["states"]:
            t = s["states"].get(state["name"])
            if t is None:
                rows.append(
                    f'<tr class="state never"><td>{_e(state["name"])}</td><td colspan="5">never active</td></tr>'
                )
                continue
            rows.append(
                f'<tr class="state"><td>{_e(state["name"])}</td><td>{100 * t["share"]:.1f} %</td>'
                f"<td>{t['activations']}</td><td>{t['mean_ms']:.0f}</td><td>{t['longest_ms']:.0f}</td>"
                f"<td>{t['longest_at_seq']}</td></tr>"
            )
    rows.append("</table>")
    return "".join(rows)


def html_report(report: dict[str, Any], descriptions: dict[str, dict[str, Any]]) -> str:
    """The report page (``descriptions``: program key -> the program description coverage counts against)."""
    from xabsl_studio.engine.docs.graphs import GraphLayoutError, render_all

    dots: list[str] = []
    slots: list[tuple[str, str | None]] = []  # (program key, option name or None for the graph)
    for key, team in report["teams"].items():
        description = descriptions[key]
        dots.append(_option_graph_dot(description, team))
        slots.append((key, None))
        for option in description["options"]:
            dots.append(_state_machine_dot(option, team["options"].get(option["name"])))
            slots.append((key, option["name"]))
    svgs: dict[tuple[str, str | None], str] = {}
    note = ""
    try:
        for slot, svg in zip(slots, render_all(dots), strict=True):
            svgs[slot] = _inline_svg(svg)
    except (GraphvizMissing, GraphLayoutError) as error:
        note = f'<p class="note">No graphs: {_e(error)}</p>'
    out = [
        '<!DOCTYPE html><html lang="en"><head><meta charset="utf-8">',
        f"<title>Profile of {_e(report['recording'])}</title><style>{_STYLE}</style></head><body>",
        f"<header><h1>Profile of {_e(report['recording'])}</h1>",
        f"<div>{report['ticks']} ticks, {report['duration_ms'] / 1000:.1f} s, {len(report['agents'])} agents; "
        f"oscillation threshold {report['oscillation_ms']:g} ms; {_e(report['cpu_note'])}</div></header><main>",
        note,
    ]
    for key, team in report["teams"].items():
        description = descriptions[key]
        out.append(f'<section id="team-{_e(key)}"><h2>Team {_e(key)}: {_e(", ".join(team["agents"]))}</h2>')
        out.append(f"<p>{_coverage_html(team['coverage'])}</p>")
        if (key, None) in svgs:
            out.append(f'<h3>Option graph</h3><div class="graph">{svgs[(key, None)]}</div>')
        out.append(_options_html(team, description))
        for option in description["options"]:
            stats = team["options"].get(option["name"])
            label = "never active" if stats is None else f"{100 * stats['share']:.1f} %"
            out.append(f"<details><summary>{_e(option['name'])} ({label})</summary>")
            if (key, option["name"]) in svgs:
                out.append(f'<div class="graph">{svgs[(key, option["name"])]}</div>')
            if stats and stats["transitions"]:
                out.append("<table><tr><th>from</th><th>to</th><th>leaf</th><th>count</th></tr>")
                out.extend(
                    f"<tr><td>{_e(t['from'])}</td><td>{_e(t['to'])}</td><td>{t['leaf']}</td><td>{t['count']}</td></tr>"
                    for t in stats["transitions"]
                )
                out.append("</table>")
            out.append("</details>")
        out.append("</section>")
    agents = list(report["agents"])
    if agents:
        out.append('<section id="activity"><h2>Activity over time</h2><label>agent <select data-agents="1">')
        out.extend(f'<option value="{_e(a)}">{_e(a)}</option>' for a in agents)
        out.append("</select></label>")
        for agent in agents:
            section = report["agents"][agent]
            out.append(
                f'<div class="activity" data-agent="{_e(agent)}"><p>{_e(agent)} ({_e(section["program"])}): '
                f"{_coverage_html(section['coverage'])}</p>{_activity_svg(report, agent)}</div>"
            )
        out.append("</section>")
    oscillations = report["oscillations"]
    out.append(f'<section id="oscillations"><h2>Oscillations ({len(oscillations)})</h2>')
    out.append("<table><tr><th>agent</th><th>kind</th><th>option</th><th>state</th><th>via</th>")
    out.append("<th>left tick</th><th>back tick</th><th>t ms</th><th>away ms</th></tr>")
    out.extend(
        f"<tr><td>{_e(o['agent'])}</td><td>{o['kind']}</td><td>{_e(o['option'])}</td><td>{_e(o['state'] or '')}</td>"
        f"<td>{_e(' → '.join(o['via']))}</td><td>{o['left_seq']}</td><td>{o['reentered_seq']}</td>"
        f"<td>{o['left_t']}</td><td>{o['away_ms']:.0f}</td></tr>"
        for o in oscillations[:2000]
    )
    out.append("</table></section></main>")
    out.append(f"<script>{_SCRIPT}</script></body></html>\n")
    return "".join(out)
