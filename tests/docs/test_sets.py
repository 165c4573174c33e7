"""The documentation of real behavior sets: every option a page, every link valid, every graph drawn.

Generated for the examples and every set of the conformance kit, then read back from disk
(:mod:`tests.docs.sitecheck`) and counted against the IR.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.docs.sitecheck import SVG, XLINK, Page, broken_links, read_site, search_index, svg_nodes
from tests.kit import KIT, SETS
from xabsl_studio.engine import ir
from xabsl_studio.engine.docs import generate
from xabsl_studio.engine.docs.xref import own_decision
from xabsl_studio.engine.emit.dot import reachable_options
from xabsl_studio.engine.lang import compile_file

ROOT = Path(__file__).resolve().parents[2]
BEHAVIORS = {
    "soccer": ROOT / "examples" / "soccer" / "behavior" / "agents.xabsl",
    "chase": ROOT / "examples" / "soccer" / "chase" / "agents.xabsl",
    "demo": ROOT / "examples" / "demo" / "agents.xabsl",
    "errands": ROOT / "examples" / "errands" / "behavior" / "agents.xabsl",
    **{f"kit-{name}": KIT / name / "agents.xabsl" for name in SETS},
}

Documented = tuple[ir.Program, Path, dict[str, Page]]


@pytest.fixture(scope="module", params=sorted(BEHAVIORS))
def documented(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Documented:
    compilation = compile_file(str(BEHAVIORS[request.param]))
    assert compilation.program is not None and not compilation.errors, [d.format() for d in compilation.errors]
    folder = tmp_path_factory.mktemp("docs")
    generate(compilation.program, folder)
    return compilation.program, folder, read_site(folder)


def by_heading(pages: dict[str, Page], kind: str) -> dict[str, Page]:
    """Pages whose heading is ``<kind> <name>``, by name."""
    prefix = kind + " "
    return {p.heading.removeprefix(prefix): p for p in pages.values() if p.heading.startswith(prefix)}


def test_every_option_and_agent_has_a_page_linked_from_the_index(documented: Documented) -> None:
    program, _, pages = documented
    options = by_heading(pages, "option")
    assert sorted(options) == sorted(program.options)
    assert all(path.startswith("options/") for path in (p.path for p in options.values()))
    agents = by_heading(pages, "agent")
    assert sorted(agents) == sorted(a.name for a in program.agents)
    index = set(pages["index.html"].links)
    assert {p.path for p in (*options.values(), *agents.values())} <= index


def test_every_link_resolves_to_a_file_and_anchor(documented: Documented) -> None:
    _, folder, pages = documented
    assert broken_links(folder, pages) == []
    # the checker sees the pages' own links and the inline SVGs' ones (xlink:href)
    assert sum(len(p.links) for p in pages.values()) > 10 * len(pages)


def test_option_pages_have_every_state_leaf_and_parameter(documented: Documented) -> None:
    program, _, pages = documented
    for name, page in by_heading(pages, "option").items():
        option = program.options[name]
        assert page.sections == [f"state-{s.name}" for s in option.states], name
        leaves = {i for i in page.ids if i.startswith("leaf-")}
        expected = {
            f"leaf-{s.index}-{leaf.leaf}"
            for s in option.states
            if s.has_decision
            for leaf in ir.leaves(own_decision(option, s))
        }
        assert leaves == expected, name
        assert {i for i in page.ids if i.startswith("param-")} == {f"param-{p.short_name}" for p in option.params}
        assert ("common-decision" in page.ids) == bool(option.common_decision)


def test_every_graph_is_svg_with_its_nodes(documented: Documented) -> None:
    program, _, pages = documented
    for name, page in by_heading(pages, "option").items():
        (svg,) = page.svgs
        ids = {g.get("id") for g in svg_nodes(svg)}
        assert ids == {"initial", *(f"state_{s.index}" for s in program.options[name].states)}, name
        # every transition edge links to its leaf, its label inside the link (what one clicks)
        for edge in (g for g in svg.iter(SVG + "g") if (g.get("id") or "").startswith("leaf_")):
            (link,) = edge.iter(SVG + "a")
            _, state, leaf = (edge.get("id") or "").split("_")
            assert link.get(XLINK + "href") in (f"#leaf-{state}-{leaf}", "#common-decision")
            assert len(list(link.iter(SVG + "text"))) == len(list(edge.iter(SVG + "text"))) > 0
    for name, page in by_heading(pages, "agent").items():
        (svg,) = page.svgs
        root = program.agent(name).root
        options = reachable_options(program, root)
        behaviors = {
            a.behavior
            for o in options
            for s in program.options[o].states
            for a in s.actions
            if isinstance(a, ir.BehaviorCall)
        }
        ids = {g.get("id") for g in svg_nodes(svg)}
        assert ids == {f"option_{program.options[o].index}" for o in options} | {
            f"behavior_{program.behaviors[b].index}" for b in behaviors
        }


def test_symbols_enumerations_constants_behaviors_have_entries(documented: Documented) -> None:
    program, _, pages = documented

    def entries(page: str, prefix: str) -> set[str]:
        return {i.removeprefix(prefix) for i in pages[page].ids if i.startswith(prefix)}

    assert entries("symbols.html", "s-") == {*program.inputs, *program.outputs}
    assert entries("enumerations.html", "e-") == set(program.enums)
    assert entries("constants.html", "c-") == set(program.constants)
    assert entries("behaviors.html", "b-") == set(program.behaviors)


def test_search_index_lists_every_option_and_symbol(documented: Documented) -> None:
    program, folder, pages = documented
    rows = search_index(folder)
    kinds: dict[str, set[str]] = {}
    for name, kind, href, _ in rows:
        kinds.setdefault(kind, set()).add(name)
        path, _, anchor = href.partition("#")
        assert path in pages and (not anchor or anchor in pages[path].ids), href
    assert kinds.get("option", set()) == set(program.options)
    assert kinds.get("input symbol", set()) == set(program.inputs)
    assert kinds.get("output symbol", set()) | kinds.get("internal symbol", set()) == set(program.outputs)
    assert kinds.get("basic behavior", set()) == set(program.behaviors)
    assert kinds.get("enum", set()) == set(program.enums)
    assert kinds.get("const", set()) == set(program.constants)
