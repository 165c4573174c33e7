"""The documentation's pictures: the DOT of :mod:`xabsl_studio.engine.emit.dot` with links added, laid out in batches.

Links are extra attribute statements appended to the emitter's DOT (``"o:walk" [href=...]``
re-declares a node with more attributes), so the pictures are exactly the studio's plus links:
option nodes open their page, basic behaviors their entry, states their section. Transition
edges already carry an ``<a>`` (their tooltip); it gets the ``href`` of the decision-tree leaf.

``dot`` starts in tens of milliseconds and lays out a small graph in a few more, so the graphs
go to one ``dot`` process per core, many graphs per process (``dot`` reads any number of graphs
from its input and writes one SVG document after another).
"""

from __future__ import annotations

import os
import re
import subprocess
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor

from xabsl_studio.engine import ir
from xabsl_studio.engine.emit.dot import option_graph, quote, reachable_options, render_svg, state_machine
from xabsl_studio.engine.errors import EmitError

#: Where an SVG document starts in ``dot``'s output (labels are escaped, so never inside one).
_SVG_START = "<?xml "
#: an edge's anchor (leaf ids, the anchor's attributes, its content) and the label lines after it
_EDGE_ANCHOR = re.compile(
    r'<g id="a_leaf_(\d+)_(\d+)"><a ([^>]*)>(.*?)</a>\n</g>\n((?:<text[^>]*>[^<]*</text>\n)*)', re.S
)


class GraphLayoutError(EmitError, RuntimeError):
    """Graphviz refused a graph (the message names the graph and quotes ``dot``)."""


def _with_links(dot: str, links: Sequence[tuple[str, str]]) -> str:
    """``dot`` with ``node [href=..., target=_top]`` statements before its closing brace."""
    body = dot.rstrip()
    assert body.endswith("}"), "the emitter's DOT ends with the graph's closing brace"
    lines = [f'  {quote(node)} [href={quote(href)}, target="_top"];' for node, href in links]
    return body[:-1] + "\n".join(lines) + "\n}\n"


def option_graph_dot(
    program: ir.Program, root: str, option_href: Callable[[str], str], behavior_href: Callable[[str], str]
) -> str:
    """The option graph below ``root`` with every node linked to its documentation."""
    names = reachable_options(program, root)
    links = [(f"o:{name}", option_href(name)) for name in names]
    called = {
        a.behavior
        for name in names
        for state in program.options[name].states
        for a in state.actions
        if isinstance(a, ir.BehaviorCall)
    }
    links += [(f"b:{name}", behavior_href(name)) for name in program.behaviors if name in called]
    return _with_links(option_graph(program, root), links)


def state_machine_dot(option: ir.Option, state_href: Callable[[str], str]) -> str:
    """The state machine of ``option`` with every state linked to its section."""
    return _with_links(state_machine(option), [(f"s:{s.name}", state_href(s.name)) for s in option.states])


def link_leaves(svg: str, leaf_href: Callable[[int, int], str]) -> str:
    """Give every transition edge of a state-machine SVG the ``href`` of its decision-tree leaf.

    Graphviz wraps an edge's path and arrowhead in the tooltip's ``<a>`` and writes the label's
    ``<text>`` lines after it; they move inside it, so the label is what a reader clicks.
    """

    def replace(match: re.Match[str]) -> str:
        href = leaf_href(int(match.group(1)), int(match.group(2)))
        return (
            f'<g id="a_leaf_{match.group(1)}_{match.group(2)}"><a xlink:href="{href}" {match.group(3)}>'
            f"{match.group(4)}{match.group(5)}</a>\n</g>\n"
        )

    return _EDGE_ANCHOR.sub(replace, svg)


def inline(svg: str) -> str:
    """An SVG document as markup for an HTML page: the XML prolog, doctype and comments dropped."""
    start = svg.find("<svg")
    return svg[start:] if start >= 0 else svg


def render_all(dots: Sequence[str], jobs: int | None = None) -> list[str]:
    """SVG documents of ``dots`` (same order), one ``dot`` process per job on a share of them.

    Raises:
        GraphvizMissing: when ``dot`` is not installed.
        GraphLayoutError: when ``dot`` rejects a graph or times out (a failed batch is retried
            one graph at a time, so the error names the graph).
    """
    if not dots:
        return []
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(dots)))
    # a share per job by DOT size (layout time grows with it), biggest graphs first
    order = sorted(range(len(dots)), key=lambda i: -len(dots[i]))
    shares: list[list[int]] = [[] for _ in range(jobs)]
    sizes = [0] * jobs
    for i in order:
        j = sizes.index(min(sizes))
        shares[j].append(i)
        sizes[j] += len(dots[i])
    result: list[str] = [""] * len(dots)

    def run(share: list[int]) -> None:
        if not share:
            return
        text = "".join(dots[i] for i in share)
        try:
            output = render_svg(text, timeout=20.0 + 0.5 * len(share))
            documents = [_SVG_START + part for part in output.split(_SVG_START)[1:]]
        except Exception:  # one bad graph fails its batch: find it (and render the rest) alone
            documents = []
        if len(documents) != len(share):
            documents = [_render_one(dots[i]) for i in share]
        for i, document in zip(share, documents, strict=True):
            result[i] = document

    with ThreadPoolExecutor(max_workers=jobs) as pool:
        for future in [pool.submit(run, share) for share in shares]:
            future.result()
    return result


def _render_one(dot: str) -> str:
    try:
        return render_svg(dot)
    except subprocess.CalledProcessError as error:
        detail = error.stderr.decode("utf-8", "replace").strip() if error.stderr else str(error)
        raise GraphLayoutError(f"Graphviz could not lay out {dot.split('{', 1)[0].strip()}: {detail}") from error
    except subprocess.TimeoutExpired as error:
        raise GraphLayoutError(f"Graphviz took too long on {dot.split('{', 1)[0].strip()}") from error
