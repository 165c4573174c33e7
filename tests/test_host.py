"""The host contract: phase order, time, rates and the headless run loop (engine/host.py)."""

from __future__ import annotations

import ast
from collections.abc import Sequence
from pathlib import Path

import pytest

from xabsl_studio.engine.host import (
    DEFAULT_BEHAVIOR_HZ,
    DEFAULT_PHYSICS_HZ,
    Agent,
    AgentController,
    BehaviorLoop,
    ExampleError,
    PhaseTimes,
    Scene,
    World,
    behavior_source,
    common_root,
    run_headless,
)


class RecordingController:
    def __init__(self, log: list[tuple], name: str) -> None:
        self.log = log
        self.name = name

    def execute(self, now_ms: int) -> None:
        self.log.append(("think", self.name, now_ms))


class RecordingAgent:
    def __init__(self, log: list[tuple], name: str, with_controller: bool = True) -> None:
        self.name = name
        self.team = "blue"
        self.number = 1
        self.log = log
        self.controller: AgentController | None = RecordingController(log, name) if with_controller else None

    def sense(self, now_ms: int) -> None:
        self.log.append(("sense", self.name, now_ms))

    def act(self, now_ms: int) -> None:
        self.log.append(("act", self.name, now_ms))


class RecordingWorld:
    def __init__(self, n_agents: int = 2, finish_after_steps: int | None = None) -> None:
        self.seed = 0
        self.log: list[tuple] = []
        self._agents = [RecordingAgent(self.log, f"a{i}", with_controller=i != 1) for i in range(n_agents)]
        self.time = 0.0
        self.steps = 0
        self.finish_after_steps = finish_after_steps

    @property
    def agents(self) -> Sequence[Agent]:
        return self._agents

    @property
    def finished(self) -> bool:
        return self.finish_after_steps is not None and self.steps >= self.finish_after_steps

    def step(self, dt: float) -> None:
        self.time += dt
        self.steps += 1
        self.log.append(("step", dt))

    def static_scene(self) -> Scene:
        return {}

    def dynamic_scene(self) -> Scene:
        return {"t": self.time}

    def status(self) -> Scene:
        return {"time_ms": round(self.time * 1000), "finished": self.finished}


def test_fakes_satisfy_the_protocols():
    world = RecordingWorld()
    assert isinstance(world, World)
    assert isinstance(world.agents[0], Agent)
    assert isinstance(world.agents[0].controller, AgentController)


def test_one_tick_senses_all_then_thinks_all_then_acts_all_then_steps_physics():
    world = RecordingWorld(n_agents=3)
    loop = BehaviorLoop(world, physics_hz=120, behavior_hz=40)
    loop.tick()
    assert world.log == [
        ("sense", "a0", 0),
        ("sense", "a1", 0),
        ("sense", "a2", 0),
        ("think", "a0", 0),
        # a1 has no controller: it is sensed and acts on its last commands, but does not think
        ("think", "a2", 0),
        ("act", "a0", 0),
        ("act", "a1", 0),
        ("act", "a2", 0),
        ("step", 1 / 120),
        ("step", 1 / 120),
        ("step", 1 / 120),
    ]


def test_now_ms_counts_ticks_in_integer_milliseconds():
    world = RecordingWorld(n_agents=1)
    seen: list[int] = []
    stats = run_headless(world, duration_s=0.2, on_tick=lambda now: seen.append(now) and None)
    assert seen == [0, 25, 50, 75, 100, 125, 150, 175]
    assert stats.ticks == 8
    assert stats.physics_steps == 8 * DEFAULT_PHYSICS_HZ // DEFAULT_BEHAVIOR_HZ
    assert stats.sim_seconds == pytest.approx(0.2)
    assert world.time == pytest.approx(0.2)


def test_thirty_hz_ticks_do_not_drift():
    loop = BehaviorLoop(RecordingWorld(n_agents=1), physics_hz=120, behavior_hz=30)
    for _ in range(300):
        loop.tick()
    assert loop.now_ms == 10_000
    assert all(isinstance(x, int) for x in [loop.now_ms])


def test_start_ms_offsets_the_clock():
    loop = BehaviorLoop(RecordingWorld(n_agents=1), start_ms=5000)
    assert loop.now_ms == 5000
    loop.tick()
    assert loop.now_ms == 5025


@pytest.mark.parametrize(
    ("physics_hz", "behavior_hz"),
    [(60, 30), (200, 60), (200, 20), (200, 30), (120, 50)],
)
def test_bad_rates_are_rejected(physics_hz, behavior_hz):
    with pytest.raises(ValueError):
        BehaviorLoop(RecordingWorld(), physics_hz=physics_hz, behavior_hz=behavior_hz)


def test_on_tick_returning_true_stops_the_run():
    world = RecordingWorld(n_agents=1)
    stats = run_headless(world, duration_s=10, on_tick=lambda now: now >= 100)
    assert stats.ticks == 5


def test_run_stops_when_the_world_is_finished():
    world = RecordingWorld(n_agents=1, finish_after_steps=30)
    stats = run_headless(world, duration_s=10)
    assert stats.physics_steps == 30
    assert world.finished


def test_run_can_ignore_finished():
    world = RecordingWorld(n_agents=1, finish_after_steps=3)
    stats = run_headless(world, duration_s=1, stop_when_finished=False)
    assert stats.ticks == 40


def test_phase_times_are_measured_and_shares_sum_to_one():
    stats = run_headless(RecordingWorld(n_agents=4), duration_s=1)
    shares = stats.phases.shares()
    assert set(shares) == {"perception", "engine", "actuation", "physics"}
    assert sum(shares.values()) == pytest.approx(1.0)
    assert stats.wall_seconds >= stats.phases.total > 0.0
    assert stats.real_time_factor > 0.0
    assert PhaseTimes().shares() == {"perception": 0.0, "engine": 0.0, "actuation": 0.0, "physics": 0.0}


def test_engine_never_imports_pymunk():
    # The architecture's rule "engine/ is platform independent": no module under engine/ may
    # import pymunk (checked on the syntax tree, so a comment mentioning it is fine).
    root = Path(__file__).resolve().parents[1] / "engine"
    offenders = []
    for path in root.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            if any(n.split(".")[0] == "pymunk" for n in names):
                offenders.append(str(path))
    assert offenders == []


# -- behavior sources of world plug-ins ------------------------------------------------------------


def _write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def test_a_behavior_source_knows_the_folders_of_its_include_closure(tmp_path: Path) -> None:
    agents = _write(
        tmp_path / "src" / "behavior" / "agents.xabsl",
        'include "options/a.xabsl";\ninclude "../common/symbols.xabsl";\n',
    )
    _write(tmp_path / "src" / "behavior" / "options" / "a.xabsl", 'include "../../common/symbols.xabsl";\n')
    _write(tmp_path / "src" / "common" / "symbols.xabsl", 'namespace s("s") { float input x; }\n')
    source = behavior_source(agents)
    assert source.key == "behavior" and source.agents_file == agents.resolve()
    # options/ lies below behavior/: served with it, not listed apart
    assert source.file_folders == ((tmp_path / "src" / "behavior").resolve(), (tmp_path / "src" / "common").resolve())
    assert common_root([source]) == (tmp_path / "src").resolve()
    assert behavior_source(agents, "home").key == "home"


def test_a_behavior_source_of_another_name_and_a_missing_one(tmp_path: Path) -> None:
    lone = _write(tmp_path / "Team.xabsl", "/* no includes */\n")
    source = behavior_source(lone)
    assert source.key == "Team" and source.file_folders == (tmp_path.resolve(),)
    with pytest.raises(ExampleError, match="no such agents file"):
        behavior_source(tmp_path / "nope.xabsl")
