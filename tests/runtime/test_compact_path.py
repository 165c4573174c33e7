"""``Engine.path()``: the compact activation path equals the activation tree, tick by tick.

Differential over every conformance set's input trace: the flat lists read straight from engine
storage must describe exactly the options, states, times, decisions, parameters and basic
behaviors that :meth:`Engine.activation` reconstructs.
"""

from __future__ import annotations

import json
from typing import Any

import pytest

from tests.kit import KIT, SETS
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.runtime.activation import BEHAVIOR_NODE, OPTION_NODE, BehaviorNode, OptionNode
from xabsl_studio.engine.trace.conformance import TraceRunner


def flatten(program: Any, nodes: list[Any], depth: int = 0) -> list[list[Any]]:
    out: list[list[Any]] = []
    for node in nodes:
        if isinstance(node, OptionNode):
            option = program.options[node.option]
            out.append(
                [
                    OPTION_NODE,
                    depth,
                    option.index,
                    option.state(node.state).index,
                    node.option_time,
                    node.state_time,
                    option.state(node.decided_in).index,
                    node.leaf,
                    [node.params[p.name] for p in option.params],
                ]
            )
            out.extend(flatten(program, list(node.sub), depth + 1))
        elif isinstance(node, BehaviorNode):
            behavior = program.behaviors[node.behavior]
            out.append(
                [BEHAVIOR_NODE, depth, behavior.index, node.time, [node.params[p.name] for p in behavior.params]]
            )
    return out


@pytest.mark.parametrize("name", SETS)
def test_compact_path_equals_the_activation_tree(name: str) -> None:
    compilation = compile_file(str(KIT / name / "agents.xabsl"))
    assert compilation.program is not None
    runner = TraceRunner(compilation.program)
    lines = [json.loads(line) for line in (KIT / name / "in.jsonl").read_text().splitlines() if line.strip()]
    nodes = 0
    for line in lines:
        runner.tick(line)
        engine = runner.engine
        expected = flatten(compilation.program, engine.activation())
        assert engine.path() == expected, f"t={line['t']}"
        nodes += len(expected)
    assert nodes >= len(lines)  # at least the root option on every tick
