"""The studio's frames read the engines through the recorder's sampler: one mechanism, display values on top."""

from __future__ import annotations

from types import SimpleNamespace

from xabsl_studio.engine.ir.ic_reader import read_ic
from xabsl_studio.engine.record import AgentSampler
from xabsl_studio.engine.runtime import Bindings, Engine
from xabsl_studio.engine.types import Kind
from xabsl_studio.server.simulation.sampling import FrameSampler, ProgramCodec

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


def make_engine() -> tuple[Engine, SimpleNamespace, dict[str, bool]]:
    world = SimpleNamespace(a=1.23456, b=2.0)
    broken = {"c": False}

    def read_c() -> float:
        if broken["c"]:
            raise RuntimeError("the sensor is gone")
        return 3.0004

    bindings = Bindings()
    bindings.input_attribute("a", Kind.DECIMAL, world, "a")
    bindings.input_attribute("b", Kind.DECIMAL, world, "b")
    bindings.input("c", Kind.DECIMAL, read_c)
    for name in ("out.a", "out.b", "out.c"):
        bindings.output(name, Kind.DECIMAL)
    return Engine(bindings, PROGRAM), world, broken


def test_frames_are_the_shared_samplers_values_for_display() -> None:
    engine, world, _ = make_engine()
    frames = FrameSampler(0, engine, ProgramCodec.build("main", PROGRAM, engine))
    assert isinstance(frames.reader, AgentSampler)
    recorder = AgentSampler(engine)
    for t in (0, 25, 50):
        world.a += 0.1
        engine.execute(t)
        raw = recorder.sample()
        assert frames.inputs() == tuple(round(v * 1000) / 1000 for v in raw.inputs)  # type: ignore[operator]
        assert frames.outputs() == tuple(round(v * 1000) / 1000 for v in raw.outputs)  # type: ignore[operator]
        assert frames.path() == raw.path  # no parameters: the engine's own path
        assert raw.unread == () and frames.reader.sample().assignments == ()  # the studio skips them


def test_a_host_getter_that_raises_is_none_in_frames_and_unread_in_recordings() -> None:
    engine, _world, broken = make_engine()
    frames = FrameSampler(0, engine, ProgramCodec.build("main", PROGRAM, engine))
    recorder = AgentSampler(engine)
    engine.execute(0)
    broken["c"] = True
    names = recorder.tables.inputs
    sample = recorder.sample()
    assert sample.unread == ("c",)
    assert dict(zip(names, sample.inputs, strict=True)) == {"a": 1.23456, "b": 2.0, "c": None}
    assert dict(zip(names, frames.inputs(), strict=True)) == {"a": 1.235, "b": 2.0, "c": None}
    broken["c"] = False
    assert dict(zip(names, frames.inputs(), strict=True)) == {"a": 1.235, "b": 2.0, "c": 3.0}
    assert recorder.sample().unread == ()
