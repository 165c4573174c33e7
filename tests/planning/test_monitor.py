"""The plan board (xabsl_studio.engine.planning.monitor): the queue an XABSL plan monitor reads, and replanning."""

from pathlib import Path

import pytest

from xabsl_studio.engine.planning.monitor import PlanBoard
from xabsl_studio.engine.planning.strips import Fact, load_task

# Copies of /work/shared/data/errands so the tests do not depend on files outside the repository.
DATA = Path(__file__).parent / "data"

PAPER_PLAN = ["goto a c", "load mug c", "goto c b", "load book b", "goto b a", "unload book a", "unload mug a"]


@pytest.fixture
def task():
    return load_task(DATA / "domain.pddl", DATA / "problem.pddl")


@pytest.fixture
def board(task):
    board = PlanBoard(task)
    board.plan_from(task.init, 0.0)
    return board


def run_ideal_world(board, facts, limit=50):
    """Execute next_executable one at a time, applying its effects; return the operators run."""
    trace = []
    for _ in range(limit):
        op = board.next_executable(facts)
        if op is None or board.goal_holds(facts):
            break
        trace.append(op.name)
        facts = op.apply(frozenset(facts))
        board.complete(op.name, float(len(trace)))
    return trace, facts


def test_the_first_plan_queues_the_paper_plan_layer_by_layer(board, task):
    assert board.solved and board.replans == 0 and board.reason == ""
    assert [a.name for a in board.queue] == PAPER_PLAN  # the two parallel UNLOADs by name
    assert [e.kind for e in board.events] == ["planned"]
    trace, facts = run_ideal_world(board, task.init)
    assert trace == PAPER_PLAN and board.goal_holds(facts)
    assert board.done == set(PAPER_PLAN)


def test_next_executable_skips_done_and_unready_operators(board, task):
    assert board.next_executable(task.init).name == "goto a c"
    # `goto b a` is executable at t=0 only by position; the queue keeps the plan's order.
    board.complete("goto a c", 1.0)
    assert board.next_executable(task.init) is None  # load mug c needs at-robot c
    facts = frozenset({"at-robot c", "at book b", "at mug c"})
    assert board.next_executable(facts).name == "load mug c"
    # With the mug gone from c, LOAD(mug, c) is skipped and the robot goes on with the book.
    assert board.next_executable(frozenset({"at-robot c", "at book b"})).name == "goto c b"


def test_done_marks_are_latched_and_counted_once(board):
    board.complete("goto a c", 1.0)
    board.complete("goto a c", 2.0)
    assert [e.kind for e in board.events] == ["planned", "done"]
    assert board.to_json()["layers"][0] == [{"op": "goto a c", "done": True}]


def test_a_replan_restarts_the_queue_from_the_derived_facts(board):
    board.complete("goto a c", 1.0)
    facts = frozenset({"at-robot c", "at book b", "at mug b"})  # the mug was moved to b
    result = board.plan_from(facts, 40.0, "op_timeout")
    assert result.solved and board.replans == 1 and board.done == set()
    assert result.plan.names() == [
        ["goto c b"],
        ["load book b", "load mug b"],
        ["goto b a"],
        ["unload book a", "unload mug a"],
    ]
    assert board.events[-1].kind == "replanned" and board.events[-1].detail.startswith("(op_timeout) goto c b")
    assert len(board.plans) == 2


def test_an_unsolvable_goal_without_a_partial_rule_is_no_plan(board):
    result = board.plan_from({"at-robot a", "at mug c"}, 3.0, "precondition_lost")
    assert not result.solved and not board.solved and board.queue == [] and board.plan is None
    assert board.reason.startswith("no plan from the derived facts: ")
    assert board.events[-1].kind == "no_plan" and board.replans == 1
    assert not board.can_extend(frozenset({"at book b"}))


class DropFacts:
    """A partial-goal rule for tests: drop the goals naming ``word``; extendable when ``signal`` holds."""

    def __init__(self, word: str, signal: Fact) -> None:
        self.word, self.signal = word, signal
        self.calls: list[tuple[frozenset[Fact], frozenset[Fact]]] = []

    def relax(self, goal, facts):
        self.calls.append((goal, facts))
        keep = frozenset(g for g in goal if self.word not in g.split())
        return (keep, f"no {self.word}") if keep != goal else None

    def can_extend(self, dropped, facts):
        return self.signal in facts


def test_a_partial_rule_plans_for_the_reachable_goals_and_says_when_to_extend(task):
    rule = DropFacts("book", "at book c")
    board = PlanBoard(task, rule)
    board.plan_from({"at-robot a", "at mug c"}, 3.0)
    assert rule.calls == [(task.goal, frozenset({"at-robot a", "at mug c"}))]
    assert board.solved and board.dropped == frozenset({"at book a"})
    assert board.reason == "partial plan: at book a left out"
    assert board.events[-1].kind == "partial" and "no book; planning without at book a: " in board.events[-1].detail
    assert [a.name for a in board.queue] == ["goto a c", "load mug c", "goto c a", "unload mug a"]
    assert len(board.results) == 2  # the full attempt and the partial one
    assert not board.can_extend(frozenset({"at-robot a"}))
    assert board.can_extend(frozenset({"at book c"}))


def test_a_partial_plan_that_would_be_empty_is_no_plan(task):
    board = PlanBoard(task, DropFacts("book", "at book c"))
    board.plan_from({"at-robot a", "at mug a"}, 5.0, "nothing_executable")
    assert not board.solved and board.reason == "no plan from the derived facts: no book"
    assert board.events[-1].kind == "no_plan"
