"""A team-shaped behavior on the bench: computed math lets go_to_point leave ``stop``; bench.toml moves the robot."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

from tests.worlds.test_bench import bench, command, simulation
from xabsl_studio.engine.host import ExampleError
from xabsl_studio.engine.worlds.bench import BenchExample, BenchWorld
from xabsl_studio.server.protocol.commands import ForceOption
from xabsl_studio.server.simulation.worker import Simulation

# A behavior shaped like a RoboCup team's (one namespace per file, math functions declared by the
# set itself, a walk request as output symbols); written for this test.
MATH = """/** Math helpers the robot code provides. */
namespace math_symbols("Math") {
  /** |value| */
  float input abs (value;);
  float input atan2 "deg" (y [..] "mm"; x [..] "mm";);
  float input cos (angle [-180..180] "deg";);
  float input sin (angle [-180..180] "deg";);
  float input normalize "deg" (angle "deg";);
  /** length of (x, y) */
  float input vector.abs (float x; float y;);
  float input team.helper (float a; float b;);
}
"""
POSE = """/** Where the robot believes it is, and the walk request. */
namespace pose_symbols("Pose") {
  float input robot_pose.x "mm";
  float input robot_pose.y "mm";
  float input robot_pose.rotation "deg";
  enum motion.type { stand, walk };
  enum motion.type output motion.type;
  float output motion.walk_speed.x "mm/s";
  float output motion.walk_speed.y "mm/s";
  float output motion.walk_speed.rot "deg/s";
  float output debug.helper;
}
"""
GO_TO = """/** Walk to a point of the field, then stand. */
option go_to_spot {
  float @x;
  float @y;
  initial target state stop {
    decision {
      if (vector.abs(x = @x - robot_pose.x, y = @y - robot_pose.y) > 800) goto far_away;
      else stay;
    }
    action { motion.type = stand; debug.helper = team.helper(a = 2, b = 3); }
  }
  state far_away {
    decision {
      if (vector.abs(x = robot_pose.x - @x, y = robot_pose.y - @y) < 200) goto stop;
      else stay;
    }
    action {
      motion.type = walk;
      motion.walk_speed.rot = normalize(angle = atan2(y = @y - robot_pose.y, x = @x - robot_pose.x)
                                              - robot_pose.rotation);
      motion.walk_speed.x = vector.abs(x = @x - robot_pose.x, y = @y - robot_pose.y)
                            * cos(angle = motion.walk_speed.rot);
      motion.walk_speed.y = vector.abs(x = @x - robot_pose.x, y = @y - robot_pose.y)
                            * sin(angle = motion.walk_speed.rot);
    }
  }
}
"""
AGENTS = """include "math_symbols.xabsl";
include "pose_symbols.xabsl";
include "go_to_spot.xabsl";
agent player("Player", go_to_spot);
"""
BENCH = """# the bench robot's pose is what the behavior believes
[inputs]
robot_pose.x = "robot.x"
"robot_pose.y" = "robot.y"
'robot_pose.rotation' = "robot.heading"

[functions]
"team.helper" = "a * 10 + b"

[pose]
when = "motion.type == motion.type.walk"
forward = "clip(motion.walk_speed.x, -300, 300)"
sideways = "clip(motion.walk_speed.y, -300, 300)"
turn = "clip(motion.walk_speed.rot * 2, -120, 120)"
"""


def team_set(folder: Path, bench_file: str | None = None) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    for name, text in (
        ("math_symbols.xabsl", MATH),
        ("pose_symbols.xabsl", POSE),
        ("go_to_spot.xabsl", GO_TO),
        ("agents.xabsl", AGENTS),
    ):
        (folder / name).write_text(text, encoding="utf-8")
    if bench_file is not None:
        (folder / "bench.toml").write_text(bench_file, encoding="utf-8")
    return folder


def go_to(sim: Simulation, x: float, y: float) -> None:
    reply: Any = sim.execute(ForceOption(op="force_option", robot=0, option="go_to_spot", params={"x": x, "y": y}))
    assert reply is None or "error" not in str(reply).lower(), reply


def state_of(sim: Simulation) -> str:
    engine = sim.engines[0]
    assert engine is not None
    option = engine.program.options["go_to_spot"]
    return str(option.states[engine.active_states()[option.index]].name)


def test_go_to_point_leaves_stop_because_vector_abs_is_computed(tmp_path: Path) -> None:
    _, sim = simulation(BenchExample(team_set(tmp_path / "team"), robots=1))
    command(sim, "set_input", robot=0, symbol="robot_pose.x", value=-1000.0)
    command(sim, "set_input", robot=0, symbol="robot_pose.y", value=0.0)
    go_to(sim, 0.0, 0.0)
    sim.tick()
    assert state_of(sim) == "far_away", "vector.abs(1000, 0) = 1000 > 800"
    ((args, value),) = bench(sim)["calls"]["vector.abs"]
    assert args == [1000.0, 0.0] and value == 1000.0
    engine = sim.engines[0]
    assert engine is not None
    assert engine.output("motion.walk_speed.x") == pytest.approx(1000.0), "atan2, normalize, cos computed too"
    assert engine.output("motion.walk_speed.rot") == pytest.approx(0.0)
    computed = sim.world.static_scene()["bench"]["computed"]
    assert computed["vector.abs"] == "vector.abs(x, y)" and computed["cos"] == "cos(angle °)"
    assert "team.helper" not in computed, "no common meaning: settable by hand as before"
    # overridable by hand: vector.abs read 0 -> the robot is "there" -> stop
    command(sim, "set_function", robot=0, symbol="vector.abs", value=0.0)
    sim.tick()
    assert state_of(sim) == "stop"
    command(sim, "follow_world", robot=0, symbol="vector.abs")
    sim.tick()
    assert state_of(sim) == "far_away"


def test_a_bench_file_lets_the_robot_walk_to_the_point_without_python(tmp_path: Path) -> None:
    _, sim = simulation(BenchExample(team_set(tmp_path / "team", BENCH), robots=1))
    world = sim.world
    assert isinstance(world, BenchWorld)
    robot = world.agents[0]
    start = (robot.x, robot.y)
    target = (800.0, 600.0)
    go_to(sim, *target)
    states = []
    for _ in range(40 * 20):  # 20 s of behavior
        sim.tick()
        states.append(state_of(sim))
        if len(states) > 2 and states[-1] == "stop" and "far_away" in states:
            break
    assert states[0] == "far_away" and states[-1] == "stop", "walked there, then stopped"
    assert math.dist((robot.x, robot.y), target) < 200.0 < math.dist(start, target)
    assert robot.values["robot_pose.x"] == pytest.approx(robot.x, abs=20.0), "the pose follows the robot"
    engine = sim.engines[0]
    assert engine is not None
    assert engine.output("debug.helper") == 23.0, "team.helper from the bench file: a * 10 + b"
    scene = world.static_scene()["bench"]
    assert scene["computed"]["team.helper"] == "bench.toml: a * 10 + b"
    assert {"robot_pose.x", "robot_pose.y", "robot_pose.rotation"} <= set(scene["world_inputs"])
    assert scene["bench_file"] == str(tmp_path / "team" / "bench.toml")
    # set by hand, a bench-file input stops following the robot until released
    command(sim, "set_input", robot=0, symbol="robot_pose.x", value=5000.0)
    sim.tick()
    assert robot.values["robot_pose.x"] == 5000.0
    command(sim, "follow_world", robot=0, symbol="robot_pose.x")
    sim.tick()
    assert robot.values["robot_pose.x"] == pytest.approx(robot.x, abs=20.0), "read before the tick moved it"


@pytest.mark.parametrize(
    ("text", "where", "message"),
    [
        ('[pose]\nforward = "motion.walk_speed.x"\nspeed = "1"\n', 3, "unknown pose key 'speed'"),
        ('[inputs]\n"robot_pose.x" = 3\n', 2, "the value is an expression in quotes"),
        ('[inputs]\n\n"robot_pose.x" = "robot.x +"\n', 3, "not an expression"),
        ("[inputs\n", 1, "not TOML"),
        ('[inputs]\n"robot_pose.x" = "' + "(" * 3000 + '"\n', 2, "characters"),
        ('[outputs]\nx = "1"\n', 1, "unknown table 'outputs'"),
    ],
)
def test_a_bad_bench_file_stops_the_start_with_file_and_line(
    tmp_path: Path, text: str, where: int, message: str
) -> None:
    folder = team_set(tmp_path / "team", text)
    with pytest.raises(ExampleError) as raised:
        BenchExample(folder)
    assert f"{folder / 'bench.toml'}:{where}" in str(raised.value) and message in str(raised.value)


@pytest.mark.parametrize(
    ("text", "where", "message"),
    [
        ('[inputs]\n# the pose\nrobot_pose.z = "robot.x"\n', 3, "robot_pose.z: the behavior declares no input symbol"),
        ('[functions]\n"robot_pose.x" = "1"\n', 2, "declares it without parameters"),
        ('[inputs]\n"vector.abs" = "1"\n', 2, "declares it with parameters"),
        ('[pose]\n\nforward = "motion.walk_speed.z"\n', 3, "forward: unknown name 'motion.walk_speed.z'"),
        ('[functions]\n"team.helper" = "a + c"\n', 2, "unknown name 'c'"),
        ('[functions]\n"team.helper" = "pow(a, b)"\n', 2, "unknown function 'pow'"),
        ('[functions]\n"team.helper" = "[a, b]"\n', 2, "not allowed in a bench expression"),
        ('[functions]\n"team.helper" = "' + "-" * 1500 + 'a"\n', 2, "nested too deeply"),
    ],
)
def test_a_bench_file_that_does_not_fit_the_behavior_names_file_and_line(
    tmp_path: Path, text: str, where: int, message: str
) -> None:
    folder = team_set(tmp_path / "team", text)
    _, sim = simulation(BenchExample(folder, robots=1))
    (error,) = sim.errors.values()  # the robots stand, the banner says why
    assert error is not None and f"{folder / 'bench.toml'}:{where}: " in error and message in error, error
    assert sim.engines == [None]


def test_a_bench_file_given_by_path_wins_over_the_one_beside_the_agents(tmp_path: Path) -> None:
    folder = team_set(tmp_path / "team", "[outputs]\n")
    other = tmp_path / "elsewhere.toml"
    other.write_text('[functions]\n"team.helper" = "a - b"\n', encoding="utf-8")
    _, sim = simulation(BenchExample(folder, robots=1, bench=str(other)))
    assert sim.world.static_scene()["bench"]["computed"]["team.helper"] == "elsewhere.toml: a - b"


def test_the_documented_bench_file_reads_and_the_documented_table_is_the_bench_s(tmp_path: Path) -> None:
    from xabsl_studio.engine.worlds.benchfile import BenchFile
    from xabsl_studio.engine.worlds.benchmath import TABLE

    doc = (Path(__file__).resolve().parents[2] / "docs" / "bench.md").read_text(encoding="utf-8")
    example = doc.split("```toml\n", 1)[1].split("```", 1)[0]
    (tmp_path / "bench.toml").write_text(example, encoding="utf-8")
    read = BenchFile.read(tmp_path / "bench.toml")
    assert [e.key for e in read.inputs][:3] == [
        "robot_pose.planned.x",
        "robot_pose.planned.y",
        "robot_pose.planned.rotation",
    ]
    assert [e.key for e in read.pose] == ["when", "forward", "sideways", "turn"]
    table = doc.split("| name | parameters, in declaration order | computes |", 1)[1].split("\n\n", 1)[0]
    documented = {name.strip("` ") for line in table.splitlines()[2:] for name in line.split("|")[1].split(",")}
    assert documented == {row.name for row in TABLE}


def test_a_deep_expression_is_refused_whatever_the_recursion_limit(tmp_path: Path) -> None:
    """Found by CI: with the process's limit raised elsewhere, 1,500 nested minus signs parsed and ran."""
    import sys

    folder = team_set(tmp_path / "team", '[functions]\n"team.helper" = "' + "-" * 1500 + 'a"\n')
    before = sys.getrecursionlimit()
    sys.setrecursionlimit(20_000)
    try:
        _, sim = simulation(BenchExample(folder, robots=1))
    finally:
        sys.setrecursionlimit(before)
    (error,) = sim.errors.values()
    assert error is not None and "nested too deeply" in error, error
