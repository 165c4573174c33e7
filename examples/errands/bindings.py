"""The plan monitor's XABSL bindings: enumerations, input and output symbols, basic behaviors (§4.2 P2).

The symbols are declared in behavior/symbols.xabsl and behavior/basic_behaviors.xabsl; this module
is their host side for the errands world. Facts are parameterized boolean input symbols
(``fact.at_robot(loc)``, ``fact.has_robot(obj)``, ``fact.at(obj, loc)``) over enum parameters; plan
data are plain input symbols; the monitor's decisions are enumerated output symbols
(``plan.op`` and its arguments, ``plan.status``, ``plan.last_failure``) written through into the
world, and two basic behaviors let the monitor make the host plan and mark operators done.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Protocol

from xabsl_studio.engine.ir.model import Parameter
from xabsl_studio.engine.planning.monitor import PlanBoard
from xabsl_studio.engine.planning.strips import Fact
from xabsl_studio.engine.runtime import BasicBehavior, Bindings
from xabsl_studio.engine.types import Kind

#: Host values of the XABSL enumerations (element order of behavior/symbols.xabsl).
LOCATIONS = ("a", "b", "c")
ITEMS = ("book", "mug")
SCHEMAS = ("none", "go_to", "load", "unload")
STATUSES = ("idle", "executing", "replanning", "done", "failed")
REASONS = (
    "none",
    "start",
    "op_timeout",
    "precondition_lost",
    "nothing_executable",
    "extend",
    "no_plan",
    "replan_limit",
)
#: XABSL schema element -> PDDL action name.
PDDL_SCHEMA = {"go_to": "goto", "load": "load", "unload": "unload"}


class MonitorHost(Protocol):
    """What the plan monitor's bindings read and call on the world (the errands world is one)."""

    #: the derived facts of this tick
    facts: frozenset[Fact]
    #: the monitor's output symbols, written through (host enum values)
    out: dict[str, int]
    #: the plan board the monitor reads
    board: PlanBoard

    def next_op(self) -> tuple[int, int, int, int]:
        """The next operator as (schema, from, loc, obj) element indices."""
        ...

    def plan_from_facts(self, reason: str) -> None:
        """Plan (again) from the derived facts, for ``reason``."""
        ...

    def complete_operator(self) -> None:
        """Mark the running operator done."""
        ...


class PlanFromFacts(BasicBehavior):
    """``plan_from_facts(reason)``: GRAPHPLAN from the derived facts, once per activation."""

    name = "plan_from_facts"
    parameters = (Parameter("reason", Kind.ENUM, "plan_reason"),)

    def __init__(self, world: MonitorHost) -> None:
        super().__init__()
        self.world = world

    def execute(self) -> None:
        """Plan from the derived facts on the first tick of the activation only."""
        if self.time_of_execution == 0:
            self.world.plan_from_facts(REASONS[int(self.param("reason"))])


class CompleteOperator(BasicBehavior):
    """``complete_operator()``: mark the monitor's operator done on the plan board."""

    name = "complete_operator"

    def __init__(self, world: MonitorHost) -> None:
        super().__init__()
        self.world = world

    def execute(self) -> None:
        """Tell the plan board that the monitor's operator is done."""
        self.world.complete_operator()


def monitor_bindings(world: MonitorHost) -> Bindings:
    """Register the plan monitor's symbols and basic behaviors on ``world``'s state.

    Input symbols read the world's derived facts and plan board; output symbols are written
    through into ``world.out`` (host enum values), which the world turns into σ_OP.
    """
    b = Bindings()
    for name, elements in (
        ("location", LOCATIONS),
        ("item", ITEMS),
        ("op_schema", SCHEMAS),
        ("plan_status", STATUSES),
        ("plan_reason", REASONS),
    ):
        b.enum(name, list(elements))
    at_robot = [f"at-robot {x}" for x in LOCATIONS]
    has_robot = [f"has-robot {o}" for o in ITEMS]
    at = [[f"at {o} {x}" for x in LOCATIONS] for o in ITEMS]
    b.input(
        "fact.at_robot",
        Kind.BOOLEAN,
        lambda loc: at_robot[loc] in world.facts,
        params=[Parameter("loc", Kind.ENUM, "location")],
    )
    b.input(
        "fact.has_robot",
        Kind.BOOLEAN,
        lambda obj: has_robot[obj] in world.facts,
        params=[Parameter("obj", Kind.ENUM, "item")],
    )
    b.input(
        "fact.at",
        Kind.BOOLEAN,
        lambda obj, loc: at[obj][loc] in world.facts,
        params=[Parameter("obj", Kind.ENUM, "item"), Parameter("loc", Kind.ENUM, "location")],
    )
    b.input("plan.next.schema", Kind.ENUM, lambda: world.next_op()[0], enum="op_schema")
    b.input("plan.next.from", Kind.ENUM, lambda: world.next_op()[1], enum="location")
    b.input("plan.next.loc", Kind.ENUM, lambda: world.next_op()[2], enum="location")
    b.input("plan.next.obj", Kind.ENUM, lambda: world.next_op()[3], enum="item")
    b.input("plan.goal_holds", Kind.BOOLEAN, lambda: world.board.goal_holds(world.facts))
    b.input("plan.solved", Kind.BOOLEAN, lambda: world.board.solved)
    b.input("plan.can_extend", Kind.BOOLEAN, lambda: world.board.can_extend(world.facts))
    b.input("plan.replans", Kind.DECIMAL, lambda: float(world.board.replans))
    out = world.out
    enums = {
        "plan.op": "op_schema",
        "plan.op.from": "location",
        "plan.op.loc": "location",
        "plan.op.obj": "item",
        "plan.status": "plan_status",
        "plan.last_failure": "plan_reason",
    }
    for name, enum in enums.items():
        b.output(name, Kind.ENUM, enum=enum, setter=_setter(out, name), getter=_getter(out, name))
    b.behavior(PlanFromFacts(world))
    b.behavior(CompleteOperator(world))
    return b


def _setter(store: dict[str, int], name: str) -> Callable[[Any], None]:
    def set_value(value: Any) -> None:
        store[name] = int(value)

    return set_value


def _getter(store: Mapping[str, int], name: str) -> Callable[[], int]:
    return lambda: store[name]
