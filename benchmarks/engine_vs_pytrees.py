"""Engine vs py_trees: the same decision logic, the same inputs, µs per tick and the ratio.

The logic: 5 levels; at level k an input x_k in [0, 1) chooses one of three branches
(x_k > 0.66 -> 2, x_k > 0.33 -> 1, else 0); the branch chosen at the last level is a leaf action.

* XABSL: one option per level with 3 states; every state has the same decision tree over x_k
  (so the state machine selects like a stateless selector) and calls the next level's option;
  the last level's states call a basic behavior with the chosen path as parameter.
* py_trees: a Selector per level over Sequence(condition, subtree) children, subtrees copied
  per branch (py_trees nodes have one parent).

Both are fed the same input stream; every tick the selected leaf (the path of branch indices)
must agree. Prints µs per tick for each, the ratio, and the cost of recording the activation
tree (``Engine.snapshot()``, and the compact path ``Engine.path()`` the studio records every tick)
and of building it as objects (``Engine.activation()``).

Run: ``.venv/bin/python benchmarks/engine_vs_pytrees.py [--ticks N]``
"""

from __future__ import annotations

import argparse
import random
import time

import py_trees

from xabsl_studio.engine.ir import model as ir
from xabsl_studio.engine.runtime import BasicBehavior, Bindings, Engine
from xabsl_studio.engine.types import Kind

LEVELS = 5
D = Kind.DECIMAL


def xabsl_program() -> ir.Program:
    options = {}
    for level in range(LEVELS):
        name = f"level{level}"
        x = ir.InputRef(f"x{level}", D)
        decision = ir.If(
            ir.Binary(">", x, ir.Number(0.66), Kind.BOOLEAN),
            ir.Transition("s2", leaf=0),
            ir.If(
                ir.Binary(">", x, ir.Number(0.33), Kind.BOOLEAN),
                ir.Transition("s1", leaf=1),
                ir.Transition("s0", leaf=2),
            ),
        )
        states = []
        for k in range(3):
            path = ir.Binary(
                "+", ir.Binary("*", ir.ParameterRef(f"{name}.path", D), ir.Number(3.0), D), ir.Number(float(k)), D
            )
            if level + 1 < LEVELS:
                child = f"level{level + 1}"
                action: ir.Action = ir.OptionCall(child, (ir.Argument(f"{child}.path", D, None, path),))
            else:
                action = ir.BehaviorCall("act", (ir.Argument("act.path", D, None, path),))
            states.append(ir.State(f"s{k}", k, decision, (action,), initial=k == 0))
        options[name] = ir.Option(name, level, (ir.Parameter(f"{name}.path", D),), tuple(states), "s0")
    inputs = {f"x{k}": ir.InputSymbol(f"x{k}", D) for k in range(LEVELS)}
    behaviors = {"act": ir.BasicBehavior("act", (ir.Parameter("act.path", D),))}
    return ir.Program("bench", options, (ir.Agent("bench", "bench", "level0"),), {}, inputs, {}, {}, behaviors)


class Act(BasicBehavior):
    name = "act"
    parameters = (("path", D),)
    last = -1.0

    def execute(self) -> None:
        Act.last = self.parameter_values[self.parameter_offset]


def xabsl_engine(x: list[float]) -> Engine:
    bindings = Bindings()
    for k in range(LEVELS):
        bindings.input(f"x{k}", D, (lambda k=k: x[k]))
    bindings.behavior(Act)
    return Engine(bindings, xabsl_program())


class Condition(py_trees.behaviour.Behaviour):
    def __init__(self, x: list[float], level: int, threshold: float) -> None:
        super().__init__(f"x{level}>{threshold}")
        self.x, self.level, self.threshold = x, level, threshold

    def update(self) -> py_trees.common.Status:
        if self.x[self.level] > self.threshold:
            return py_trees.common.Status.SUCCESS
        return py_trees.common.Status.FAILURE


class Leaf(py_trees.behaviour.Behaviour):
    last = -1.0

    def __init__(self, path: float) -> None:
        super().__init__(f"act{int(path)}")
        self.path = path

    def update(self) -> py_trees.common.Status:
        Leaf.last = self.path
        return py_trees.common.Status.SUCCESS


def pytrees_tree(x: list[float], level: int = 0, path: float = 0.0) -> py_trees.behaviour.Behaviour:
    def branch(k: int) -> py_trees.behaviour.Behaviour:
        sub_path = path * 3 + k
        if level + 1 < LEVELS:
            return pytrees_tree(x, level + 1, sub_path)
        return Leaf(sub_path)

    return py_trees.composites.Selector(
        f"level{level}",
        memory=False,
        children=[
            py_trees.composites.Sequence("b2", memory=False, children=[Condition(x, level, 0.66), branch(2)]),
            py_trees.composites.Sequence("b1", memory=False, children=[Condition(x, level, 0.33), branch(1)]),
            branch(0),
        ],
    )


def count(node: py_trees.behaviour.Behaviour) -> int:
    return 1 + sum(count(c) for c in node.children)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--ticks", type=int, default=20000)
    args = parser.parse_args()
    rng = random.Random(7)
    stream = [[rng.random() for _ in range(LEVELS)] for _ in range(args.ticks)]
    x = [0.0] * LEVELS
    engine = xabsl_engine(x)
    tree = pytrees_tree(x)

    # Same leaf action every tick (not timed).
    for now, values in enumerate(stream[:2000]):
        x[:] = values
        engine.execute(now * 10)
        tree.tick_once()
        assert Act.last == Leaf.last, (now, Act.last, Leaf.last)
    assert engine.fault is None

    def timed(step: object) -> float:
        start = time.perf_counter()
        step()  # type: ignore[operator]
        return (time.perf_counter() - start) / args.ticks * 1e6

    def run_engine() -> None:
        execute = engine.execute
        for now, values in enumerate(stream):
            x[:] = values
            execute(now * 10)

    def run_engine_recorded() -> None:
        execute, snapshot = engine.execute, engine.snapshot
        for now, values in enumerate(stream):
            x[:] = values
            execute(now * 10)
            snapshot()

    def run_engine_path() -> None:
        execute, path = engine.execute, engine.path
        for now, values in enumerate(stream):
            x[:] = values
            execute(now * 10)
            path()

    def run_pytrees() -> None:
        tick = tree.tick_once
        for values in stream:
            x[:] = values
            tick()

    def run_inputs_only() -> None:
        for values in stream:
            x[:] = values

    base = min(timed(run_inputs_only) for _ in range(3))
    ours = min(timed(run_engine) for _ in range(3)) - base
    recorded = min(timed(run_engine_recorded) for _ in range(3)) - base
    with_path = min(timed(run_engine_path) for _ in range(3)) - base
    theirs = min(timed(run_pytrees) for _ in range(3)) - base
    start = time.perf_counter()
    for _ in range(2000):
        engine.activation()
    tree_us = (time.perf_counter() - start) / 2000 * 1e6

    print(f"logic: {LEVELS} levels x 3 branches; py_trees tree has {count(tree)} nodes, active path {LEVELS} deep")
    print(f"ticks: {args.ticks}, same leaf action checked on 2000 ticks")
    print(f"py_trees        {theirs:8.2f} µs/tick")
    print(f"xabsl engine    {ours:8.2f} µs/tick   ratio py_trees/engine = {theirs / ours:.1f}x")
    print(
        f"  + snapshot    {recorded:8.2f} µs/tick   (recording cost {recorded - ours:.2f} µs/tick, "
        f"{(recorded - ours) / ours:.0%} of a tick)"
    )
    print(
        f"  + path        {with_path:8.2f} µs/tick   (compact path for the studio: {with_path - ours:.2f} µs/tick, "
        f"{(with_path - ours) / ours:.0%} of a tick)"
    )
    print(f"activation tree built as objects on request: {tree_us:.2f} µs")


if __name__ == "__main__":
    main()
