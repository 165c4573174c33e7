"""The bench world for a team's own behavior: values by hand, input functions, traces, bindings, broken sets."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest

from tests.server.conftest import LiveServer
from xabsl_studio.engine.host import ExampleError
from xabsl_studio.engine.worlds.bench import BenchExample, BenchWorld
from xabsl_studio.server.session.live import Session
from xabsl_studio.server.simulation.worker import Simulation, WorkerConfig


def simulation(example: BenchExample) -> tuple[Session, Simulation]:
    session = Session(example)
    programs: Any = {k: (s.running, s.running_json) for k, s in session.programs.items()}
    sim = Simulation(WorkerConfig(example, seed=3, programs=programs))
    sim.generation("connect")
    return session, sim


def bench(sim: Simulation, robot: int = 0) -> dict[str, Any]:
    scene: dict[str, Any] = sim.world.dynamic_scene()
    return scene["bench"][robot]


def command(sim: Simulation, name: str, **args: Any) -> Any:
    return sim.world.command(name, args)  # type: ignore[attr-defined]


def test_a_computed_input_function_can_be_set_by_hand_and_computed_again(demo_dir: Path) -> None:
    _, sim = simulation(BenchExample(demo_dir))
    sim.execute(_force(sim, "approach_ball", stop_at=100.0))
    sim.tick()
    calls = bench(sim)["calls"]["clamp"]
    # clamp(value = ball.distance / 2, lo = 50, hi = max_speed): the demo declares clamp(value, lo, hi),
    # so the bench computes it
    ((args, value),) = calls
    assert args[1:] == [50.0, 250.0] and value == max(50.0, min(250.0, args[0]))
    walk = [n for n in sim.samplers[0].path() if n[0] == 1]  # type: ignore[union-attr]
    assert walk and walk[0][4][0] == value, "walk got the function's value as its speed"
    command(sim, "set_function", robot=0, symbol="clamp", value=120.0)
    sim.tick()
    assert bench(sim)["calls"]["clamp"][0][1] == 120.0 and bench(sim)["functions"] == {"clamp": 120.0}
    walk = [n for n in sim.samplers[0].path() if n[0] == 1]  # type: ignore[union-attr]
    assert walk[0][4][0] == 120.0
    assert bench(sim, 1)["functions"] == {}, "per robot"
    scene = sim.world.static_scene()
    assert scene["bench"]["functions"] == ["clamp"] and scene["bench"]["bound"] == []
    assert scene["bench"]["computed"] == {"clamp": "clamp(value, lo, hi)"}
    assert {c["name"] for c in scene["commands"]} == {"set_input", "set_function", "follow_world"}
    command(sim, "follow_world", robot=0, symbol="clamp")
    sim.tick()
    ((args, value),) = bench(sim)["calls"]["clamp"]
    assert value == max(50.0, min(250.0, args[0])) and bench(sim)["functions"] == {}


def _force(sim: Simulation, option: str, **params: Any) -> Any:
    from xabsl_studio.server.protocol.commands import ForceOption

    return ForceOption(op="force_option", robot=0, option=option, params=params)


def test_a_plain_input_set_by_hand_stays_until_changed_and_a_world_input_can_follow_again(demo_dir: Path) -> None:
    _, sim = simulation(BenchExample(demo_dir))
    world = sim.world
    assert isinstance(world, BenchWorld)
    agent = world.agents[0]
    command(sim, "set_input", robot=0, symbol="ball.distance", value=42.0)
    command(sim, "set_input", robot=0, symbol="game.state", value=4)  # element index: finished
    for _ in range(30):
        sim.tick()
    assert agent.values["ball.distance"] == 42.0 and agent.values["game.state"] == 4
    assert bench(sim)["hand"] == ["ball.distance", "game.state"]
    command(sim, "set_input", robot=0, symbol="game.state", value="game.state.playing")
    command(sim, "follow_world", robot=0, symbol="ball.distance")
    sim.tick()
    assert agent.values["ball.distance"] != 42.0 and agent.values["game.state"] == 3
    assert world.agents[1].values["ball.distance"] != 42.0


@pytest.mark.parametrize(
    ("name", "args", "error"),
    [
        ("set_input", {"robot": 0, "symbol": "clamp", "value": 1.0}, "has parameters: set its value with set_function"),
        ("set_function", {"robot": 0, "symbol": "ball.seen", "value": True}, "has no parameters"),
        ("set_input", {"robot": 0, "symbol": "ball.speed", "value": 1.0}, "unknown input symbol 'ball.speed'"),
        ("set_input", {"robot": 0, "symbol": "ball.seen", "value": 1.0}, "is boolean"),
        ("set_input", {"robot": 0, "symbol": "ball.distance", "value": float("nan")}, "not a finite number"),
        ("set_input", {"robot": 0, "symbol": "game.state", "value": 9}, "no element 9"),
        ("set_input", {"robot": 5, "symbol": "ball.seen", "value": True}, "robot must be a robot id in 0..1"),
        ("set_input", {"robot": 0, "symbol": "ball.seen"}, "value is missing"),
        ("follow_world", {"robot": 0, "symbol": "kicks"}, "the bench does not compute 'kicks'"),
        ("teleport", {}, "unknown command 'teleport'"),
    ],
)
def test_bad_values_by_hand_are_refused_with_what_is_wrong(demo_dir: Path, name: str, args: Any, error: str) -> None:
    from xabsl_studio.engine.host import WorldCommandError

    _, sim = simulation(BenchExample(demo_dir))
    with pytest.raises(WorldCommandError, match=None) as raised:
        command(sim, name, **args)
    assert error in str(raised.value)


def test_an_input_trace_plays_on_the_session_clock_and_selects_agents(demo_dir: Path, tmp_path: Path) -> None:
    trace = tmp_path / "in.jsonl"
    lines = [
        {"t": 0, "set": {"ball.distance": 5.0}},
        {"t": 500, "agent": "searcher", "set": {"ball.seen": True, "game.state": "game.state.set"}},
        {"t": 1000, "set": {"ball.distance": 7.5}},
    ]
    trace.write_text("".join(json.dumps(line) + "\n" for line in lines))
    _, sim = simulation(BenchExample(demo_dir, inputs=trace))
    agent = sim.world.agents[0]
    root = sim.samplers[0]
    sim.tick()
    assert agent.values["ball.distance"] == 5.0  # type: ignore[attr-defined]
    first_root = root.path()[0][2]  # type: ignore[union-attr]
    while sim.loop.now_ms <= 500:
        sim.tick()
    assert agent.values["ball.seen"] is True and agent.values["game.state"] == 2  # type: ignore[attr-defined]
    assert agent.values["ball.distance"] == 5.0, "stays until the trace sets it again"  # type: ignore[attr-defined]
    searcher = sim.samplers[0].codec.option_ids["search_ball"]  # type: ignore[union-attr]
    assert root.path()[0][2] == searcher != first_root  # type: ignore[union-attr]
    while sim.loop.now_ms <= 1000:
        sim.tick()
    assert agent.values["ball.distance"] == 7.5  # type: ignore[attr-defined]
    assert sim.world.static_scene()["bench"]["trace"]["end_ms"] == 1000


@pytest.mark.parametrize(
    ("text", "error"),
    [
        ('{"t": 0}\n{"t": "x"}\n', "in.jsonl:2: t must be a non-negative integer"),
        ('{"t": 10}\n\n{"t": 5}\n', "in.jsonl:3: t 5 is before the previous line's 10"),
        ("{nope\n", "in.jsonl:1: not JSON"),
        ('{"t": 0, "sett": {}}\n', "in.jsonl:1: unknown key 'sett'"),
    ],
)
def test_a_malformed_input_trace_is_refused_with_its_line(
    demo_dir: Path, tmp_path: Path, text: str, error: str
) -> None:
    trace = tmp_path / "in.jsonl"
    trace.write_text(text)
    with pytest.raises(ExampleError) as raised:
        BenchExample(demo_dir, inputs=trace)
    assert error in str(raised.value)


def test_a_trace_naming_what_the_behavior_lacks_says_where(demo_dir: Path, tmp_path: Path) -> None:
    trace = tmp_path / "in.jsonl"
    trace.write_text('{"t": 0}\n{"t": 5, "set": {"ball.speed": 1}}\n')
    _, sim = simulation(BenchExample(demo_dir, inputs=trace))
    assert sim.engines == [None, None]
    (error,) = set(sim.errors.values())
    assert error is not None and "in.jsonl:2: unknown input symbol 'ball.speed'" in error


BINDINGS = """
import math
from xabsl_studio.engine.runtime import BasicBehavior
from xabsl_studio.engine.types import Kind


class Stand(BasicBehavior):
    name = "stand"

    def __init__(self, robot):
        super().__init__()
        self.robot = robot

    def execute(self):
        self.robot.rate = 33.0


def bind(bindings, robot):
    def clamp(value, lo, hi):
        return max(lo, min(hi, value))

    params = [("value", Kind.DECIMAL), ("lo", Kind.DECIMAL), ("hi", Kind.DECIMAL)]
    bindings.input("clamp", Kind.DECIMAL, clamp, params=params)
    bindings.input("ball.time_since_seen", Kind.DECIMAL, lambda: 1234.0)
    bindings.behavior(Stand(robot))
"""


def test_a_bindings_module_supplies_functions_plain_inputs_and_basic_behaviors(demo_dir: Path, tmp_path: Path) -> None:
    module = tmp_path / "my_bindings.py"
    module.write_text(BINDINGS)
    _, sim = simulation(BenchExample(demo_dir, bindings=module))
    scene = sim.world.static_scene()["bench"]
    assert scene["bound"] == ["ball.time_since_seen", "clamp"] and scene["functions"] == []
    assert scene["computed"] == {}, "the bindings module replaces the computed clamp"
    assert scene["bindings"] == str(module)
    sim.execute(_force(sim, "approach_ball", stop_at=100.0))
    sim.tick()
    ((args, value),) = bench(sim)["calls"]["clamp"]
    assert value == max(50.0, min(250.0, args[0])) and value > 0
    with pytest.raises(Exception, match="comes from the bindings module"):
        command(sim, "set_function", robot=0, symbol="clamp", value=1.0)
    engine = sim.engines[0]
    assert engine is not None and engine.input_sampler(["ball.time_since_seen"])() == (1234.0,)
    from xabsl_studio.server.protocol.commands import ForceBehavior

    sim.execute(ForceBehavior(op="force_behavior", robot=0, behavior="stand", params={}))
    sim.tick()
    assert sim.world.agents[0].rate == 33.0  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("text", "error"),
    [("x = 1\n", "defines no function bind(bindings, robot)"), ("import nowhere_at_all\n", "ModuleNotFoundError")],
)
def test_a_bindings_module_that_does_not_load_says_why(demo_dir: Path, tmp_path: Path, text: str, error: str) -> None:
    module = tmp_path / f"b{len(text)}.py"
    module.write_text(text)
    with pytest.raises(ExampleError) as raised:
        BenchExample(demo_dir, bindings=module)
    assert error in str(raised.value) and str(module) in str(raised.value)


def _break(demo_dir: Path) -> Path:
    file = demo_dir / "options" / "approach_ball.xabsl"
    file.write_text(file.read_text().replace("goto kicked;", "goto kicked"))
    return file


def test_a_behavior_with_errors_opens_with_what_parsed_and_starts_when_fixed(demo_dir: Path, client_for: Any) -> None:
    file = _break(demo_dir)
    session = Session(BenchExample(demo_dir), speed=2.0)
    key = next(iter(session.programs))
    with LiveServer(session) as server, httpx.Client(base_url=server.url) as http:
        client = client_for(server)
        hello = client.wait_hello("connect")
        program = hello["structure"]["programs"][key]
        assert sorted(o["name"] for o in program["options"]) == ["play", "search_ball"]
        assert {a["name"] for a in program["agents"]} == {"chaser", "searcher"}
        assert {s["name"] for s in program["inputs"]} >= {"ball.distance", "clamp"}
        robots = hello["structure"]["robots"]
        assert [(r["program"], r["engine"]) for r in robots] == [(key, False), (key, False)]
        status = http.get("/api/status").json()["programs"][key]
        assert status["ok"] is False and status["running"] is False and status["partial"] is True
        (error,) = [d for d in status["diagnostics"] if d["severity"] == "error"]
        assert error["span"]["file"] == "options/approach_ball.xabsl" and error["span"]["line"] == 20
        graph = http.get(f"/api/graph/{key}")
        assert graph.status_code == 200 and 'id="missing_approach_ball"' in graph.text
        assert "approach_ball (does not compile)" in graph.text
        assert http.get(f"/api/graph/{key}/play").status_code == 200
        refused = client.command("force_option", robot=0, option="play")
        assert refused["ok"] is False and "its behavior has errors" in refused["error"]
        # fix it in the editor: the robots start
        listed = http.get(f"/api/files/{error['span']['file']}").json()
        fixed = listed["text"].replace("goto kicked\n", "goto kicked;\n")
        saved = http.put(f"/api/files/{listed['path']}", json={"text": fixed, "version": listed["version"]})
        assert saved.status_code == 200, saved.text
        reload = client.wait_hello("reload")
        assert [r["engine"] for r in reload["structure"]["robots"]] == [True, True]
        assert len(reload["structure"]["programs"][key]["options"]) == 3
        client.wait_frame(lambda f: bool(f["robots"][0]["path"]))
        assert file.read_text() == fixed


def test_a_hot_reload_that_breaks_keeps_the_last_good_behavior_running(demo_dir: Path, client_for: Any) -> None:
    session = Session(BenchExample(demo_dir), speed=2.0)
    key = next(iter(session.programs))
    with LiveServer(session) as server, httpx.Client(base_url=server.url) as http:
        client = client_for(server)
        client.wait_hello("connect")
        listed = http.get("/api/files/options/approach_ball.xabsl").json()
        broken = listed["text"].replace("goto kicked;", "goto kicked")
        saved = http.put(f"/api/files/{listed['path']}", json={"text": broken, "version": listed["version"]})
        assert saved.status_code == 422 and saved.json()["saved"] is True
        status = http.get("/api/status").json()["programs"][key]
        assert status["ok"] is False and status["running"] is True and status["partial"] is False
        assert any(d["severity"] == "error" for d in status["diagnostics"])
        frame = client.wait_frame(lambda f: bool(f["robots"][0]["path"]))
        assert frame["robots"][0]["path"], "the last good behavior keeps running"
        assert 'id="option_0"' in http.get(f"/api/graph/{key}").text


def test_a_hot_reload_that_adds_inputs_runs_on_the_bench(demo_dir: Path) -> None:
    session, sim = simulation(BenchExample(demo_dir))
    key = next(iter(session.programs))
    symbols = demo_dir / "symbols.xabsl"
    symbols.write_text(
        symbols.read_text().replace(
            "  /** The game phase",
            '  float input ball.speed "mm/s";\n  bool input near ( float x; float y; );\n  /** The game phase',
        )
    )
    compilation = session.compile(key)
    assert compilation.program is not None, [d.format() for d in compilation.errors]
    from xabsl_studio.engine.emit.json import program_to_json

    assert sim.apply(key, compilation.program, program_to_json(compilation.program, compilation.source_text)) is None
    command(sim, "set_input", robot=0, symbol="ball.speed", value=12.5)
    command(sim, "set_function", robot=0, symbol="near", value=True)
    sim.tick()
    assert sim.world.agents[0].values["ball.speed"] == 12.5  # type: ignore[attr-defined]
    assert "near" in sim.world.static_scene()["bench"]["functions"]


DOC = Path(__file__).resolve().parents[2] / "docs" / "own-behaviors.md"


def _block(language: str) -> str:
    text = DOC.read_text()
    start = text.index(f"```{language}\n") + len(language) + 4
    return text[start : text.index("```", start)]


def test_the_worked_example_of_the_docs_runs_its_bindings_and_its_trace(demo_dir: Path, tmp_path: Path) -> None:
    module = tmp_path / "my_bindings.py"
    module.write_text(_block("python"))
    trace = tmp_path / "steps.jsonl"
    trace.write_text(_block("jsonl"))
    _, sim = simulation(BenchExample(demo_dir, bindings=module, inputs=trace))
    assert sim.world.static_scene()["bench"]["bound"] == ["ball.time_since_seen", "clamp"]
    sim.execute(_force(sim, "approach_ball", stop_at=100.0))
    sim.tick()
    ((args, value),) = bench(sim)["calls"]["clamp"]
    assert args == [450.0, 50.0, 250.0] and value == 250.0, "ball.distance 900 from the trace, halved, clamped"
    walk = [n for n in sim.samplers[0].path() if n[0] == 1]  # type: ignore[union-attr]
    assert walk[0][4][:2] == [250.0, 40.0]


@pytest.mark.parametrize(
    ("flags", "error"),
    [
        (["--bindings", "nope.py"], "nope.py: no such file"),
        (["--inputs", "nope.jsonl"], "nope.jsonl"),
    ],
)
def test_serve_refuses_bench_flags_that_do_not_load(demo_dir: Path, flags: list[str], error: str) -> None:
    import subprocess
    import sys

    result = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "serve", str(demo_dir), *flags],
        capture_output=True,
        text=True,
        cwd=demo_dir,
    )
    assert result.returncode == 2 and error in result.stderr


def test_serve_says_the_bench_flags_are_the_bench_worlds(tmp_path: Path) -> None:
    import subprocess
    import sys

    soccer = Path(__file__).resolve().parents[2] / "examples" / "soccer"
    result = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "serve", str(soccer), "--inputs", str(tmp_path / "x.jsonl")],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 2 and "options of the bench world" in result.stderr
