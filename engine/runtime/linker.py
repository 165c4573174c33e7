"""Link a program against the host's bindings: resolve every name, decide every storage slot.

This is the Python counterpart of the name resolution in ``Engine::createOptionGraph`` (§2.10):
every external input/output symbol, enum element, basic behavior and parameter the program
names must be registered, with the right kind. All problems are collected and raised together
as one :class:`~xabsl_studio.engine.errors.LinkError`. Internal symbols and enumerations (§2.1) get
engine storage; internal enum elements get the values 0..n-1 in declaration order.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

from xabsl_studio.engine.codegen.layout import (
    BehaviorSlot,
    InputSlot,
    Layout,
    OptionSlot,
    OutputSlot,
    assignment_sites,
    default_value,
)
from xabsl_studio.engine.errors import LinkError
from xabsl_studio.engine.ir.model import (
    Action,
    BehaviorCall,
    DecisionTree,
    EnumLiteral,
    Expression,
    If,
    InputRef,
    OptionCall,
    OutputRef,
    Parameter,
    Program,
    walk,
)
from xabsl_studio.engine.runtime.bindings import BasicBehavior, Bindings, InputBinding, OutputBinding
from xabsl_studio.engine.types import Kind, Value

__all__ = ["Linked", "link", "program_expressions"]


@dataclass
class Linked:
    """A program resolved against bindings: the layout plus the host objects behind each slot."""

    program: Program
    layout: Layout
    inputs: list[InputBinding]
    outputs: list[OutputBinding | None]  # None: internal symbol (engine storage)
    output_names: list[str]
    output_initial: list[Value]
    behaviors: list[BasicBehavior]
    behavior_names: list[str]
    option_names: list[str]
    #: qualified enum element -> value, for every enumeration the program uses
    enum_values: dict[str, int]
    #: enum name -> value -> first element with that value (for display)
    enum_names: dict[str, dict[int, str]] = field(default_factory=dict)
    n_option_params: int = 0
    n_behavior_params: int = 0


def _expressions_of_action(action: Action) -> list[Any]:
    if isinstance(action, OptionCall | BehaviorCall):
        return [a.value for a in action.args]
    return [action.value]


def _conditions(tree: DecisionTree) -> Iterator[Expression]:
    if isinstance(tree, If):
        yield tree.condition
        yield from _conditions(tree.then)
        yield from _conditions(tree.otherwise)


def program_expressions(program: Program) -> Iterator[Expression]:
    """Every expression node of every state (decisions and actions), pre-order."""
    for option in program.options.values():
        for state in option.states:
            for condition in _conditions(state.decision):
                yield from walk(condition)
            for action in state.actions:
                for expression in _expressions_of_action(action):
                    yield from walk(expression)


def link(
    program: Program,
    bindings: Bindings,
    *,
    double_execution_is_error: bool = True,
    reuse: dict[str, BasicBehavior] | None = None,
) -> Linked:
    """Resolve ``program`` against ``bindings``.

    Args:
        program: the behavior to load.
        bindings: what the host registered.
        double_execution_is_error: policy B2 (True) or B1 (False), see §2.10.
        reuse: basic behavior instances of a running engine to keep across a hot reload.

    Raises:
        LinkError: listing every missing or mismatching name.
    """
    problems: list[str] = []

    # -- enumerations -------------------------------------------------------------------------
    enum_values: dict[str, int] = {}
    missing_elements: set[str] = set()
    for enum in program.enums.values():
        if enum.internal:
            if enum.name in bindings.enums:
                problems.append(f"enumeration {enum.name} is internal and must not be registered by the host")
            enum_values.update((element, i) for i, element in enumerate(enum.elements))
        else:
            registered = bindings.enums.get(enum.name, {})
            for element in enum.elements:
                if element in registered:
                    enum_values[element] = registered[element]
                else:
                    missing_elements.add(element)
                    problems.append(f"enum element {element} of enumeration {enum.name} is not registered")
    # Elements the program mentions but no declaration lists (e.g. IC-only enums).
    for node in program_expressions(program):
        if isinstance(node, EnumLiteral) and node.element not in enum_values and node.element not in missing_elements:
            registered = bindings.enums.get(node.enum, {})
            if node.element in registered:
                enum_values[node.element] = registered[node.element]
            else:
                missing_elements.add(node.element)
                problems.append(f"enum element {node.element} is not registered")
    enum_names: dict[str, dict[int, str]] = {}
    for enum in program.enums.values():
        names: dict[int, str] = {}
        for element in enum.elements:
            if element in enum_values:
                names.setdefault(enum_values[element], element)
        if not enum.internal:
            for element, value in bindings.enums.get(enum.name, {}).items():
                names.setdefault(value, element)
        enum_names[enum.name] = names

    # -- input symbols ------------------------------------------------------------------------
    inputs: list[InputBinding] = []
    input_slots: dict[str, InputSlot] = {}
    for symbol in program.inputs.values():
        binding = bindings.inputs.get(symbol.name)
        if binding is None:
            problems.append(f"input symbol {symbol.name} ({symbol.kind.value}) is not registered")
            continue
        if binding.kind is not symbol.kind:
            problems.append(
                f"input symbol {symbol.name} is {symbol.kind.value} in the behavior "
                f"but registered as {binding.kind.value}"
            )
        _check_parameters(f"input symbol {symbol.name}", symbol.params, binding.params, problems)
        input_slots[symbol.name] = InputSlot(
            len(inputs), tuple((p.name, p.kind) for p in binding.params), binding.attribute, binding.key
        )
        inputs.append(binding)

    # -- output and internal symbols -----------------------------------------------------------
    outputs: list[OutputBinding | None] = []
    output_names: list[str] = []
    output_initial: list[Value] = []
    output_slots: dict[str, OutputSlot] = {}
    for output in program.outputs.values():
        out_binding: OutputBinding | None
        if output.internal:
            if output.name in bindings.outputs:
                problems.append(f"internal symbol {output.name} must not be registered by the host")
            out_binding = None
            initial = _first_value(output.kind, output.enum, program, enum_values)
        else:
            out_binding = bindings.outputs.get(output.name)
            if out_binding is None:
                problems.append(f"output symbol {output.name} ({output.kind.value}) is not registered")
                continue
            if out_binding.kind is not output.kind:
                problems.append(
                    f"output symbol {output.name} is {output.kind.value} in the behavior "
                    f"but registered as {out_binding.kind.value}"
                )
            initial = (
                out_binding.initial
                if out_binding.initial is not None
                else _first_value(output.kind, output.enum or out_binding.enum, program, enum_values, bindings)
            )
        stored = out_binding is None or out_binding.setter is None
        output_slots[output.name] = OutputSlot(len(outputs), stored)
        outputs.append(out_binding)
        output_names.append(output.name)
        output_initial.append(initial)

    # -- basic behaviors ------------------------------------------------------------------------
    behaviors: list[BasicBehavior] = []
    behavior_names: list[str] = []
    behavior_slots: dict[str, BehaviorSlot] = {}
    offset = 0
    for declared in program.behaviors.values():
        registered_bb = bindings.behaviors.get(declared.name)
        if registered_bb is None:
            problems.append(f"basic behavior {declared.name} is not registered")
            continue
        if isinstance(registered_bb, BasicBehavior):
            instance = registered_bb
        elif reuse is not None and type(reuse.get(declared.name)) is registered_bb:
            instance = reuse[declared.name]
        else:
            instance = registered_bb()
        params = type(instance).declared_parameters()
        _check_parameters(f"basic behavior {declared.name}", declared.params, params, problems)
        hook = type(instance).parameters_changed is not BasicBehavior.parameters_changed
        behavior_slots[declared.name] = BehaviorSlot(
            len(behaviors), offset, tuple((p.name, p.kind) for p in params), hook
        )
        offset += len(params)
        behaviors.append(instance)
        behavior_names.append(declared.name)

    # -- options --------------------------------------------------------------------------------
    option_slots: dict[str, OptionSlot] = {}
    option_offset = 0
    for index, option in enumerate(program.options.values()):
        option_slots[option.name] = OptionSlot(
            index,
            option_offset,
            tuple((p.name, p.kind) for p in option.params),
            option.state(option.initial_state).index,
            tuple(s.target for s in option.states),
            tuple(s.coop != "n" for s in option.states),
        )
        option_offset += len(option.params)
    # Calls of options/behaviors/inputs that the program itself does not declare (IC mistakes).
    for option in program.options.values():
        for state in option.states:
            for action in state.actions:
                if isinstance(action, OptionCall) and action.option not in option_slots:
                    problems.append(f"option {action.option} called in {option.name}.{state.name} does not exist")
                if isinstance(action, BehaviorCall) and action.behavior not in program.behaviors:
                    problems.append(f"basic behavior {action.behavior} is not declared")
    for node in program_expressions(program):
        if isinstance(node, InputRef) and node.symbol not in program.inputs:
            problems.append(f"input symbol {node.symbol} is not declared")
        if isinstance(node, OutputRef) and node.symbol not in program.outputs:
            problems.append(f"output symbol {node.symbol} is not declared")

    if problems:
        raise LinkError(list(dict.fromkeys(problems)))
    layout = Layout(
        option_slots,
        input_slots,
        output_slots,
        behavior_slots,
        enum_values,
        assignment_sites(program),
        double_execution_is_error,
    )
    return Linked(
        program,
        layout,
        inputs,
        outputs,
        output_names,
        output_initial,
        behaviors,
        behavior_names,
        list(option_slots),
        enum_values,
        enum_names,
        option_offset,
        offset,
    )


def _check_parameters(
    owner: str, declared: Sequence[Parameter], registered: Sequence[Parameter], problems: list[str]
) -> None:
    """Report every declared parameter the host did not register, or registered with another type."""
    by_name = {p.name: p for p in registered}
    for param in declared:
        have = by_name.get(param.name)
        if have is None:
            problems.append(f"parameter {param.name} of {owner} is not registered")
        elif have.kind is not param.kind:
            problems.append(
                f"parameter {param.name} of {owner} is {param.kind.value} but registered as {have.kind.value}"
            )


def _first_value(
    kind: Kind,
    enum: str | None,
    program: Program,
    enum_values: dict[str, int],
    bindings: Bindings | None = None,
) -> Value:
    """0.0, false, or the value of the enumeration's first element (§2.1)."""
    if kind is not Kind.ENUM:
        return default_value(kind)
    if enum is not None and enum in program.enums and program.enums[enum].elements:
        return enum_values.get(program.enums[enum].elements[0], 0)
    if enum is not None and bindings is not None and bindings.enums.get(enum):
        return next(iter(bindings.enums[enum].values()))
    return 0
