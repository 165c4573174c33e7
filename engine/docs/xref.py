"""Cross references of a program: who calls, reads, writes and uses each declaration.

Who calls each option and basic behavior, who reads and writes each symbol, which options use
each constant and enumeration.

A *place* is ``(option, state)``; ``state`` is None for the option's common decision tree and
common action, which run in every state and are documented once. Everything comes from the IR:
the option's own common tree and common action, and each state's decision and actions with
the inlined common part peeled off (the IR inlines it, :mod:`xabsl_studio.engine.ir.model`).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field

from xabsl_studio.engine import ir

#: ``(option name, state name or None for the common part)``
Place = tuple[str, str | None]


def own_decision(option: ir.Option, state: ir.State) -> ir.DecisionTree:
    """The state's own decision tree: ``state.decision`` without the inlined common branches."""
    tree = state.decision
    for _ in option.common_decision:
        if not isinstance(tree, ir.If):
            break
        tree = tree.otherwise
    return tree


def own_actions(option: ir.Option, state: ir.State) -> tuple[ir.Action, ...]:
    """The state's own action items (the IR puts the common action in front of them)."""
    return state.actions[len(option.common_action) :]


def tree_expressions(tree: ir.DecisionTree) -> Iterator[ir.Expression]:
    """The conditions of a decision tree, pre-order."""
    if isinstance(tree, ir.If):
        yield tree.condition
        yield from tree_expressions(tree.then)
        yield from tree_expressions(tree.otherwise)


def action_expressions(actions: Iterable[ir.Action]) -> Iterator[ir.Expression]:
    """The argument and assigned values of action items."""
    for action in actions:
        if isinstance(action, ir.Assignment):
            yield action.value
        else:
            yield from (a.value for a in action.args)


@dataclass
class CrossReferences:
    """Every use of every declaration, each list of places in IC option order, without repeats."""

    option_callers: dict[str, list[Place]] = field(default_factory=dict)
    behavior_callers: dict[str, list[Place]] = field(default_factory=dict)
    readers: dict[str, list[Place]] = field(default_factory=dict)
    writers: dict[str, list[Place]] = field(default_factory=dict)
    constant_users: dict[str, list[Place]] = field(default_factory=dict)
    enum_users: dict[str, list[Place]] = field(default_factory=dict)
    #: what each place reads (symbol names), for the state sections of option pages
    reads: dict[Place, list[str]] = field(default_factory=dict)


def _add(table: dict[str, list[Place]], name: str, place: Place) -> None:
    places = table.setdefault(name, [])
    if place not in places:
        places.append(place)


def cross_references(program: ir.Program) -> CrossReferences:
    """Walk every option once and index every use."""
    refs = CrossReferences()
    add = _add
    for option in program.options.values():
        parts: list[tuple[str | None, list[ir.Expression], tuple[ir.Action, ...]]] = [
            (
                None,
                [e for branch in option.common_decision for e in (branch.condition, *tree_expressions(branch.tree))],
                option.common_action,
            )
        ]
        for state in option.states:
            parts.append((state.name, list(tree_expressions(own_decision(option, state))), own_actions(option, state)))
        for state_name, conditions, actions in parts:
            place: Place = (option.name, state_name)
            reads: list[str] = []
            for expression in (*conditions, *action_expressions(actions)):
                for node in ir.walk(expression):
                    if isinstance(node, ir.InputRef | ir.OutputRef):
                        add(refs.readers, node.symbol, place)
                        if node.symbol not in reads:
                            reads.append(node.symbol)
                    elif isinstance(node, ir.Constant):
                        add(refs.constant_users, node.name, place)
                    elif isinstance(node, ir.EnumLiteral):
                        add(refs.enum_users, node.enum, place)
            if reads:
                refs.reads[place] = reads
            for action in actions:
                if isinstance(action, ir.OptionCall):
                    add(refs.option_callers, action.option, place)
                elif isinstance(action, ir.BehaviorCall):
                    add(refs.behavior_callers, action.behavior, place)
                else:
                    add(refs.writers, action.symbol, place)
    return refs
