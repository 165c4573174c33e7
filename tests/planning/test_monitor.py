from pathlib import Path

import pytest

from engine.planning.graphplan import graphplan
from engine.planning.monitor import DEFAULT_TIMEOUTS, OpStatus, PlanMonitor, PlanStatus, is_done
from engine.planning.strips import load_task

# Copies of /work/shared/data/errands so the tests do not depend on files outside the repository.
DATA = Path(__file__).parent / "data"


@pytest.fixture
def task():
    return load_task(DATA / "domain.pddl", DATA / "problem.pddl")


@pytest.fixture
def monitor(task):
    return PlanMonitor(task, graphplan(task).plan)


def run_ideal_world(monitor, facts, dt=1.0, op_duration=3.0, limit=200.0):
    """Apply the current operator's effects after it has been current for op_duration seconds."""
    trace, t, since = [], 0.0, None
    cur_name = None
    while t < limit:
        status = monitor.update(facts, t)
        if status is not PlanStatus.EXECUTING:
            return status, trace, facts
        cur = monitor.current
        if cur.name != cur_name:
            cur_name, since = cur.name, t
            trace.append(cur.name)
        if t - since >= op_duration:
            facts = cur.apply(frozenset(facts))
        t += dt
    return monitor.status, trace, facts


def test_executes_paper_plan_one_operator_at_a_time(monitor, task):
    status, trace, facts = run_ideal_world(monitor, task.init)
    assert status is PlanStatus.DONE
    assert trace == [
        "goto a c",
        "load mug c",
        "goto c b",
        "load book b",
        "goto b a",
        "unload book a",
        "unload mug a",
    ]
    assert task.goal <= facts


def test_first_operator_selected_and_later_ops_not_done_early(monitor, task):
    assert monitor.update(task.init, 0.0) is PlanStatus.EXECUTING
    assert monitor.current.name == "goto a c"
    # `goto b a` satisfies add ⊆ F ∧ del ∩ F = ∅ at t=0, but its layer is not open yet.
    goto_ba = next(q for q in monitor.queue if q.name == "goto b a")
    assert is_done(goto_ba.action, task.init)
    assert goto_ba.status is OpStatus.PENDING


def test_done_requires_add_present_and_delete_absent(task):
    load = task.action("load mug c")
    assert not is_done(load, frozenset({"has-robot mug", "at mug c"}))
    assert is_done(load, frozenset({"has-robot mug", "at-robot c"}))


def test_done_is_latched(monitor, task):
    monitor.update(task.init, 0.0)
    f1 = task.action("goto a c").apply(task.init)
    monitor.update(f1, 1.0)
    assert monitor.current.name == "load mug c"
    f2 = task.action("load mug c").apply(f1)
    f3 = task.action("goto c b").apply(f2)
    monitor.update(f3, 2.0)
    # goto a c is no longer "done" in F (robot left c) but stays done: no going back.
    assert next(q for q in monitor.queue if q.name == "goto a c").status is OpStatus.DONE
    assert monitor.current.name == "load book b"


def test_timeout_per_schema(monitor, task):
    assert DEFAULT_TIMEOUTS == {"goto": 60.0, "load": 30.0, "unload": 10.0}
    monitor.update(task.init, 0.0)
    assert monitor.update(task.init, 60.0) is PlanStatus.EXECUTING
    assert monitor.update(task.init, 60.02) is PlanStatus.REPLANNING
    assert monitor.reason == "goto a c timed out after 60 s"
    assert monitor.queue[0].status is OpStatus.FAILED


def test_timeouts_configurable(task):
    m = PlanMonitor(task, graphplan(task).plan, timeouts={"goto": 5.0}, default_timeout=2.0)
    m.update(task.init, 0.0)
    assert m.update(task.init, 5.5) is PlanStatus.REPLANNING
    assert m.timeout_for(task.action("load mug c")) == 2.0


def test_mug_moved_timeout_then_replan_from_facts(monitor, task):
    # §4.4 claim 21 at the data level: the mug is moved from c to b during GOTO(a,c). Object
    # locations are not observable, so the derived facts still say `at mug c` and LOAD times out.
    monitor.update(task.init, 0.0)
    belief = frozenset({"at-robot c", "at book b", "at mug c"})
    monitor.update(belief, 10.0)
    assert monitor.current.name == "load mug c"
    assert monitor.update(belief, 40.0) is PlanStatus.EXECUTING
    assert monitor.update(belief, 40.1) is PlanStatus.REPLANNING
    assert monitor.reason == "load mug c timed out after 30 s"
    # The caller (world or XABSL option) revises the belief before replanning.
    facts = frozenset({"at-robot c", "at book b", "at mug b"})
    result = monitor.replan(facts, 40.1)
    assert result.solved
    assert result.plan.names() == [
        ["goto c b"],
        ["load book b", "load mug b"],
        ["goto b a"],
        ["unload book a", "unload mug a"],
    ]
    assert monitor.replans == 1
    status, trace, _ = run_ideal_world(monitor, facts)
    assert status is PlanStatus.DONE
    assert trace == ["goto c b", "load book b", "load mug b", "goto b a", "unload book a", "unload mug a"]


def test_non_executable_operator_skipped_then_blocked(monitor, task):
    # current = first not-done op whose pre ⊆ F: with the mug gone from c, LOAD(mug,c) is
    # skipped and the robot goes on with the book; when nothing is executable the monitor asks
    # for a replan.
    monitor.update(task.init, 0.0)
    facts = frozenset({"at-robot c", "at book b"})
    monitor.update(facts, 1.0)
    assert monitor.current.name == "goto c b"
    status, trace, _ = run_ideal_world(monitor, facts)
    assert status is PlanStatus.REPLANNING
    assert trace == ["goto c b", "load book b", "goto b a", "unload book a"]
    assert monitor.reason == "no remaining operator is executable in the derived facts"
    assert monitor.current is None


def test_replan_unsolvable_fails_with_reason(task):
    blocked = task.with_goal({"at book a", "at mug a"})
    m = PlanMonitor(blocked, graphplan(blocked).plan)
    # Book vanished: no fact says where it is, so no plan can bring it to a.
    res = m.replan({"at-robot a", "at mug c"}, 3.0)
    assert not res.solved
    assert m.status is PlanStatus.FAILED
    assert "no plan" in m.reason


def test_max_replans(task):
    m = PlanMonitor(task, graphplan(task).plan, max_replans=1)
    assert m.replan(task.init, 0.0) is not None
    assert m.replan(task.init, 1.0) is None
    assert m.status is PlanStatus.FAILED
    assert m.reason == "gave up after 1 replans"


def test_parallel_layer_any_order(task):
    # If the world happens to finish `unload mug a` first, `unload book a` is still selected.
    m = PlanMonitor(task, graphplan(task).plan)
    facts = frozenset({"at-robot a", "has-robot book", "has-robot mug"})
    for q in m.queue[:5]:
        q.status = OpStatus.DONE
    m.update(facts, 0.0)
    assert m.current.name == "unload book a"
    facts2 = task.action("unload mug a").apply(facts)
    m.update(facts2, 1.0)
    assert [q.status for q in m.queue[5:]] == [OpStatus.CURRENT, OpStatus.DONE]
    m.update(task.action("unload book a").apply(facts2), 2.0)
    assert m.status is PlanStatus.DONE
    assert m.snapshot()["status"] == "done"


def test_start_plans_from_init(task):
    m = PlanMonitor(task)
    assert m.status is PlanStatus.IDLE
    m.start(task.init, 0.0)
    assert m.status is PlanStatus.EXECUTING
    assert len(m.queue) == 7
    assert m.events[-1].kind == "planned"
