"""Option groups and the grouped option graph, on a generated team-shaped set of 200 options."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from tests import navset
from xabsl_studio.engine import ir
from xabsl_studio.engine.emit.dot import reachable_options, render_svg
from xabsl_studio.engine.emit.groups import ALL, BEHAVIORS, grouped_option_graph, option_groups
from xabsl_studio.engine.lang import compile_file


@pytest.fixture(scope="module")
def team(tmp_path_factory: pytest.TempPathFactory) -> ir.Program:
    root = tmp_path_factory.mktemp("team")
    compilation = compile_file(str(navset.write_set(root)), base=str(root))
    assert not compilation.errors, [d.format() for d in compilation.errors[:5]]
    assert compilation.program is not None
    return compilation.program


def test_groups_are_the_source_folders_below_the_common_one(team: ir.Program) -> None:
    groups = option_groups(team, list(team.options))
    expected = {folder.removeprefix("Options/") for folder in navset.FOLDERS}
    assert [g.key for g in groups if g.key != BEHAVIORS] == sorted(expected, key=[g.key for g in groups].index)
    assert {g.key for g in groups} == expected | {BEHAVIORS}
    folder_of = navset.option_names()
    by_index = {o.index: o.name for o in team.options.values()}
    for group in groups:
        for index in group.options:
            assert folder_of[by_index[index]] == "Options/" + group.key
    assert sum(len(g.options) for g in groups) == 200
    assert groups[-1].key == BEHAVIORS and len(groups[-1].behaviors) == len(team.behaviors)


def test_one_folder_is_grouped_by_name_prefix(team: ir.Program, tmp_path: Path) -> None:
    # the same options written into one folder
    flat = tmp_path / "flat"
    navset.write_set(flat)
    agents = flat / "agents.xabsl"
    text = agents.read_text()
    for folder in sorted(navset.FOLDERS, key=len, reverse=True):
        for file in (flat / folder).glob("*.xabsl"):
            shutil.move(file, flat / file.name)
        text = text.replace(f'"{folder}/', '"')
    agents.write_text(text)
    program = compile_file(str(agents), base=str(flat)).program
    assert program is not None
    keys = {g.key for g in option_groups(program, list(program.options))}
    # the root, play_soccer, has a prefix of its own
    assert keys == set(navset.FOLDERS.values()) | {"play", BEHAVIORS}


def test_collapsed_graph_has_one_node_per_group_and_merged_edges(team: ir.Program) -> None:
    dot, groups = grouped_option_graph(team, navset.ROOT, [ALL])
    svg = render_svg(dot)
    nodes = re.findall(r'<g id="([a-z]+_\d+)" class="node"', svg)
    assert sorted(nodes) == sorted(f"group_{n}" for n in range(len(groups)))
    edges = re.findall(r'<g id="(gcall_g\d+_g\d+)" class="edge"', svg)
    assert edges and len(edges) == len(set(edges))
    # the root's folder calls every other folder's first options
    root_group = next(n for n, g in enumerate(groups) if team.options[navset.ROOT].index in g.options)
    callees = {int(e.split("_g")[-1]) for e in edges if e.startswith(f"gcall_g{root_group}_")}
    assert len(callees) >= len(groups) - 2


def test_expanded_group_shows_its_options_in_a_cluster(team: ir.Program) -> None:
    _, groups = grouped_option_graph(team, navset.ROOT, [])
    striker = next(n for n, g in enumerate(groups) if g.key == "Soccer/Striker")
    others = [g.key for g in groups if g.key != "Soccer/Striker"]
    dot, _ = grouped_option_graph(team, navset.ROOT, [*others, "no/such/folder"])
    svg = render_svg(dot)
    shown = set(re.findall(r'<g id="(option_\d+)" class="node"', svg))
    assert shown == {f"option_{i}" for i in groups[striker].options}
    assert f'id="cluster_{striker}"' in svg
    assert f'id="group_{striker}"' not in svg
    # calls between two drawn options keep the plain graph's ids
    inner = [e for e in re.findall(r'<g id="(call_\d+_o\d+)" class="edge"', svg)]
    assert inner
    for edge in inner:
        caller, callee = edge.removeprefix("call_").split("_o")
        assert int(caller) in groups[striker].options and int(callee) in groups[striker].options


def test_nothing_collapsed_draws_every_reachable_option(team: ir.Program) -> None:
    dot, _ = grouped_option_graph(team, navset.ROOT, [])
    assert len(re.findall(r'id="option_\d+"', dot)) == len(reachable_options(team, navset.ROOT)) == 200
    assert "group_" not in dot
