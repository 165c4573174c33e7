"""The documentation writer: lays out every picture, renders every page, writes the folder.

:func:`build` returns the files as ``{relative path: bytes}`` (pure: no file is touched);
:func:`write` puts them into a folder, each file atomically (:mod:`xabsl_studio.engine.files`), leaving other
files there alone. :func:`generate` does both and says how long each stage took.
"""

from __future__ import annotations

import hashlib
import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import orjson

from xabsl_studio.engine import ir
from xabsl_studio.engine.docs import assets, graphs
from xabsl_studio.engine.docs.pages import Renderer, Site, fragment
from xabsl_studio.engine.docs.xref import cross_references, own_decision
from xabsl_studio.engine.emit.dot import reachable_options
from xabsl_studio.engine.files import write_atomically

#: Changes whenever the pages change for the same program, so cached documentation is redone.
DOCS_VERSION = 1


def program_digest(program: ir.Program) -> str:
    """A digest of everything the documentation shows of ``program`` (and of this generator's version).

    The IR is frozen data whose ``repr`` lists every field (doc comments and spans included), so
    two programs with the same digest have the same documentation.
    """
    text = f"xabsl-docs {DOCS_VERSION}\n{program!r}"
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:32]


@dataclass
class DocsResult:
    """What :func:`generate` wrote and how long it took."""

    folder: Path
    files: dict[str, bytes]
    #: seconds per stage: "graphs" (``dot``), "pages", "write"
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def pages(self) -> list[str]:
        """The HTML pages written (relative paths)."""
        return [path for path in self.files if path.endswith(".html")]


def build(program: ir.Program, jobs: int | None = None, timings: dict[str, float] | None = None) -> dict[str, bytes]:
    """Every file of the documentation of ``program``, by path relative to the folder.

    Args:
        program: the checked program.
        jobs: ``dot`` processes at once (default: one per core).
        timings: filled with seconds per stage ("graphs", "pages") when given.
    """
    timings = timings if timings is not None else {}
    site = Site(program)
    refs = cross_references(program)
    reached = {agent.name: reachable_options(program, agent.root) for agent in program.agents}
    agents_of: dict[str, list[str]] = {}
    for agent_name, names in reached.items():
        for name in names:
            agents_of.setdefault(name, []).append(agent_name)

    started = time.perf_counter()
    options = list(program.options.values())
    dots = [
        # the option graph is inlined in agents/<agent>.html: hrefs from that subfolder
        graphs.option_graph_dot(
            program, agent.root, lambda name: "../" + site.option(name), lambda name: "../" + site.behavior(name)
        )
        for agent in program.agents
    ]
    dots += [graphs.state_machine_dot(option, lambda s: f"#state-{fragment(s)}") for option in options]
    svgs = graphs.render_all(dots, jobs)
    timings["graphs"] = time.perf_counter() - started

    started = time.perf_counter()
    renderer = Renderer(program, refs, site, agents_of)
    files: dict[str, str | bytes] = {}
    for agent, agent_svg in zip(program.agents, svgs, strict=False):
        files[site.agent(agent.name)] = renderer.agent_page(agent, graphs.inline(agent_svg), reached[agent.name])
    for option, svg in zip(options, svgs[len(program.agents) :], strict=True):
        own = {state.index: {leaf.leaf for leaf in ir.leaves(own_decision(option, state))} for state in option.states}

        def leaf_href(state: int, leaf: int, own: dict[int, set[int]] = own) -> str:
            return f"#leaf-{state}-{leaf}" if leaf in own.get(state, ()) else "#common-decision"

        files[site.option_paths[option.name]] = renderer.option_page(
            option, graphs.inline(graphs.link_leaves(svg, leaf_href))
        )
    files["index.html"] = renderer.index_page()
    files["symbols.html"] = renderer.symbols_page()
    files["enumerations.html"] = renderer.enumerations_page()
    files["constants.html"] = renderer.constants_page()
    files["behaviors.html"] = renderer.behaviors_page()
    files["style.css"] = assets.STYLE
    files["search.js"] = assets.SEARCH
    index = orjson.dumps(renderer.search_index()).decode("utf-8").replace("</", "<\\/")
    files["search-index.js"] = f"window.XABSL_DOCS_INDEX = {index};\n"
    timings["pages"] = time.perf_counter() - started
    return {path: data.encode("utf-8") if isinstance(data, str) else data for path, data in files.items()}


#: The list of files the last :func:`write` put into a folder (one relative path a line).
MANIFEST = ".xabsl-docs"


def write(files: dict[str, bytes], folder: str | os.PathLike[str], jobs: int = 4) -> None:
    """Write ``files`` below ``folder`` (created if missing), each atomically.

    Pages a previous run wrote that this one does not (an option since renamed) are removed,
    so no stale page links to a missing one; files the documentation did not write stay.
    """
    root = Path(folder)
    for sub in sorted({Path(path).parent for path in files}):
        (root / sub).mkdir(parents=True, exist_ok=True)
    manifest = root / MANIFEST
    try:
        previous = manifest.read_text(encoding="utf-8").splitlines()
    except FileNotFoundError:
        previous = []
    # fsync per file is I/O wait, not CPU: a few threads overlap it
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        for future in [pool.submit(write_atomically, root / path, data) for path, data in files.items()]:
            future.result()
    for stale in set(previous) - set(files):
        target = (root / stale).resolve()
        if target.is_relative_to(root.resolve()) and target.is_file():
            target.unlink()
    write_atomically(manifest, "".join(f"{path}\n" for path in sorted(files)).encode("utf-8"))


def generate(program: ir.Program, folder: str | os.PathLike[str], jobs: int | None = None) -> DocsResult:
    """Build the documentation of ``program`` and write it into ``folder``."""
    timings: dict[str, float] = {}
    files = build(program, jobs, timings)
    started = time.perf_counter()
    write(files, folder)
    timings["write"] = time.perf_counter() - started
    return DocsResult(Path(folder), files, timings)
