"""A structural diff as the JSON document, as text lines and as one self-contained HTML page.

The document (docs/compare.md, ``xabsl diff --json``, ``GET /api/compare``) is
``{"format": "xabsl-diff/1", "old": SIDE, "new": SIDE, "counts": {...}, "changes": [CHANGE...],
"renames": {...}}``; a ``SIDE`` says what was compared (``spec``, ``title``, ``agents_file``,
``commit``). The page draws the option graph and each changed state machine with the changes
marked (:mod:`xabsl_studio.engine.compare.graphs`) beside the list of changes; without Graphviz it
says so and keeps the list.
"""

from __future__ import annotations

import html
from collections.abc import Mapping
from typing import Any

from xabsl_studio.engine.compare.graphs import COLOURS, Drawings
from xabsl_studio.engine.compare.structure import Change, StructuralDiff

__all__ = ["FORMAT", "SIGNS", "change_line", "document", "html_page", "text_lines"]

#: ``format`` of the document.
FORMAT = "xabsl-diff/1"
#: The sign of each kind of change in the text lines.
SIGNS = {"added": "+", "removed": "-", "changed": "~", "renamed": ">"}


def document(diff: StructuralDiff, old: Mapping[str, Any], new: Mapping[str, Any]) -> dict[str, Any]:
    """The JSON-ready document of ``diff``; ``old``/``new`` describe the two sides (``spec``, ``commit``...)."""
    return {
        "format": FORMAT,
        "old": {"title": diff.old.title, **old},
        "new": {"title": diff.new.title, **new},
        "counts": diff.counts(),
        "changes": [c.as_dict() for c in diff.changes],
        "renames": {
            "options": dict(diff.option_renames),
            "states": {option: dict(states) for option, states in diff.state_renames.items()},
        },
    }


def _summary(change: Change) -> str:
    parts = []
    if change.path is not None and change.kind == "transition":
        target = next((d for d in change.details if d.field == "target"), None)
        to = (target.new if change.change != "removed" else target.old) if target is not None else None
        shown = f" -> {to}" if to and change.change != "changed" else ""  # a changed one says target: a -> b
        parts.append(f"[{' && '.join(change.path) or 'always'}]{shown}")
    elif change.kind not in ("option", "state", "condition"):
        parts.append(change.name)  # the where names options and states; conditions say it in their detail
    for detail in change.details:
        if change.kind == "transition" and detail.field == "target" and change.change != "changed":
            continue
        if detail.old is not None and detail.new is not None:
            parts.append(f"{detail.field}: {detail.old} -> {detail.new}")
        elif detail.new is not None:
            parts.append(f"{detail.field}: {detail.new}")
        elif detail.old is not None:
            parts.append(f"{detail.field} was: {detail.old}")
    return "; ".join(p for p in parts if p)


def change_line(change: Change) -> str:
    """One change as a line: sign, kind, where, what, and the file:line of both sides."""
    where = change.where if change.option is not None else ""
    places = " -> ".join(str(w) for w in (change.old, change.new) if w is not None)
    head = f"{SIGNS[change.change]} {change.change} {change.kind}"
    text = " ".join(p for p in (head, where) if p)
    summary = _summary(change)
    return text + (f": {summary}" if summary else "") + (f"  ({places})" if places else "")


def text_lines(diff: StructuralDiff, old_label: str, new_label: str) -> list[str]:
    """The report as text: a header, then one line per change (program level first, option by option)."""
    counts = diff.counts()
    plural = "" if len(diff.changes) == 1 else "s"
    lines = [
        f"OLD {old_label}  vs  NEW {new_label}",
        f"{len(diff.changes)} change{plural}: {counts['added']} added, {counts['removed']} removed, "
        f"{counts['renamed']} renamed, {counts['changed']} changed",
    ]
    lines.extend(change_line(c) for c in diff.changes)
    return lines


# -- HTML ------------------------------------------------------------------------------------------

_STYLE = """
body { font: 14px/1.45 system-ui, sans-serif; margin: 2em; color: #222; }
h1 { font-size: 1.4em; } h2 { font-size: 1.15em; margin-top: 2em; }
table { border-collapse: collapse; margin: .5em 0 1.5em; }
th, td { padding: 3px 10px; border-bottom: 1px solid #ddd; text-align: left; vertical-align: top; }
code { font-size: 12px; }
.graph { overflow: auto; border: 1px solid #ddd; padding: 8px; max-width: 100%; }
.graph svg { max-width: 100%; height: auto; }
.legend span { display: inline-block; margin-right: 1.2em; font-weight: bold; }
.note { color: #8a6d3b; }
"""


def _row(change: Change) -> str:
    e = html.escape
    colour = COLOURS.get(change.change, "#222")
    return (
        f"<tr><td style='color:{colour}'><b>{e(change.change)}</b></td><td>{e(change.kind)}</td>"
        f"<td>{e(change.where)}</td><td>{e(_summary(change))}</td>"
        f"<td><code>{e(str(change.old) if change.old else '')}</code></td>"
        f"<td><code>{e(str(change.new) if change.new else '')}</code></td></tr>"
    )


def _table(changes: list[Change]) -> str:
    head = "".join(f"<th>{h}</th>" for h in ("change", "kind", "where", "what", "old", "new"))
    return f"<table><tr>{head}</tr>{''.join(_row(c) for c in changes)}</table>"


def html_page(diff: StructuralDiff, old_label: str, new_label: str, drawings: Drawings | None, note: str = "") -> str:
    """The report as one HTML page (inline CSS and SVG, no script, no request)."""
    e = html.escape
    lines = text_lines(diff, old_label, new_label)
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>{e(lines[0])}</title>"]
    parts.append(f"<style>{_STYLE}</style></head><body>")
    parts.append(f"<h1>{e(lines[0])}</h1><p>{e(lines[1])}</p>")
    parts.append(
        "<p class='legend'>" + "".join(f"<span style='color:{c}'>{e(m)}</span>" for m, c in COLOURS.items()) + "</p>"
    )
    if note:
        parts.append(f"<p class='note'>{e(note)}</p>")
    program_level = [c for c in diff.changes if c.option is None]
    parts.append("<h2>Option graph</h2>")
    if drawings is not None:
        parts.append(f"<div class='graph'>{drawings.option_graph}</div>")
    if program_level:
        parts.append("<h2>Symbols, enumerations, constants, basic behaviors, agents</h2>")
        parts.append(_table(program_level))
    options = [n for n in [*diff.new.options, *diff.old.options] if any(c.option == n for c in diff.changes)]
    for name in dict.fromkeys(options):
        own = [c for c in diff.changes if c.option == name]
        status = diff.status(name) or "changed"
        parts.append(
            f"<h2 id='option-{e(name)}'>option {e(name)} "
            f"<small style='color:{COLOURS[status]}'>{e(status)}</small></h2>"
        )
        if drawings is not None and name in drawings.state_machines:
            parts.append(f"<div class='graph'>{drawings.state_machines[name]}</div>")
        parts.append(_table(own))
    if not diff.changes:
        parts.append("<p>The two versions are the same behavior.</p>")
    parts.append("</body></html>\n")
    return "".join(parts)
