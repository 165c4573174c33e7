"""STRIPS tasks grounded from PDDL: the planning side's input (dual-dynamics.md §2.2, §2.3).

This module owns the step from a PDDL domain and problem (parsed by the MIT ``pddl`` package) to a
propositional STRIPS :class:`Task`: ground facts, ground actions with precondition, add and delete
sets, an initial state and a goal. GRAPHPLAN (:mod:`xabsl_studio.engine.planning.graphplan`), the plan monitor
(:mod:`xabsl_studio.engine.planning.monitor`) and the replanner all work on this data and never see PDDL again.

Conventions (chosen so that plans read like the paper's and like §2.4 of the doc):

* A ground fact is a string ``"at book a"``: predicate name, then its arguments, single spaces.
* A ground action is named ``"goto a c"`` the same way; its schema is the first word.
* Static predicates (never in any effect, ``connected`` in the errands domain) are evaluated
  against the initial state while grounding and then pruned from preconditions, init and goal;
  §2.4 counts |P0| = 3 for the errands problem, which only holds with statics pruned.
* Everything is sorted: ground actions by name, facts lexically. Same input, same task, same plan.

Only ``:strips`` and ``:typing`` are supported. Anything else (negative preconditions,
disjunctions, quantifiers, conditional effects, equality, numeric fluents, ...) raises
:class:`UnsupportedPDDLError` naming the construct, rather than being silently mis-grounded.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

from pddl.core import Domain, Problem
from pddl.logic.base import And, Formula, Not
from pddl.logic.predicates import Predicate
from pddl.logic.terms import Constant
from pddl.parser.domain import DomainParser
from pddl.parser.problem import ProblemParser
from pddl.requirements import Requirements

from xabsl_studio.engine.errors import PlanningError

#: A ground fact, e.g. ``"at-robot a"``.
Fact = str

#: The PDDL requirements the grounder understands; everything else is rejected by name.
SUPPORTED_REQUIREMENTS = frozenset({Requirements.STRIPS, Requirements.TYPING})


class UnsupportedPDDLError(PlanningError):
    """The PDDL uses a construct outside STRIPS + typing; the message names the construct."""


@dataclass(frozen=True, slots=True, order=True)
class GroundAction:
    """One STRIPS operator instance: ``goto a c`` with its precondition, add and delete sets.

    Ordering compares ``name`` first, which is the deterministic tie-break GRAPHPLAN uses.
    """

    name: str
    pre: frozenset[Fact] = field(compare=False)
    add: frozenset[Fact] = field(compare=False)
    delete: frozenset[Fact] = field(compare=False)

    @property
    def schema(self) -> str:
        """The operator schema (PDDL action name), e.g. ``"goto"``."""
        return self.name.split(" ", 1)[0]

    @property
    def args(self) -> tuple[str, ...]:
        """The objects the schema's parameters are bound to, in parameter order."""
        return tuple(self.name.split(" ")[1:])

    def applicable(self, state: frozenset[Fact]) -> bool:
        """Whether the precondition holds in ``state``."""
        return self.pre <= state

    def apply(self, state: frozenset[Fact]) -> frozenset[Fact]:
        """Return the STRIPS successor: delete first, then add (an action that adds and deletes p keeps p)."""
        return (state - self.delete) | self.add

    def to_json(self) -> dict[str, object]:
        """Plain data for the UI and recordings."""
        return {
            "name": self.name,
            "pre": sorted(self.pre),
            "add": sorted(self.add),
            "del": sorted(self.delete),
        }


@dataclass(frozen=True, slots=True)
class Task:
    """A grounded STRIPS problem with statics pruned.

    Attributes:
        name: the PDDL problem name.
        facts: every fluent ground fact that occurs in init, goal or some action, sorted.
        init: fluent facts true initially.
        goal: fluent facts that must hold at the end.
        actions: ground actions sorted by name.
        statics: the static facts of the initial state (kept for display and for replanning).
        objects: object name -> its type names (including supertypes).
    """

    name: str
    facts: tuple[Fact, ...]
    init: frozenset[Fact]
    goal: frozenset[Fact]
    actions: tuple[GroundAction, ...]
    statics: frozenset[Fact]
    objects: Mapping[str, frozenset[str]]

    def with_init(self, init: Iterable[Fact]) -> Task:
        """Return the same task from another initial state: what replanning from derived facts needs.

        Static facts in ``init`` are ignored (they are already compiled into the actions); unknown
        fluent facts are an error because no action could ever use or change them.
        """
        state = frozenset(init) - self.statics
        known = set(self.facts)
        unknown = sorted(state - known)
        if unknown:
            raise PlanningError(f"unknown facts in new initial state: {', '.join(unknown)}")
        return Task(self.name, self.facts, state, self.goal, self.actions, self.statics, self.objects)

    def with_goal(self, goal: Iterable[Fact]) -> Task:
        """Return the same task with another goal (facts must be fluent facts of the task)."""
        g = frozenset(goal)
        unknown = sorted(g - set(self.facts))
        if unknown:
            raise PlanningError(f"unknown goal facts: {', '.join(unknown)}")
        return Task(self.name, self.facts, self.init, g, self.actions, self.statics, self.objects)

    def action(self, name: str) -> GroundAction:
        """Return the ground action called ``name``; ``KeyError`` names it when absent."""
        for a in self.actions:
            if a.name == name:
                return a
        raise KeyError(f"no ground action {name!r} in task {self.name!r}")


def fact(name: str, *args: str) -> Fact:
    """Spell a ground fact the way the grounder does: ``fact("at", "book", "a") == "at book a"``."""
    return " ".join((name, *args))


# --- loading -------------------------------------------------------------------------------------


#: The largest PDDL file read (a real domain or problem is a few kilobytes).
MAX_PDDL_BYTES = 16 * 1024 * 1024


def read_pddl(path: str | Path) -> str:
    """The text of a PDDL file: a regular file of at most :data:`MAX_PDDL_BYTES`, UTF-8.

    Raises:
        OSError: missing, unreadable, not a regular file (``xabsl_studio.engine.files.NotRegularFile``) or too large.
        UnicodeDecodeError: not UTF-8.
    """
    from xabsl_studio.engine.files import read_regular

    return read_regular(path, MAX_PDDL_BYTES).decode("utf-8")


def load_task(domain_path: str | Path, problem_path: str | Path) -> Task:
    """Parse a PDDL domain and problem file and ground them.

    Raises:
        OSError, UnicodeDecodeError: a file that cannot be read (see :func:`read_pddl`).
        UnsupportedPDDLError: a requirement or construct outside STRIPS + typing.
        PlanningError: a problem inconsistent with its domain (unknown type or predicate).
    """
    return parse_task(read_pddl(domain_path), read_pddl(problem_path))


def parse_task(domain_text: str, problem_text: str) -> Task:
    """Like :func:`load_task` but from PDDL text (what the studio's ``POST /plan`` receives)."""
    domain = DomainParser()(domain_text)
    problem = ProblemParser()(problem_text)
    return ground(domain, problem)


def ground(domain: Domain, problem: Problem) -> Task:
    """Ground a parsed domain and problem into a :class:`Task`.

    Actions are instantiated over every type-correct tuple of objects (and domain constants);
    instances whose static preconditions fail in the initial state are dropped.
    """
    _check_requirements(domain.requirements, "domain")
    _check_requirements(problem.requirements, "problem")

    parents = {str(k): (str(v) if v is not None else None) for k, v in dict(domain.types).items()}
    objects: dict[str, frozenset[str]] = {}
    for obj in [*domain.constants, *problem.objects]:
        objects[str(obj.name)] = _with_supertypes(obj.type_tags, parents)

    schemas = []
    for action in sorted(domain.actions, key=lambda a: str(a.name)):
        where = f"action {action.name!s}"
        pre = _atoms(action.precondition, where + " :precondition", allow_negation=False)
        eff = _atoms(action.effect, where + " :effect", allow_negation=True)
        schemas.append((action, pre, eff))

    fluent_preds = {name for _, _, eff in schemas for name, _, _ in eff}
    init_atoms = _atoms(And(*problem.init) if problem.init else None, "problem :init", False)
    init_all = {fact(n, *(a for a, _ in args)) for n, args, _ in init_atoms}
    statics = frozenset(f for f in init_all if f.split(" ", 1)[0] not in fluent_preds)
    init = frozenset(init_all - statics)

    goal_atoms = _atoms(problem.goal, "problem :goal", allow_negation=False)
    goal_all = {fact(n, *(a for a, _ in args)) for n, args, _ in goal_atoms}
    static_goal = {g for g in goal_all if g.split(" ", 1)[0] not in fluent_preds}
    goal = frozenset(goal_all - static_goal)
    if not static_goal <= statics:
        missing = ", ".join(sorted(static_goal - statics))
        raise PlanningError(f"goal needs static facts that are false initially: {missing}")

    actions: list[GroundAction] = []
    for action, pre, eff in schemas:
        params = [(str(v.name), _with_supertypes(v.type_tags, parents)) for v in action.parameters]
        domains = [sorted(o for o, types in objects.items() if ptypes <= types) for _, ptypes in params]
        for binding in itertools.product(*domains):
            env = {pname: obj for (pname, _), obj in zip(params, binding, strict=True)}
            ground_pre = {fact(n, *_bind(args, env)) for n, args, _ in pre}
            static_pre = {f for f in ground_pre if f.split(" ", 1)[0] not in fluent_preds}
            if not static_pre <= statics:
                continue
            add = frozenset(fact(n, *_bind(args, env)) for n, args, neg in eff if not neg)
            delete = frozenset(fact(n, *_bind(args, env)) for n, args, neg in eff if neg)
            name = " ".join((str(action.name), *binding))
            actions.append(GroundAction(name, frozenset(ground_pre - static_pre), add, delete))
    actions.sort()

    facts = set(init) | goal
    for a in actions:
        facts |= a.pre | a.add | a.delete
    return Task(
        name=str(problem.name),
        facts=tuple(sorted(facts)),
        init=init,
        goal=goal,
        actions=tuple(actions),
        statics=statics,
        objects=dict(sorted(objects.items())),
    )


# --- helpers -------------------------------------------------------------------------------------


def _check_requirements(requirements: Iterable[Requirements], where: str) -> None:
    extra = sorted(str(r) for r in requirements if r not in SUPPORTED_REQUIREMENTS)
    if extra:
        raise UnsupportedPDDLError(f"{where} declares {' '.join(extra)}: only :strips and :typing are supported")


def _with_supertypes(tags: Iterable[object], parents: Mapping[str, str | None]) -> frozenset[str]:
    out: set[str] = set()
    for tag in tags:
        t: str | None = str(tag)
        while t is not None and t not in out:
            out.add(t)
            t = parents.get(t)
    return frozenset(out)


def _bind(args: tuple[tuple[str, bool], ...], env: Mapping[str, str]) -> Iterator[str]:
    for name, is_var in args:
        yield env[name] if is_var else name


def _atoms(
    formula: Formula | None, where: str, allow_negation: bool
) -> list[tuple[str, tuple[tuple[str, bool], ...], bool]]:
    """Flatten a conjunction of (possibly negated) atoms into (predicate, args, negated) triples.

    Each argument is ``(name, is_variable)``. Any other connective is rejected by its PDDL name.
    """
    if formula is None:
        return []
    if isinstance(formula, And):
        out = []
        for part in formula.operands:
            out.extend(_atoms(part, where, allow_negation))
        return out
    if isinstance(formula, Predicate):
        args = tuple((str(t.name), not _is_constant(t)) for t in formula.terms)
        return [(str(formula.name), args, False)]
    if isinstance(formula, Not) and allow_negation and isinstance(formula.argument, Predicate):
        ((name, args, _),) = _atoms(formula.argument, where, allow_negation)
        return [(name, args, True)]
    construct = _construct_name(formula, allow_negation)
    raise UnsupportedPDDLError(f"{where}: {construct} is not STRIPS (only conjunctions of atoms)")


def _is_constant(term: object) -> bool:
    return isinstance(term, Constant)


#: PDDL spellings of the pddl package's formula classes, for error messages.
_CONSTRUCT_NAMES = {
    "Or": "disjunction (or ...)",
    "Not": "negative literal (not ...)",
    "Imply": "implication (imply ...)",
    "ExistsCondition": "existential quantifier (exists ...)",
    "ForallCondition": "universal quantifier (forall ...)",
    "Forall": "universal effect (forall ...)",
    "When": "conditional effect (when ...)",
    "EqualTo": "equality (= ...)",
    "OneOf": "non-deterministic effect (oneof ...)",
    "Increase": "numeric effect (increase ...)",
    "Decrease": "numeric effect (decrease ...)",
    "Assign": "numeric effect (assign ...)",
}


def _construct_name(formula: object, allow_negation: bool) -> str:
    cls = type(formula).__name__
    if cls == "Not" and allow_negation:
        return "negation of a non-atom (not ...)"
    if cls == "Not":
        return "negative precondition (not ...)"
    return _CONSTRUCT_NAMES.get(cls, f"{cls} {formula}")
