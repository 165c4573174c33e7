"""The errands world piece by piece: sensors, gripper, truth, plan board, host contract, scenes."""

from __future__ import annotations

import math

import orjson
import pytest

from xabsl_studio.engine.host import Agent, World
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.planning.monitor import PlanBoard
from xabsl_studio.engine.planning.strips import load_task
from xabsl_studio.examples.errands.arena import Arena, Box
from xabsl_studio.examples.errands.facts import Truth, truth_facts
from xabsl_studio.examples.errands.plan import errands_board
from xabsl_studio.examples.errands.world import AGENTS_PATH, DOMAIN_PATH, PROBLEM_PATH, build_world, run_world

# -- arena sensors ----------------------------------------------------------------------------------


def test_bearing_is_positive_to_the_left():
    arena = Arena()
    arena.place_robot(4.0, 3.0, 0.0)  # facing +x; c = (4, 6.5) is straight to the left
    s = arena.sense({})
    assert s["φ_c"] == pytest.approx(0.5)
    assert s["φ_b"] < 0.0  # b = (6.5, 1.5) is ahead and to the right


def test_range_rays_read_one_minus_distance_over_range():
    arena = Arena()
    # Facing the east wall (x = 8) from 0.5 m inside the rim: each ray at ±0.5 rad travels
    # (0.8 − 0.2·cos 0.5)/cos 0.5 m... measured from the rim along the ray.
    arena.place_robot(7.0, 3.0, 0.0)
    s = arena.sense({})
    rim_to_wall = (8.0 - 0.02 - 7.0) / math.cos(0.5) - 0.2
    assert s["o_l"] == pytest.approx(1.0 - rim_to_wall, abs=1e-6)
    assert s["o_l"] == pytest.approx(s["o_r"], abs=1e-9)
    arena.place_robot(2.0, 3.0, 0.0)  # nothing within 1 m
    s = arena.sense({})
    assert s["o_l"] == 0.0 and s["o_r"] == 0.0


def test_object_detector_is_graded_and_limited_to_the_cone():
    arena = Arena()
    bx, by = arena.items["book"].x, arena.items["book"].y
    for d, expected in ((0.3, 1.0), (0.55, 0.5), (0.8, 0.0), (1.0, 0.0)):
        arena.place_robot(bx - d, by, 0.0)
        assert arena.sense({})["γ_book"] == pytest.approx(expected, abs=1e-9)
    arena.place_robot(bx - 0.5, by, math.pi / 2)  # book at −90°: outside ±0.6 rad
    s = arena.sense({})
    assert s["γ_book"] == 0.0 and s["ψ_book"] == 0.0


def test_gripper_grabs_only_close_and_in_front_and_releases_at_the_gripper():
    arena = Arena()
    bx, by = arena.items["book"].x, arena.items["book"].y
    arena.place_robot(bx - 0.5, by, 0.0)
    assert arena.grip("book", 1.0, 0.0) is None  # too far
    arena.place_robot(bx - 0.25, by, 0.0)
    assert arena.grip("book", 1.0, 0.0) == "grabbed"
    assert arena.sense({})["γ_book"] == 0.0  # held objects are not detected
    assert "has-robot book" in truth_facts(arena)
    arena.place_robot(2.0, 2.0, 0.0)
    assert arena.grip("book", 0.0, 1.0) == "released"
    assert (arena.items["book"].x, arena.items["book"].y) == pytest.approx(arena.gripper_point())


def test_cached_truth_equals_recomputed_truth_through_item_events():
    arena = Arena()
    truth = Truth(arena)
    assert truth() == truth_facts(arena) == frozenset({"at-robot a", "at book b", "at mug c"})
    arena.teleport("mug", 6.5, 1.8)
    assert truth() == truth_facts(arena)
    arena.remove("book")
    assert truth() == truth_facts(arena) == frozenset({"at-robot a", "at mug b"})


def test_robot_slides_along_a_blocking_wall_instead_of_passing_it():
    arena = Arena()
    arena.block(Box(3.0, 1.3, 0.2, 1.6))
    arena.place_robot(2.0, 1.3, 0.0)
    arena.drive(1.0, 1.0)
    for _ in range(300):
        arena.step(0.01)
    x, _, _ = arena.pose()
    assert x < 3.0 - 0.1 - 0.2 + 0.02  # stopped at the wall (its face minus the robot radius)


# -- plan board ---------------------------------------------------------------------------------------


@pytest.fixture
def board() -> PlanBoard:
    return errands_board(load_task(DOMAIN_PATH, PROBLEM_PATH))


def test_board_next_executable_follows_the_queue_and_the_facts(board: PlanBoard):
    board.plan_from(board.task.init, 0.0)
    facts = board.task.init
    assert board.next_executable(facts).name == "goto a c"
    board.complete("goto a c", 1.0)
    assert board.next_executable(facts) is None  # load mug c needs at-robot c
    facts = frozenset({"at-robot c", "at book b", "at mug c"})
    assert board.next_executable(facts).name == "load mug c"


def test_board_plans_partially_when_an_object_is_lost_and_extends_when_it_is_seen(board: PlanBoard):
    board.plan_from({"at-robot c", "at book b"}, 5.0, "precondition_lost")
    assert board.solved and board.dropped == frozenset({"at mug a"})
    assert board.plan is not None and str(board.plan).startswith("goto c b | load book b")
    assert not board.can_extend(frozenset({"at-robot b", "has-robot book"}))
    assert board.can_extend(frozenset({"at-robot b", "has-robot book", "at mug b"}))


def test_board_gives_no_plan_when_nothing_but_lost_goals_remain(board: PlanBoard):
    board.plan_from({"at-robot a", "at mug a"}, 5.0, "nothing_executable")
    assert not board.solved
    assert "location of book unknown" in board.reason
    assert board.replans == 1


# -- behavior and host contract -------------------------------------------------------------------------


def test_behavior_compiles_without_diagnostics():
    compilation = compile_file(str(AGENTS_PATH))
    assert compilation.ok and not compilation.diagnostics, [d.format() for d in compilation.diagnostics]
    assert {a.name for a in compilation.program.agents} == {"planner", "reactive"}


def test_world_implements_the_host_contract():
    world = build_world(3)
    assert isinstance(world, World)
    assert all(isinstance(a, Agent) for a in world.agents)
    for scene in (world.static_scene(), world.dynamic_scene(), world.status()):
        orjson.dumps(scene)
    status = world.status()
    assert isinstance(status["time_ms"], int) and status["finished"] is False


def test_same_seed_same_run_and_scenes_stay_plain_data():
    scenes = []
    for _ in range(2):
        world = build_world(7)
        run_world(world, 8.0)
        scenes.append(orjson.dumps(world.dynamic_scene()))
    assert scenes[0] == scenes[1]
    world = build_world(8)
    run_world(world, 8.0)
    assert orjson.dumps(world.dynamic_scene()) != scenes[0]


def test_debug_frame_explains_the_tick():
    world = build_world(1)
    run_world(world, 3.0)
    frame = world.debug_frame()
    orjson.dumps(frame)
    assert frame["monitor"]["op"] == "goto a c" and frame["monitor"]["status"] == "executing"
    assert frame["switches"]["goto a c"] > 0.9
    assert set(frame["alpha"]) == set(world.dd.model.behaviors)
    assert "goto a c" in frame["activation_terms"]["oct"]
    assert set(frame["fusion"]) == set(world.dd.model.actuators)
    assert frame["plan"]["layers"][0] == [{"op": "goto a c", "done": False}]
    assert frame["monitor"]["activation"][0]["option"] == "execute_plan"


def test_fact_events_carry_their_causes():
    world = build_world(1)
    run_world(world, 30.0)  # past arriving at c and loading the mug
    events = {(e.fact, e.cause["phase"]): e for e in world.deriver.events}
    confirmed = events[("has-robot mug", "confirmed")]
    tentative = events[("has-robot mug", "tentative")]
    assert tentative.cause["signals"]["prev(γ_mug)"] >= 0.8 and tentative.cause["signals"]["γ_mug"] == 0.0
    assert confirmed.t - tentative.t == pytest.approx(1.0, abs=0.03)
    assert events[("at mug c", "implied")].cause["by"] == "has-robot mug"
