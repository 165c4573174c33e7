"""State-machine edge labels: the deciding conditions, wrapped; the whole path in the tooltip.

The labels used to be the whole path cut at 48 characters, so every edge of a state after its
first if read the same "!(...) && …" (issue 13).
"""

from __future__ import annotations

import re

from tests.emit.test_dot import program
from xabsl_studio.engine.emit.dot import state_machine


def test_labels_name_the_deciding_conditions_and_tooltips_the_whole_path() -> None:
    dot = state_machine(program("demo-approach").options["approach"])
    edges = dict(re.findall(r'id="(leaf_\d+_\d+)", label="((?:[^"\\]|\\.)*)"', dot))
    tooltips = dict(re.findall(r'id="(leaf_\d+_\d+)".*tooltip="((?:[^"\\]|\\.)*)"', dot))
    assert edges["leaf_0_1"] == "ball.distance < @stop_at"
    assert tooltips["leaf_0_1"] == "!(robot.fallen) && ball.distance < @stop_at"
    # wrapped at 30 characters a line (a DOT newline)
    assert edges["leaf_2_1"] == "state_time > 3000 &&\\n!robot.fallen"
    assert all(not label.startswith("!(") for label in edges.values())
    assert "node [fontsize=14]" in dot
