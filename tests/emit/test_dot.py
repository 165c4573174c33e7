"""DOT output: addressable ids for the studio, and a real Graphviz layout of the kit's sets."""

from __future__ import annotations

import re

import pytest

from tests.kit import KIT, SETS
from xabsl_studio.engine import ir
from xabsl_studio.engine.emit.dot import option_graph, reachable_options, render_svg, state_machine
from xabsl_studio.engine.lang import compile_file


def program(name: str) -> ir.Program:
    compilation = compile_file(str(KIT / name / "agents.xabsl"))
    assert compilation.program is not None
    return compilation.program


def test_option_graph_has_ids_for_options_behaviors_and_calls() -> None:
    prog = program("parameters")
    dot = option_graph(prog, "root")
    for option in ("root", "drive", "step", "turn"):
        assert f'id="option_{prog.options[option].index}"' in dot
    assert f'id="behavior_{prog.behaviors["move"].index}"' in dot
    assert f'id="call_{prog.options["root"].index}_o{prog.options["drive"].index}"' in dot


def test_reachable_options_follow_calls_from_the_root() -> None:
    prog = program("agents")
    assert reachable_options(prog, "alpha") == ["alpha", "shared"]
    assert reachable_options(prog, "beta") == ["beta"]


def test_state_machine_has_one_edge_per_state_changing_leaf() -> None:
    prog = program("demo-approach")
    dot = state_machine(prog.options["approach"])
    edges = re.findall(r'id="(leaf_\d+_\d+)"', dot)
    # go: robot.fallen -> recover (leaf 0), distance -> arrived (leaf 1); arrived: -> recover;
    # recover: -> recover is a stay (no edge), -> go (leaf 1)
    assert edges == ["leaf_0_0", "leaf_0_1", "leaf_1_0", "leaf_2_1"]
    assert 'id="state_1"' in dot and "doublecircle" in dot  # arrived is a target state


@pytest.mark.parametrize("name", SETS)
def test_graphviz_lays_out_every_graph(name: str) -> None:
    prog = program(name)
    svg = render_svg(option_graph(prog))
    assert svg.lstrip().startswith("<?xml") and "<svg" in svg
    for option in prog.options.values():
        assert f'id="option_{option.index}"' in svg
        machine = render_svg(state_machine(option))
        for state in option.states:
            assert f'id="state_{state.index}"' in machine
