"""Policy B1: a basic behavior called twice in one tick keeps each call's own parameters (issue 23).

B2 rejects such a program at load time; B1 (NaoTH's engine) runs it, and the storage then holds
the last call's values. The activation tree and the compact path must still show, on each call's
node, the values that call was given: what the behavior itself saw when it ran.
"""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.runtime import BasicBehavior, Bindings, Engine, Policy
from xabsl_studio.engine.runtime.activation import BEHAVIOR_NODE, BehaviorNode, OptionNode
from xabsl_studio.engine.types import Kind

SOURCES = {
    "agents.xabsl": 'include "skills.xabsl";\ninclude "both.xabsl";\ninclude "inner.xabsl";\nagent a("A", both);\n',
    "skills.xabsl": 'namespace skills("Skills") {\n  behavior walk {\n    float speed;\n  }\n}\n',
    "inner.xabsl": (
        "option inner {\n  float @speed;\n  initial state go {\n    decision {\n      stay;\n    }\n"
        "    action {\n      walk(speed = @speed + 1);\n    }\n  }\n}\n"
    ),
    "both.xabsl": (
        "option both {\n  initial state go {\n    decision {\n      stay;\n    }\n"
        "    action {\n      walk(speed = 10);\n      inner(speed = 20);\n      walk(speed = 30);\n    }\n  }\n}\n"
    ),
}


class Walk(BasicBehavior):
    """Remembers the speed of every call, as the host's leg control would receive it."""

    name = "walk"
    parameters = (("walk.speed", Kind.DECIMAL),)
    seen: ClassVar[list[float]] = []

    def execute(self) -> None:
        Walk.seen.append(float(self.param("speed")))


def program(tmp_path: Path) -> Program:
    for name, text in SOURCES.items():
        (tmp_path / name).write_text(text)
    compilation = compile_file(str(tmp_path / "agents.xabsl"))
    assert compilation.program is not None, [d.format() for d in compilation.errors]
    return compilation.program


def behaviors(nodes: list[object]) -> list[float]:
    out: list[float] = []
    for node in nodes:
        if isinstance(node, BehaviorNode):
            out.append(float(node.params["walk.speed"]))
        elif isinstance(node, OptionNode):
            out.extend(behaviors(list(node.sub)))
    return out


def test_each_call_of_a_basic_behavior_shows_its_own_parameters(tmp_path: Path) -> None:
    bindings = Bindings()
    bindings.behavior(Walk)
    engine = Engine(bindings, program(tmp_path), policy=Policy.B1)
    for tick in range(3):
        Walk.seen = []
        engine.execute(100 * tick)
        assert Walk.seen == [10.0, 21.0, 30.0]
        assert behaviors(engine.activation()) == Walk.seen
        assert [n[4][0] for n in engine.path() if n[0] == BEHAVIOR_NODE] == Walk.seen
        # a snapshot taken now still tells the calls apart when the tree is built later
        snapshot = engine.snapshot()
        engine.execute(100 * tick + 50)
        assert behaviors(engine.activation(snapshot)) == [10.0, 21.0, 30.0]
