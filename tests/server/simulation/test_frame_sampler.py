"""The studio's samples read the engines through the recorder's sampler: one mechanism, raw symbols.

The simulation process sends the symbols raw; the server turns them into display values
(``SampleDisplay``, from what the generation announced), so these tests check that conversion
against one made from the simulation's own program tables.
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import orjson

from tests.navset import write_set
from xabsl_studio.engine.emit.json import program_to_json
from xabsl_studio.engine.ir.ic_reader import read_ic
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.lang import Compilation
from xabsl_studio.engine.record import AgentSampler
from xabsl_studio.engine.runtime import Bindings, Engine
from xabsl_studio.engine.types import Kind, Value
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.protocol.display import Displayed, converter, display_values
from xabsl_studio.server.protocol.host import NewGeneration, Sample
from xabsl_studio.server.session.frames import Generation
from xabsl_studio.server.session.live import Session
from xabsl_studio.server.simulation.sampling import FrameSampler, ProgramCodec
from xabsl_studio.server.simulation.worker import Simulation, WorkerConfig

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


def test_samples_carry_the_shared_samplers_raw_values() -> None:
    engine, world, _ = make_engine()
    frames = FrameSampler(0, engine, ProgramCodec.build("main", PROGRAM, engine))
    assert isinstance(frames.reader, AgentSampler)
    recorder = AgentSampler(engine)
    for t in (0, 25, 50):
        world.a += 0.1
        engine.execute(t)
        raw = recorder.sample()
        assert frames.inputs() == raw.inputs and frames.outputs() == raw.outputs  # exact, as read
        assert frames.path() == raw.path  # no parameters: the engine's own path
        assert raw.unread == () and frames.reader.sample().assignments == ()  # the studio skips them


def test_a_host_getter_that_raises_is_none_in_samples_and_unread_in_recordings() -> None:
    engine, _world, broken = make_engine()
    frames = FrameSampler(0, engine, ProgramCodec.build("main", PROGRAM, engine))
    recorder = AgentSampler(engine)
    engine.execute(0)
    broken["c"] = True
    names = recorder.tables.inputs
    sample = recorder.sample()
    assert sample.unread == ("c",)
    assert dict(zip(names, sample.inputs, strict=True)) == {"a": 1.23456, "b": 2.0, "c": None}
    shown = Displayed(tuple(converter(Kind.DECIMAL) for _ in names))
    assert dict(zip(names, shown.display(frames.inputs()), strict=True)) == {"a": 1.235, "b": 2.0, "c": None}
    broken["c"] = False
    assert dict(zip(names, shown.display(frames.inputs()), strict=True)) == {"a": 1.235, "b": 2.0, "c": 3.0}
    assert recorder.sample().unread == ()


def test_display_values_converted_only_where_raw_values_changed_are_those_of_a_full_conversion() -> None:
    rng = random.Random(7)
    calls = [0]

    def counted(value: float) -> float:
        calls[0] += 1
        return round(value * 1000) / 1000

    converters = (counted,) * 40
    shown = Displayed(converters)
    values: list[float | None] = [rng.uniform(-1e4, 1e4) for _ in range(40)]
    for tick in range(300):
        changed = rng.sample(range(40), rng.choice((0, 1, 3, 40)))
        for i in changed:
            values[i] = rng.choice((rng.uniform(-1e4, 1e4), math.nan, math.inf, -0.0, 0.0005, None))
        raw = tuple(values)
        calls[0] = 0
        got = shown.display(raw)
        converted = calls[0]
        assert _nan_free(got) == _nan_free(display_values(converters, raw))
        assert all(g is None for g, v in zip(got, raw, strict=True) if v is None)  # unknown stays unknown
        if tick:  # after the first tick, only what differs from the tick before is converted again
            assert converted <= len(changed) + sum(1 for v in raw if v != v)
    # a getter that raised: None there; its next value is converted
    assert shown.display((None, *values[1:]))[0] is None
    values[0] = 1.23456
    assert shown.display(tuple(values))[0] == 1.235


def _nan_free(values: tuple[object, ...]) -> tuple[object, ...]:
    return tuple("nan" if v != v else v for v in values)


SYMBOLS = 'namespace s("S") { float input speed; bool input flag; float output o; float output p; }\n'
OPTIONS = {
    "agents.xabsl": 'include "s.xabsl";\ninclude "go.xabsl";\ninclude "main.xabsl";\nagent x("X", main);\n',
    "s.xabsl": SYMBOLS,
    "go.xabsl": "option go { float @speed; initial state s { action { o = @speed; p = 2; } } }\n",
    "main.xabsl": "option main { initial state s { action { go(speed = speed); } } }\n",
}


def _options_engine(compile_sources: Callable[..., Compilation], bind: Callable[[Bindings], None]) -> Engine:
    """An engine of OPTIONS whose two inputs ``bind`` registers (the outputs are the engine's)."""
    program = compile_sources(OPTIONS, "agents.xabsl").program
    assert program is not None
    bindings = Bindings()
    bind(bindings)
    for name in ("o", "p"):
        bindings.output(name, Kind.DECIMAL)
    return Engine(bindings, program)


def _generation(program: Program, codec: ProgramCodec) -> Generation:
    """The server's generation of one robot running ``program``, as a host with raw values announces it."""
    structure = {"programs": {"main": program_to_json(program)}, "robots": [{"name": "x", "program": "main"}]}
    message = NewGeneration(
        1,
        "start",
        orjson.dumps(structure),
        b"{}",
        (tuple(i for i, *_ in codec.inputs),),
        (tuple(i for i, *_ in codec.outputs),),
        0,
        {},
        enums={"main": codec.tables.enums},
        raw_values=True,
    )
    return Generation.from_message(message)


def _shown(gen: Generation, frames: FrameSampler, seq: int) -> Sample:
    """One tick of ``frames``'s robot as the simulation sends it, then as the server shows it."""
    path, ins, outs = orjson.dumps(frames.path()), (frames.inputs(),), (frames.outputs(),)
    return gen.shown(Sample(seq, 1, 25 * seq, 0.0, False, 1.0, (path,), (b"",), ins, outs, b"{}", b"{}"))


def test_path_parameters_follow_every_change_of_the_raw_values(compile_sources: Callable[..., Compilation]) -> None:
    world = SimpleNamespace(speed=1.0, flag=True)

    def bind(bindings: Bindings) -> None:
        bindings.input_attribute("speed", Kind.DECIMAL, world, "speed")
        bindings.input_attribute("flag", Kind.BOOLEAN, world, "flag")

    engine = _options_engine(compile_sources, bind)
    program = engine.program
    codec = ProgramCodec.build("main", program, engine)
    frames = FrameSampler(0, engine, codec)
    gen = _generation(program, codec)
    for t, speed in enumerate((1.0, 1.0, 2.00049, 2.00049, 1.0, -3.5, math.nan, 4.25)):
        world.speed = speed
        engine.execute(25 * t)
        (raw,) = [node for node in frames.path() if node[2] == program.options["go"].index]
        assert raw[-1] == [speed] or speed != speed  # the simulation sends it as the engine holds it
        (go,) = [node for node in orjson.loads(_shown(gen, frames, t).paths[0]) if node[2] == raw[2]]
        # shown to 3 digits; NaN, which has no display value, is unknown and the path stays whole
        assert go[-1] == ([round(speed * 1000) / 1000] if speed == speed else [None])


def test_a_sampler_of_one_mapping_returns_what_the_behavior_reads_overrides_included(
    compile_sources: Callable[..., Compilation],
) -> None:
    values: dict[str, Value] = {"speed": 1.0, "flag": True}

    def bind(bindings: Bindings) -> None:
        bindings.input_item("speed", Kind.DECIMAL, values, "speed")
        bindings.input_item("flag", Kind.BOOLEAN, values, "flag")

    engine = _options_engine(compile_sources, bind)
    sample = engine.input_sampler(("speed", "flag"))
    engine.execute(0)
    assert sample() == (1.0, True)
    values["speed"] = 2.5
    assert sample() == (2.5, True)
    engine.root_actions.override_input("speed", 7.0)
    assert sample() == (7.0, True)
    engine.root_actions.release_input("speed")
    assert sample() == (2.5, True)
    assert engine.output_sampler(("p", "o"))() == (2.0, 1.0)  # stored outputs, in the order asked


def _codec_display(codec: ProgramCodec, kinds: tuple[tuple[int, str, Kind, str | None], ...]) -> tuple[Any, ...]:
    """The conversion of a symbol tuple as the simulation's own tables give it (the server's must agree)."""
    return tuple((lambda v, k=kind, e=enum: codec.display(k, e, v)) for _, _, kind, enum in kinds)


def test_a_team_sized_bench_set_shows_what_a_full_conversion_gives(tmp_path: Path) -> None:
    # naoth-2018's shape: 195 inputs and 71 outputs per robot, a few of them set by hand
    write_set(tmp_path, inputs=184, outputs=69)
    example = BenchExample(tmp_path, robots=3)
    session = Session(example)
    programs: Any = {k: (s.running, s.running_json) for k, s in session.programs.items()}
    sim = Simulation(WorkerConfig(example, seed=3, programs=programs))
    message = sim.generation("connect")
    assert isinstance(message, NewGeneration) and message.raw_values
    gen = Generation.from_message(message)
    sampler = sim.samplers[1]
    assert sampler is not None
    assert len(sampler.codec.inputs) == 195 and len(sampler.codec.outputs) == 71
    full_in = _codec_display(sampler.codec, sampler.codec.inputs)
    full_out = _codec_display(sampler.codec, sampler.codec.outputs)
    hand = {5: ("sensor.approach.s0", 1.23456), 9: ("sensor.turn.s3", 2), 14: ("sensor.approach.s0", -0.0004)}
    for tick in range(20):
        if tick in hand:
            symbol, value = hand[tick]
            sim.world.command("set_input", {"robot": 1, "symbol": symbol, "value": value})  # type: ignore[attr-defined]
        raw = sim.tick()
        sample = gen.shown(raw)
        raw_in, raw_out = sampler.reader.inputs()[0], sampler.reader.outputs()[0]
        assert raw.inputs[1] == raw_in and raw.outputs[1] == raw_out  # sent as read
        assert sample.inputs[1] == display_values(full_in, raw_in)
        assert sample.outputs[1] == display_values(full_out, raw_out)
        shown = dict(zip((name for _, name, *_ in sampler.codec.inputs), sample.inputs[1], strict=True))
        if tick >= 14:
            assert shown["sensor.approach.s0"] == -0.0 and shown["sensor.turn.s3"] == 2  # enum: element index
        elif tick >= 5:
            assert shown["sensor.approach.s0"] == 1.235


ENUM_OPTIONS = {
    "agents.xabsl": 'include "s.xabsl";\ninclude "show.xabsl";\ninclude "main.xabsl";\nagent x("X", main);\n',
    "s.xabsl": 'namespace s("S") {\n  enum mode { slow, fast, off };\n  enum mode input mode;\n'
    "  float input speed;\n  enum mode output shown;\n}\n",
    "show.xabsl": "option show { enum mode @m; initial state s { action { shown = @m; } } }\n",
    "main.xabsl": "option main { initial state s { action { show(m = mode); } } }\n",
}


def test_the_server_names_enum_values_the_host_numbers_its_own_way(compile_sources: Callable[..., Compilation]) -> None:
    # Host values 30, 10, 20 for slow, fast, off: a display value is the element's index (0, 1, 2),
    # whatever number the host gives it, and a number the enumeration does not name is -1.
    program = compile_sources(ENUM_OPTIONS, "agents.xabsl").program
    assert program is not None
    world = SimpleNamespace(mode=30, speed=1.23456)
    bindings = Bindings()
    bindings.enum("mode", {"slow": 30, "fast": 10, "off": 20})
    bindings.input_attribute("mode", Kind.ENUM, world, "mode", enum="mode")
    bindings.input_attribute("speed", Kind.DECIMAL, world, "speed")
    bindings.output("shown", Kind.ENUM, enum="mode")
    engine = Engine(bindings, program)
    codec = ProgramCodec.build("main", program, engine)
    frames = FrameSampler(0, engine, codec)
    gen = _generation(program, codec)
    names = [name for _, name, *_ in codec.inputs]
    for t, (mode, element) in enumerate(((30, 0), (10, 1), (20, 2), (99, -1), (30, 0))):
        world.mode = mode
        engine.execute(25 * t)
        assert frames.inputs() == tuple(world.mode if n == "mode" else world.speed for n in names)  # raw as read
        shown = _shown(gen, frames, t)
        assert dict(zip(names, shown.inputs[0], strict=True)) == {"mode": element, "speed": 1.235}
        assert shown.outputs[0] == (element,)
        (show,) = [n for n in orjson.loads(shown.paths[0]) if n[2] == program.options["show"].index]
        assert show[-1] == [element]  # an enum parameter the same way
