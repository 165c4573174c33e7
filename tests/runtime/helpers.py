"""Small hosts for the engine rule tests: programs from IC snippets, trees printed as traces."""

from __future__ import annotations

import json
import textwrap
from typing import Any

from xabsl_studio.engine.ir.ic_reader import read_ic
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.runtime import Engine, Policy
from xabsl_studio.engine.trace.conformance import conformance_bindings
from xabsl_studio.engine.types import Value


def ic(text: str) -> Program:
    """A program from an IC snippet (``//`` comments allowed, any layout)."""
    return read_ic(textwrap.dedent(text))


class Host:
    """An engine on the kit's bindings; ``values`` are the plain inputs."""

    def __init__(self, program: Program, policy: Policy = Policy.B2, **overrides: Any) -> None:
        self.program = program
        self.bindings, self.values = conformance_bindings(program)
        for name, read in overrides.items():
            symbol = program.inputs[name]
            self.bindings.input(name, symbol.kind, read, params=symbol.params, enum=symbol.enum)
        self.engine = Engine(self.bindings, program, policy=policy)

    def tick(self, now: int, **values: Value) -> Engine:
        self.values.update({k.replace("__", "."): v for k, v in values.items()})
        self.engine.execute(now)
        print(f"t={now}", json.dumps(self.engine.activation_dict()), json.dumps(self.engine.outputs()))
        if self.engine.fault:
            print("fault:", self.engine.fault)
        return self.engine

    def state(self, option: str) -> str:
        for node in _walk(self.engine.activation()):
            if getattr(node, "option", None) == option:
                return node.state
        raise AssertionError(f"option {option} did not run")

    def ran(self, option: str) -> bool:
        return any(getattr(n, "option", None) == option for n in _walk(self.engine.activation()))

    def node(self, option: str) -> Any:
        for node in _walk(self.engine.activation()):
            if getattr(node, "option", None) == option:
                return node
        raise AssertionError(f"option {option} did not run")


def _walk(nodes: list[Any]) -> Any:
    for node in nodes:
        yield node
        yield from _walk(list(getattr(node, "sub", ())))
