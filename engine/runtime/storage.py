"""A program bound to one engine: flat storage lists, generated functions, host objects (§2.1).

:class:`LoadedProgram` is what :meth:`xabsl_studio.engine.runtime.engine.Engine.load` builds: the storage
lists of :data:`xabsl_studio.engine.codegen.layout.STORAGE` (active states, tick stamps, activation times,
decision records, parameters, outputs), the generated option functions bound to them as
globals, the input overrides (the generated code reads an overridden input through a constant)
and the root actions that call options and basic behaviors with constant parameters (§2.5,
§2.9). The Engine owns the lifecycle (load, reload, ticks, faults), :mod:`xabsl_studio.engine.runtime.roots`
what runs at the root; this module owns the storage, and derives everything that copies it
(snapshots, ``reset``, hot reload) from the one table.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import SimpleNamespace
from typing import Any, cast

from xabsl_studio.engine.codegen.layout import NEVER, STORAGE, Per, Start, StorageList, default_value, engine_order
from xabsl_studio.engine.codegen.python import GeneratedProgram
from xabsl_studio.engine.codegen.support import MS_MASK, SUPPORT_GLOBALS
from xabsl_studio.engine.errors import DoubleExecutionError
from xabsl_studio.engine.ir.model import Parameter
from xabsl_studio.engine.runtime.activation import PATH_FIELDS, BehaviorCalls, PathPlan, PathStorage, Root, Snapshot
from xabsl_studio.engine.runtime.coop import CoopStates
from xabsl_studio.engine.runtime.linker import Linked
from xabsl_studio.engine.runtime.values import EnumValues
from xabsl_studio.engine.types import Ms, Value

__all__ = ["LoadedProgram", "RootAction"]

#: One root action: called with ``(now, tick)`` once per tick.
RootAction = Callable[[int, int], None]

#: The storage lists a snapshot copies, in :class:`Snapshot` field order (after ``now``, ``tick``,
#: ``roots``; before ``behavior_calls``, which is the B1 call record, not a storage list).
SNAPSHOT_FIELDS = tuple(spec.field for spec in STORAGE if spec.snapshot)
if Snapshot._fields[3:-1] != SNAPSHOT_FIELDS:  # pragma: no cover - a schema edit that forgot Snapshot
    raise AssertionError(f"Snapshot fields {Snapshot._fields[3:-1]} do not follow STORAGE {SNAPSHOT_FIELDS}")


class LoadedProgram:
    """One program bound to one engine: storage lists, generated functions, host objects.

    Args:
        linked: the program resolved against the host's bindings.
        generated: its generated code (shared by engines with equal layouts).
        tick: the engine's tick counter (cooperative states compare tick stamps with it).
        warnings: where a double execution under policy B1 is reported.
    """

    # The storage lists, by their field names in STORAGE (set from the table in __init__).
    states: list[int]
    last_tick: list[int]
    previous_tick: list[int]
    activated: list[Ms]
    state_entered: list[Ms]
    decisions: list[tuple[int, int, int] | None]
    decision_state_time: list[float]
    option_params: list[Value]
    behavior_params: list[Value]
    behavior_last_tick: list[int]
    behavior_previous_tick: list[int]
    behavior_activated: list[Ms]
    assignments: list[Value | None]
    outputs: list[Value]

    def __init__(
        self, linked: Linked, generated: GeneratedProgram, *, tick: Callable[[], int], warnings: list[str]
    ) -> None:
        self.linked = linked
        self.program = linked.program
        self.layout = linked.layout
        self.generated = generated
        self.warnings = warnings
        self.lists: dict[str, list[Any]] = {spec.field: self._start(spec) for spec in STORAGE}
        for field, values in self.lists.items():
            setattr(self, field, values)
        #: per basic behavior: its declared parameters, qualified (``BehaviorNode`` names)
        self.behavior_declared: dict[str, tuple[Parameter, ...]] = {}
        for name, bslot in linked.layout.behaviors.items():
            instance = linked.behaviors[bslot.index]
            declared = type(instance).declared_parameters()
            self.behavior_declared[name] = declared
            instance.bind_parameters(self.behavior_params, bslot.offset, declared)
        self.coop = CoopStates.of(self.program)
        self.coop.tick = tick
        self.coop.executing = self.executing_coop_states
        g: dict[str, Any] = dict(SUPPORT_GLOBALS)
        g.update((spec.name, self.lists[spec.field]) for spec in STORAGE)
        #: what the decisions of the last tick read, when the code records reads (``Engine.record_reads``)
        self.reads: list[object] = []
        g.update(DX=self.double_execution, CC=self.coop.check, CF=self.coop.conflict, RA=self.reads.append)
        #: B1 only (B2 rejects a behavior that could run twice in a tick): per behavior slot, the
        #: tick of its recorded calls and each call's parameter values (``calls_of_tick``)
        self.call_tick: list[int] = []
        self.calls: list[list[tuple[Value, ...]]] = []
        record = not linked.layout.double_execution_is_error
        if record:
            self.call_tick = [NEVER] * len(linked.behaviors)
            self.calls = [[] for _ in linked.behaviors]
        for k, behavior in enumerate(linked.behaviors):
            # Generated basic-behavior calls do the bookkeeping of ``run_behavior`` inline.
            g[f"BB{k}"] = behavior
            g[f"BE{k}"] = self._recording_call(k, behavior.execute) if record else behavior.execute
        for k, binding in enumerate(linked.inputs):
            g[f"I{k}"] = binding.read
            if binding.attribute is not None or binding.key is not None:
                g[f"IA{k}"] = binding.source
            if binding.params:
                storage = [default_value(p.kind) for p in binding.params]
                g[f"FP{k}"] = storage
                g[f"FS{k}"] = storage.__setitem__
        for k, out in enumerate(linked.outputs):
            if out is not None and out.setter is not None:
                g[f"OS{k}"] = out.setter
                g[f"OG{k}"] = out.getter
        self.globals = g
        self.functions: list[Callable[[int, int], None]] = []
        self.bind(generated)
        self.input_reads = {name: g[f"I{slot.index}"] for name, slot in linked.layout.inputs.items()}
        #: input symbols the generated code reads as a constant instead of from the host
        self.overrides: dict[str, Value] = {}
        #: built on the first :meth:`Engine.path` call (hosts that never record pay nothing)
        self.path_plan: PathPlan | None = None
        self.path_storage = cast(PathStorage, tuple(self.lists[field] for field in PATH_FIELDS))
        #: what :meth:`Engine.snapshot` copies: the ``snapshot`` lists of STORAGE, in order
        self.snapshot_lists = tuple(self.lists[field] for field in SNAPSHOT_FIELDS)
        self.enums = self._enum_values()

    def bind(self, generated: GeneratedProgram) -> None:
        """Run ``generated`` on this storage: the same program, with or without recording reads.

        Between ticks only; the root actions must be built again (they hold option functions).
        """
        self.generated = generated
        generated.bind(self.globals)
        self.functions[:] = [self.globals[f"O{i}"] for i in range(len(self.linked.option_names))]
        self.reads.clear()

    def _start(self, spec: StorageList) -> list[Any]:
        """The list ``spec`` as a load leaves it."""
        layout, linked = self.layout, self.linked
        if spec.start is Start.INITIAL_STATE:
            return [layout.options[name].initial for name in linked.option_names]
        if spec.start is Start.INITIAL_VALUE:
            return list(linked.output_initial)
        if spec.start is Start.DEFAULT:
            slots = layout.options.values() if spec.per is Per.OPTION_PARAMETER else layout.behaviors.values()
            size = linked.n_option_params if spec.per is Per.OPTION_PARAMETER else linked.n_behavior_params
            values: list[Value] = [0.0] * size
            for slot in slots:
                for k, (_, kind) in enumerate(slot.params):
                    values[slot.offset + k] = default_value(kind)
            return values
        size = {
            Per.OPTION: len(linked.option_names),
            Per.OPTION_PARAMETER: linked.n_option_params,
            Per.BEHAVIOR: len(linked.behaviors),
            Per.BEHAVIOR_PARAMETER: linked.n_behavior_params,
            Per.SYMBOL: len(linked.outputs),
            Per.ASSIGNMENT: len(layout.sites),
        }[spec.per]
        start: object = {Start.NEVER: NEVER, Start.ZERO_MS: 0, Start.ZERO_TIME: 0.0, Start.NOTHING: None}[spec.start]
        return [start] * size

    def _enum_values(self) -> dict[str | None, EnumValues]:
        """Per enumeration its elements and host values (declared elements first, in order)."""
        values = self.linked.enum_values
        enums: dict[str | None, EnumValues] = {}
        for name, enum in self.program.enums.items():
            elements = {element: values[element] for element in enum.elements if element in values}
            for value, element in self.linked.enum_names.get(name, {}).items():
                elements.setdefault(element, value)
            enums[name] = EnumValues(name, elements)
        # Parameters read from intermediate code may not know their enumeration: any element.
        enums[None] = EnumValues("(any enumeration)", dict(values))
        return enums

    def enum_values(self, enum: str | None) -> EnumValues:
        """The elements and host values of enumeration ``enum`` (any element when it is unknown)."""
        found = self.enums.get(enum)
        return found if found is not None else self.enums[None]

    # -- ticks ------------------------------------------------------------------------------------

    def double_execution(self, option: int, tick: int) -> bool:
        """Option ``option`` runs a second time in tick ``tick`` (§2.2): a fault under B2, else a warning.

        Returns whether the option counts as active in the previous tick (B1).
        """
        message = f"option {self.linked.option_names[option]} is contained in the activation tree more than once"
        if self.layout.double_execution_is_error:
            raise DoubleExecutionError(message)
        self.warnings.append(message)
        return self.previous_tick[option] == tick - 1

    def run_behavior(self, k: int, now: int, tick: int, changed: bool) -> None:
        """One call of basic behavior ``k`` (§2.2 ``ActionBehavior.execute``), parameters already set.

        Used for root actions; generated calls inline the same steps (``xabsl_studio.engine.codegen.python``).
        """
        lt = self.behavior_last_tick[k]
        if lt != tick:
            self.behavior_previous_tick[k] = lt
            self.behavior_last_tick[k] = tick
            was = lt == tick - 1
        else:
            was = self.behavior_previous_tick[k] == tick - 1
        behavior = self.linked.behaviors[k]
        if changed:
            behavior.parameters_changed()
        if not was:
            self.behavior_activated[k] = now
        behavior.time_of_execution = (now - self.behavior_activated[k]) & MS_MASK
        behavior.execute()

    def _recording_call(self, k: int, execute: Callable[[], None]) -> Callable[[], None]:
        """``execute`` of behavior slot ``k``, first noting the parameter values of this call (B1).

        The generated call has set the parameters and the tick stamp (``BLT``) just before; the
        storage keeps only the last call's values, so each call's are copied here.
        """
        bslot = next(b for b in self.layout.behaviors.values() if b.index == k)
        start, end = bslot.offset, bslot.offset + len(bslot.params)
        params, stamps, call_tick, calls = self.behavior_params, self.behavior_last_tick, self.call_tick, self.calls

        def call() -> None:
            tick = stamps[k]
            values = tuple(params[start:end])
            if call_tick[k] != tick:
                call_tick[k] = tick
                calls[k] = [values]
            else:
                calls[k].append(values)
            execute()

        return call

    def calls_of_tick(self, tick: int) -> BehaviorCalls | None:
        """The behaviors that ran more than once in ``tick``, each call's values (B1; None under B2)."""
        if not self.calls:
            return None
        stamps = self.call_tick
        return {k: tuple(c) for k, c in enumerate(self.calls) if stamps[k] == tick and len(c) > 1}

    def executing_coop_states(self) -> list[tuple[int, int]]:
        """The ``(option, state)`` of every cooperative state that ran in the current tick."""
        tick = self.coop.tick()
        return [key for key in self.coop.states if self.last_tick[key[0]] == tick and self.states[key[0]] == key[1]]

    # -- copies of the storage ----------------------------------------------------------------------

    def reset(self) -> None:
        """Every option and basic behavior restarts when next called (the ``reset`` lists of STORAGE)."""
        for spec in STORAGE:
            if spec.reset:
                values = self.lists[spec.field]
                values[:] = [NEVER] * len(values)

    def keep(self, old: LoadedProgram) -> None:
        """Take over from ``old`` (hot reload) what still exists by name (the ``reload`` lists of STORAGE).

        An option keeps its lists only while its active state still exists (else it restarts when
        next called); a parameter while it has the same type; a stored symbol while it is stored
        with the same type. Cooperative-state settings are kept.
        """
        program, layout = self.program, self.layout
        kept_options: list[tuple[int, int]] = []
        kept_params: list[tuple[int, int]] = []
        for name, slot in layout.options.items():
            old_slot = old.layout.options.get(name)
            if old_slot is None:
                continue
            state = old.program.options[name].states[old.states[old_slot.index]].name
            if state not in {s.name for s in program.options[name].states}:
                continue  # its active state is gone: the option restarts when next called
            kept_options.append((old_slot.index, slot.index))
            self.states[slot.index] = program.options[name].state(state).index
            old_params = {p: (k, kind) for k, (p, kind) in enumerate(old_slot.params)}
            for k, (p, kind) in enumerate(slot.params):
                if p in old_params and old_params[p][1] is kind:
                    kept_params.append((old_slot.offset + old_params[p][0], slot.offset + k))
        kept_behaviors = [
            (old.layout.behaviors[name].index, slot.index)
            for name, slot in layout.behaviors.items()
            if name in old.layout.behaviors
        ]
        kept_symbols = []
        for name, out in layout.outputs.items():
            old_out = old.layout.outputs.get(name)
            if (
                old_out is not None
                and out.stored
                and old_out.stored
                and program.outputs[name].kind is old.program.outputs[name].kind
            ):
                kept_symbols.append((old_out.index, out.index))
        pairs = {
            Per.OPTION: kept_options,
            Per.OPTION_PARAMETER: kept_params,
            Per.BEHAVIOR: kept_behaviors,
            Per.SYMBOL: kept_symbols,
        }
        for spec in STORAGE:
            if not spec.reload or spec.start is Start.INITIAL_STATE:  # states: mapped by name above
                continue
            new_values, old_values = self.lists[spec.field], old.lists[spec.field]
            for o, n in pairs[spec.per]:
                new_values[n] = old_values[o]
        self.coop.agent = old.coop.agent
        self.coop.agent_priority = old.coop.agent_priority
        self.coop.synchronization_ticks = old.coop.synchronization_ticks

    # -- input overrides ------------------------------------------------------------------------------

    def override_input(self, symbol: str, value: Value | None) -> None:
        """Make the generated code read input ``symbol`` as ``value`` (None: from the host again)."""
        slot = self.layout.inputs[symbol]
        key = f"I{slot.index}"
        binding = self.linked.inputs[slot.index]
        if value is None:
            self.overrides.pop(symbol, None)
            self.globals[key] = binding.read
            if slot.attribute is not None or slot.key is not None:
                self.globals[f"IA{slot.index}"] = binding.source
        else:
            self.overrides[symbol] = value
            self.globals[key] = lambda *_args, _value=value: _value
            if slot.attribute is not None:
                # Generated code reads ``IA{k}.<attribute>``: give it an object that has the value.
                self.globals[f"IA{slot.index}"] = SimpleNamespace(**{slot.attribute: value})
            elif slot.key is not None:
                self.globals[f"IA{slot.index}"] = {slot.key: value}
        self.input_reads[symbol] = self.globals[key]

    # -- root actions ---------------------------------------------------------------------------------

    def root_action(self, root: Root, params: Mapping[str, Value]) -> RootAction:
        """A root action calling ``root`` with constant ``params`` (others get defaults, §2.5).

        A root of kind ``"output"`` assigns ``params["value"]`` to that output symbol on every
        tick (``addRootActionDecimalOutputSymbol`` and siblings, §2.9).
        """
        if root.kind == "output":
            oslot = self.layout.outputs[root.name]
            value = params["value"]
            if oslot.stored:
                outputs, position = self.outputs, oslot.index

                def assign_stored(now: int, tick: int) -> None:
                    outputs[position] = value

                return assign_stored
            binding = self.linked.outputs[oslot.index]
            assert binding is not None and binding.setter is not None
            setter = binding.setter
            return lambda now, tick: setter(value)
        if root.kind == "option":
            slot = self.layout.options[root.name]
            values = [
                (slot.offset + p, params.get(slot.params[p][0], default_value(slot.params[p][1])))
                for p in engine_order(slot.params)
            ]
            function = self.functions[slot.index]
            if not values:
                return function  # nothing to set: the generated option is the root action
            store = self.option_params

            def run_option(now: int, tick: int) -> None:
                for position, value in values:
                    store[position] = value
                function(now, tick)

            return run_option
        bslot = self.layout.behaviors[root.name]
        bvalues = [
            (bslot.offset + p, params.get(bslot.params[p][0], default_value(bslot.params[p][1])))
            for p in engine_order(bslot.params)
        ]
        bstore = self.behavior_params
        index = bslot.index
        run = self.run_behavior

        def run_behavior(now: int, tick: int) -> None:
            changed = False
            for position, value in bvalues:
                if bstore[position] != value:
                    bstore[position] = value
                    changed = True
            run(index, now, tick, changed)

        return run_behavior
