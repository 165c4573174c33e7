"""``Engine.input_sampler`` / ``output_sampler``: one call reads many symbols, overrides included."""

from __future__ import annotations

from types import SimpleNamespace

from xabsl_studio.engine.ir.ic_reader import read_ic
from xabsl_studio.engine.runtime import Bindings, Engine
from xabsl_studio.engine.types import Kind

PROGRAM = read_ic(
    """
    0 0
    1
    main 0
    1 s n s
    0 3 d out.a i a 0 d out.b i b 0 d out.c i c 0
    t s
    1 ag main
    """
)


def make_engine() -> tuple[Engine, SimpleNamespace, dict[str, float]]:
    world = SimpleNamespace(a=1.0, b=2.0)
    plain = {"c": 3.0}
    bindings = Bindings()
    bindings.input_attribute("a", Kind.DECIMAL, world, "a")
    bindings.input_attribute("b", Kind.DECIMAL, world, "b")
    bindings.input("c", Kind.DECIMAL, lambda: plain["c"])
    for name in ("out.a", "out.b", "out.c"):
        bindings.output(name, Kind.DECIMAL)
    return Engine(bindings, PROGRAM), world, plain


def test_input_sampler_reads_in_the_requested_order() -> None:
    engine, world, plain = make_engine()
    sample = engine.input_sampler(["c", "b", "a"])
    assert sample() == (3.0, 2.0, 1.0)
    world.a, plain["c"] = 10.0, 30.0
    assert sample() == (30.0, 2.0, 10.0)


def test_input_sampler_sees_debugger_overrides() -> None:
    engine, _world, _ = make_engine()
    sample = engine.input_sampler(["a", "c"])
    engine.root_actions.override_input("a", 42.0)
    assert sample() == (42.0, 3.0)
    engine.root_actions.release_input("a")
    assert sample() == (1.0, 3.0)


def test_output_sampler_reads_engine_storage() -> None:
    engine, world, _ = make_engine()
    engine.execute(0)
    sample = engine.output_sampler(["out.c", "out.a"])
    assert sample() == (3.0, 1.0)
    world.a = 5.0
    engine.execute(25)
    assert sample() == (3.0, 5.0)


def test_input_sampler_reads_mapping_items_with_one_call() -> None:
    values = {"a": 1.0, "b.x": 2.0}
    bindings = Bindings()
    bindings.input_item("a", Kind.DECIMAL, values, "a")
    bindings.input_item("b", Kind.DECIMAL, values, "b.x")
    bindings.input("c", Kind.DECIMAL, lambda: 3.0)
    for name in ("out.a", "out.b", "out.c"):
        bindings.output(name, Kind.DECIMAL)
    engine = Engine(bindings, PROGRAM)
    sample = engine.input_sampler(["c", "b", "a"])
    assert sample() == (3.0, 2.0, 1.0)
    values["a"], values["b.x"] = 10.0, 20.0
    assert sample() == (3.0, 20.0, 10.0)
    engine.root_actions.override_input("b", 42.0)
    assert sample() == (3.0, 42.0, 10.0)
    engine.execute(0)
    assert engine.output("out.b") == 42.0 and engine.output("out.a") == 10.0


def test_output_sampler_reads_host_symbols_through_their_getters_in_the_order_asked() -> None:
    world = SimpleNamespace(a=1.0, b=2.0)
    host: dict[str, float] = {}
    bindings = Bindings()
    bindings.input_attribute("a", Kind.DECIMAL, world, "a")
    bindings.input_attribute("b", Kind.DECIMAL, world, "b")
    bindings.input("c", Kind.DECIMAL, lambda: 3.0)
    bindings.output("out.a", Kind.DECIMAL)
    bindings.output("out.b", Kind.DECIMAL, setter=lambda v: host.__setitem__("b", v), getter=lambda: host["b"])
    bindings.output("out.c", Kind.DECIMAL)
    engine = Engine(bindings, PROGRAM)
    engine.execute(0)
    for names in (["out.b", "out.c", "out.a"], ["out.c", "out.b"], ["out.b"], ["out.a", "out.b", "out.c"]):
        sample = engine.output_sampler(names)
        assert sample() == tuple(engine.output(n) for n in names)
    sample = engine.output_sampler(["out.c", "out.b", "out.a"])
    world.b = 7.0
    engine.execute(25)
    assert sample() == (3.0, 7.0, 1.0) and host["b"] == 7.0
