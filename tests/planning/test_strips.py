from pathlib import Path

import pytest

from xabsl_studio.engine.planning.strips import (
    PlanningError,
    UnsupportedPDDLError,
    fact,
    load_task,
    parse_task,
)

# Copies of /work/shared/data/errands so the tests do not depend on files outside the repository.
DATA = Path(__file__).parent / "data"
DOMAIN = (DATA / "domain.pddl").read_text()
PROBLEM = (DATA / "problem.pddl").read_text()


@pytest.fixture(scope="module")
def task():
    return load_task(DATA / "domain.pddl", DATA / "problem.pddl")


def test_grounds_eighteen_actions_sorted_by_name(task):
    names = [a.name for a in task.actions]
    assert len(names) == 18  # §2.4: pyperplan grounding gives 18 ground operators too
    assert names == sorted(names)
    assert names[:6] == ["goto a b", "goto a c", "goto b a", "goto b c", "goto c a", "goto c b"]


def test_static_predicate_pruned_from_init_and_preconditions(task):
    assert task.init == {"at-robot a", "at book b", "at mug c"}
    assert all(not f.startswith("connected") for f in task.facts)
    assert "connected a c" in task.statics
    goto = task.action("goto a c")
    assert goto.pre == {"at-robot a"}
    assert goto.add == {"at-robot c"}
    assert goto.delete == {"at-robot a"}
    assert goto.schema == "goto" and goto.args == ("a", "c")


def test_self_loops_not_grounded_because_connected_excludes_them(task):
    assert all(a.args[0] != a.args[1] for a in task.actions if a.schema == "goto")


def test_typing_respected(task):
    # load ?o - item ?l - location: never an item as location or vice versa.
    assert {a.args[0] for a in task.actions if a.schema == "load"} == {"book", "mug"}
    assert {a.args[1] for a in task.actions if a.schema == "load"} == {"a", "b", "c"}


def test_goal_and_fact_helper(task):
    assert task.goal == {fact("at", "book", "a"), fact("at", "mug", "a")}


def test_with_init_rejects_unknown_fact(task):
    with pytest.raises(PlanningError, match="unknown facts in new initial state: at-robot z"):
        task.with_init({"at-robot z"})
    assert task.with_init({"at-robot b", "connected a b"}).init == {"at-robot b"}


def test_apply_deletes_then_adds(task):
    s = task.action("goto a c").apply(task.init)
    assert s == {"at-robot c", "at book b", "at mug c"}


def test_unsupported_requirement_named():
    dom = DOMAIN.replace("(:requirements :strips :typing)", "(:requirements :strips :typing :conditional-effects)")
    with pytest.raises(UnsupportedPDDLError, match=":conditional-effects"):
        parse_task(dom, PROBLEM)


def test_negative_precondition_named():
    dom = DOMAIN.replace("(:requirements :strips :typing)", "(:requirements :strips :typing :negative-preconditions)")
    with pytest.raises(UnsupportedPDDLError, match="negative-preconditions"):
        parse_task(dom, PROBLEM)


def test_disjunctive_precondition_named_by_construct():
    dom = DOMAIN.replace(
        "(:requirements :strips :typing)", "(:requirements :strips :typing :disjunctive-preconditions)"
    )
    dom = dom.replace(
        ":precondition (and (at-robot ?from) (connected ?from ?to))",
        ":precondition (or (at-robot ?from) (connected ?from ?to))",
    )
    # The requirement is reported first; without it the pddl parser itself refuses `or`.
    with pytest.raises(UnsupportedPDDLError, match="disjunctive-preconditions"):
        parse_task(dom, PROBLEM)


def test_construct_check_independent_of_requirements():
    from pddl.core import Domain
    from pddl.logic.base import Or
    from pddl.parser.domain import DomainParser
    from pddl.parser.problem import ProblemParser

    from xabsl_studio.engine.planning.strips import ground

    dom = DomainParser()(DOMAIN)
    goto = next(a for a in dom.actions if a.name == "goto")
    bad = type(goto)(goto.name, goto.parameters, precondition=Or(*goto.precondition.operands), effect=goto.effect)
    dom2 = Domain(
        dom.name,
        requirements=dom.requirements,
        types=dom.types,
        predicates=dom.predicates,
        actions=[bad, *(a for a in dom.actions if a.name != "goto")],
    )
    with pytest.raises(UnsupportedPDDLError, match=r"action goto :precondition: disjunction \(or \.\.\.\)"):
        ground(dom2, ProblemParser()(PROBLEM))


def test_static_goal_false_is_error():
    prob = PROBLEM.replace("(:goal (and (at book a) (at mug a)))", "(:goal (and (at book a) (connected a a)))")
    with pytest.raises(PlanningError, match="static facts that are false initially: connected a a"):
        parse_task(DOMAIN, prob)
