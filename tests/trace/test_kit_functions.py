"""The kit host's parameterized input symbols: ``sum((i+1) * value_i)``, bit for bit at every arity."""

from __future__ import annotations

import math
import random
import struct

from xabsl_studio.engine.ir import model as ir
from xabsl_studio.engine.trace.conformance import conformance_bindings
from xabsl_studio.engine.types import Kind

D = Kind.DECIMAL


def reference(*values: float | bool | int) -> float:
    """The kit's definition, as a loop (what the unrolled bindings must equal bit for bit)."""
    total = 0.0
    for i, value in enumerate(values):
        total += (i + 1) * float(value)
    return total


def bits(x: float) -> bytes:
    return struct.pack("<d", x)


def program(arities: range) -> ir.Program:
    inputs = {}
    for n in arities:
        name = f"f{n}"
        params = tuple(ir.Parameter(f"{name}.p{i}", D, owner=name) for i in range(n))
        inputs[name] = ir.InputSymbol(name, D, params=params)
        inputs[f"b{n}"] = ir.InputSymbol(f"b{n}", Kind.BOOLEAN, params=params)
    return ir.Program("kit", {}, (), {}, inputs, {}, {}, {})


def test_functions_equal_the_loop_bit_for_bit() -> None:
    bindings, _ = conformance_bindings(program(range(1, 6)))
    rnd = random.Random(7)
    specials = [0.0, -0.0, 1e308, -1e308, 5e-324, math.inf, True, False, 3]
    for _ in range(300):
        for n in range(1, 6):
            values = [rnd.choice(specials) if rnd.random() < 0.2 else rnd.uniform(-1e6, 1e6) for _ in range(n)]
            expected = reference(*values)
            got = bindings.inputs[f"f{n}"].read(*values)
            assert bits(got) == bits(expected) or (math.isnan(got) and math.isnan(expected)), (values, got)
            assert bindings.inputs[f"b{n}"].read(*values) == (expected > 0)
