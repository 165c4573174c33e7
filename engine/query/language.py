"""The query language: a breakpoint condition plus the activation predicates, checked per program.

A query is one boolean XABSL expression, parsed and checked by the breakpoint conditions'
checker (:func:`xabsl_studio.engine.lang.condition.check_condition`): symbols, constants,
enumerations, comparisons, arithmetic, ``&&``, ``||``, ``!``, ``? :`` and input functions with
arguments. What a recorded tick also knows, its option activation path, is offered to that
checker as extra read-only input symbols, one family per option and basic behavior of the
program (``O`` an option, ``B`` a basic behavior)::

    O.active        boolean   O ran in the tick
    O.state         enum      O's active state (an enumeration of O's states, written short:
                              ``striker.state == kick``); while O did not run it equals no state
    O.decided_in    enum      the state whose decision ran (the leaf below belongs to it)
    O.leaf          decimal   the id of the decision leaf that fired (-1: no decision ran)
    O.option_time   decimal   ms since O was activated
    O.state_time    decimal   ms since O's active state was entered
    O.<parameter>   as declared: the value O was called with (``go_to_position.x``)
    B.active        boolean   basic behavior B ran in the tick
    B.<parameter>   as declared: the value B was called with

The values of ``O.leaf``, the times and the parameters exist only while the option (behavior)
runs: in other ticks they are unknown (so ``O.active && O.option_time > 2000`` is false there,
not unknown). A name the program itself declares (a symbol, a constant, an enumeration) keeps its
meaning: the predicate of that name is not offered.

:func:`compile_query` checks the text against one program generation (from its recorded JSON
description, which holds every declaration, used or not) and says which symbols, options,
behaviors and input functions the evaluation needs.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass, field
from typing import Any, Literal

from xabsl_studio.engine import ir
from xabsl_studio.engine.lang.condition import CheckedCondition, check_condition
from xabsl_studio.engine.lang.diagnostics import Diagnostic
from xabsl_studio.engine.types import Kind

__all__ = [
    "STATE_ENUM_SUFFIX",
    "CompiledQuery",
    "Predicate",
    "PredicateKind",
    "compile_query",
    "state_element",
]

PredicateKind = Literal[
    "active", "state", "decided_in", "leaf", "option_time", "state_time", "param", "behavior_active", "behavior_param"
]
#: The enumeration of an option's states is named ``<option>.state``; its elements ``<option>.state.<s>``.
STATE_ENUM_SUFFIX = ".state"
_OPTION_FIELDS: tuple[tuple[str, PredicateKind, Kind], ...] = (
    ("active", "active", Kind.BOOLEAN),
    ("state", "state", Kind.ENUM),
    ("decided_in", "decided_in", Kind.ENUM),
    ("leaf", "leaf", Kind.DECIMAL),
    ("option_time", "option_time", Kind.DECIMAL),
    ("state_time", "state_time", Kind.DECIMAL),
)


@dataclass(frozen=True, slots=True)
class Predicate:
    """A value read from a tick's activation path, offered as an input symbol called ``name``.

    ``target`` is the option or basic behavior; ``position`` the parameter's position in its
    declaration (``param`` / ``behavior_param``); ``enum`` the enumeration of an enum value.
    """

    name: str
    kind: PredicateKind
    target: str
    value_kind: Kind
    enum: str | None = None
    position: int = -1


def state_element(option: str, state: str) -> str:
    """The element of ``option``'s state enumeration that names ``state``."""
    return f"{option}{STATE_ENUM_SUFFIX}.{state}"


@dataclass(frozen=True)
class CompiledQuery:
    """A query checked against one program generation.

    ``expression`` is None when it has errors (``diagnostics``). ``symbols`` are the plain input,
    output and internal symbols it reads, ``predicates`` the activation values, ``functions``
    the input functions it calls (evaluated from the tick's recorded reads).
    """

    text: str
    expression: ir.Expression | None
    diagnostics: list[Diagnostic]
    symbols: frozenset[str] = frozenset()
    predicates: dict[str, Predicate] = field(default_factory=dict)
    functions: frozenset[str] = frozenset()

    @property
    def ok(self) -> bool:
        """True when it can be evaluated."""
        return self.expression is not None

    def errors(self) -> list[Diagnostic]:
        """The error diagnostics (with spans in the condition's text)."""
        return [d for d in self.diagnostics if d.is_error]


def _parameter(data: dict[str, Any], owner: str) -> ir.Parameter:
    return ir.Parameter(
        data["name"], Kind(data["type"]), data.get("enum"), data.get("range"), data.get("unit"), owner=owner
    )


def symbol_program(description: dict[str, Any]) -> tuple[ir.Program, dict[str, Predicate]]:
    """The declarations of a recorded program description, with the activation predicates added.

    What :func:`check_condition` resolves names in: every enumeration, input and output symbol,
    constant and basic behavior the description lists, plus one input symbol per predicate (see
    the module docstring) and one enumeration per option's states.
    """
    enums = {
        e["name"]: ir.Enumeration(e["name"], tuple(e["elements"]), bool(e.get("internal")))
        for e in description["enums"]
    }
    inputs = {
        s["name"]: ir.InputSymbol(
            s["name"], Kind(s["type"]), s.get("enum"), tuple(_parameter(p, s["name"]) for p in s.get("params", ()))
        )
        for s in description["inputs"]
    }
    outputs = {
        s["name"]: ir.OutputSymbol(s["name"], Kind(s["type"]), s.get("enum"), bool(s.get("internal")))
        for s in description["outputs"]
    }
    constants = {
        c["name"]: ir.ConstantDecl(c["name"], float(c["value"]), str(c["text"])) for c in description["constants"]
    }
    behaviors = {
        b["name"]: ir.BasicBehavior(b["name"], tuple(_parameter(p, b["name"]) for p in b["params"]))
        for b in description["behaviors"]
    }
    taken = set(enums) | set(inputs) | set(outputs) | set(constants)
    predicates: dict[str, Predicate] = {}

    def offer(predicate: Predicate) -> None:
        if predicate.name not in taken and predicate.name not in predicates:
            predicates[predicate.name] = predicate

    for option in description["options"]:
        name = option["name"]
        state_enum = name + STATE_ENUM_SUFFIX
        has_states = state_enum not in taken
        if has_states:
            enums[state_enum] = ir.Enumeration(
                state_enum, tuple(state_element(name, s["name"]) for s in option["states"])
            )
        for suffix, kind, value_kind in _OPTION_FIELDS:
            if value_kind is Kind.ENUM and not has_states:
                continue
            offer(
                Predicate(f"{name}.{suffix}", kind, name, value_kind, state_enum if value_kind is Kind.ENUM else None)
            )
        for position, param in enumerate(option["params"]):
            offer(Predicate(param["name"], "param", name, Kind(param["type"]), param.get("enum"), position))
    for behavior in description["behaviors"]:
        name = behavior["name"]
        offer(Predicate(f"{name}.active", "behavior_active", name, Kind.BOOLEAN))
        for position, param in enumerate(behavior["params"]):
            offer(Predicate(param["name"], "behavior_param", name, Kind(param["type"]), param.get("enum"), position))
    for predicate in predicates.values():
        inputs[predicate.name] = ir.InputSymbol(predicate.name, predicate.value_kind, predicate.enum)
    program = ir.Program(
        title=str(description.get("title", "")),
        options={},
        agents=(),
        enums=enums,
        inputs=inputs,
        outputs=outputs,
        constants=constants,
        behaviors=behaviors,
    )
    return program, predicates


_NAMED = re.compile(r"no matching symbol found for '([^']+)'")
_STATE_READ = re.compile(r"([A-Za-z_][A-Za-z0-9_.]*)\.(?:state|decided_in)\s*[!=]=\s*([A-Za-z_][A-Za-z0-9_.]*)")


def _name_states(description: dict[str, Any], text: str, diagnostics: list[Diagnostic]) -> list[Diagnostic]:
    """Diagnostics where a name compared with ``O.state`` that is no state of ``O`` says O's states.

    The checker's own message would hint at enum elements of other enumerations; a query's
    reader wants the states.
    """
    states = {o["name"]: [s["name"] for s in o["states"]] for o in description["options"]}
    compared = {m.group(2): m.group(1) for m in _STATE_READ.finditer(text) if m.group(1) in states}
    out: list[Diagnostic] = []
    for diagnostic in diagnostics:
        found = _NAMED.match(diagnostic.message)
        option = compared.get(found.group(1)) if found else None
        if found and option is not None:
            message = f"option {option} has no state '{found.group(1)}' (states: {', '.join(states[option])})"
            diagnostic = dataclasses.replace(diagnostic, message=message)
        out.append(diagnostic)
    return out


def compile_query(description: dict[str, Any], text: str) -> CompiledQuery:
    """Check ``text`` against the program a recorded description describes (see the module docstring)."""
    program, predicates = symbol_program(description)
    checked: CheckedCondition = check_condition(program, text)
    if checked.expression is None:
        return CompiledQuery(text, None, _name_states(description, text, checked.diagnostics))
    symbols: set[str] = set()
    used: dict[str, Predicate] = {}
    functions: set[str] = set()
    for node in ir.walk(checked.expression):
        if isinstance(node, ir.InputRef):
            if node.symbol in predicates:
                used[node.symbol] = predicates[node.symbol]
            elif node.args or program.inputs[node.symbol].params:
                functions.add(node.symbol)
            else:
                symbols.add(node.symbol)
        elif isinstance(node, ir.OutputRef):
            symbols.add(node.symbol)
    return CompiledQuery(text, checked.expression, checked.diagnostics, frozenset(symbols), used, frozenset(functions))
