"""State-machine edge labels: the deciding conditions on one line, numbered by decision order;
the whole path in the tooltip.

The labels used to be the whole path cut at 48 characters, so every edge of a state after its
first if read the same "!(...) && …" (issue 13); then wrapped conditions of up to four lines,
which tangled the big machines of team sets (issue 31).
"""

from __future__ import annotations

import re

from tests.emit.test_dot import program
from xabsl_studio.engine import ir
from xabsl_studio.engine.emit.dot import _LABEL_LINE, state_machine

EDGE = re.compile(r'id="(leaf_\d+_\d+)", label="((?:[^"\\]|\\.)*)", tooltip="((?:[^"\\]|\\.)*)"')


def test_labels_name_the_deciding_conditions_and_tooltips_the_whole_path() -> None:
    dot = state_machine(program("demo-approach").options["approach"])
    edges = {leaf: (label, tooltip) for leaf, label, tooltip in EDGE.findall(dot)}
    # two transitions leave state 0: numbered in the order its decision tries them
    assert edges["leaf_0_0"] == ("1. robot.fallen", "1. robot.fallen")
    assert edges["leaf_0_1"] == ("2. ball.distance < @stop_at", "2. !(robot.fallen) && ball.distance < @stop_at")
    # a single transition is not numbered
    assert edges["leaf_2_1"][0] == "state_time > 3000 && !robot.fallen"
    assert all(not label.split(". ", 1)[-1].startswith("!(") for label, _ in edges.values())
    assert all("\\n" not in label for label, _ in edges.values())
    assert "node [fontsize=14]" in dot
    # out-edges keep their declared (decision) order in the layout
    assert "ordering=out" in dot


def test_long_conditions_are_cut_on_the_label_and_whole_in_the_tooltip() -> None:
    condition = " && ".join(f"sensor.value_{i} > {i * 100}" for i in range(6))
    decision = ir.If(ir.BooleanLiteral(True), ir.Transition("b", leaf=0), ir.Transition("a", True, 1), text=condition)
    states = (ir.State("a", 0, decision, ()), ir.State("b", 1, ir.Transition("b", True, 0), ()))
    option = ir.Option("long", 0, (), states, "a")
    dot = state_machine(option)
    ((_, label, tooltip),) = EDGE.findall(dot)
    assert len(label) <= _LABEL_LINE and label.endswith(" …")
    assert condition.startswith(label.removesuffix(" …"))
    assert tooltip == condition
