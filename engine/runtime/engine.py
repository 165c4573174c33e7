"""The Engine: load a program against host bindings and execute it tick by tick (§2).

One :class:`Engine` runs one agent. ``load`` links the program (§2.10), checks the option
graph of every agent root, generates Python code for it once (:mod:`xabsl_studio.engine.codegen.python`)
and binds that code to this engine's storage. ``execute(now_ms)`` runs one tick exactly as
§2.2 says: one clock value for the whole tick, the root actions in order, decision before
actions in every option, outputs written through at once.

Persistent per-option state lives in flat lists indexed by option index (active state, tick
stamps of the last two executions, activation times, the tick's decision record; the table
:data:`xabsl_studio.engine.codegen.layout.STORAGE` names them all): a tick stamp replaces the original's
per-tick ``wasActive``/``isActive`` flag swap, so nothing is reset at the end of a tick.

Faults (§2.9, architecture "Engine"): a host callable or basic behavior that raises, a ``%`` by
zero or (policy B2) a double execution marks the engine as errored with a :class:`Fault`
naming the option, state and XABSL span; ``execute`` then does nothing until ``reset()``.

Hot reload: ``reload(program)`` swaps programs between ticks, keeping the active state and
times of options and states that still exist by name; a program that fails to link or check
leaves the running one untouched and raises.

What runs at the root (the selected agent, forced roots, input overrides) belongs to the
engine's :class:`~xabsl_studio.engine.runtime.roots.RootActions` (``engine.root_actions``); the storage
lists to its :class:`~xabsl_studio.engine.runtime.storage.LoadedProgram` (``engine.loaded``).
"""

from __future__ import annotations

import traceback
from collections.abc import Callable, Mapping, Sequence
from operator import attrgetter, itemgetter
from types import MappingProxyType
from typing import Any

from xabsl_studio.engine.codegen.python import generate
from xabsl_studio.engine.codegen.support import MS_MASK
from xabsl_studio.engine.errors import DebugError, DoubleExecutionError
from xabsl_studio.engine.ir.model import Agent, Program
from xabsl_studio.engine.runtime.activation import Node, PathPlan, Snapshot, build_tree, compact_path, node_to_dict
from xabsl_studio.engine.runtime.bindings import Bindings
from xabsl_studio.engine.runtime.checks import Policy, check_root
from xabsl_studio.engine.runtime.coop import CoopStates
from xabsl_studio.engine.runtime.fault import Fault
from xabsl_studio.engine.runtime.linker import link
from xabsl_studio.engine.runtime.roots import RootActions
from xabsl_studio.engine.runtime.storage import LoadedProgram
from xabsl_studio.engine.types import Ms, Value

__all__ = ["Engine"]

_new_tuple = tuple.__new__


class Engine:
    """Runs one agent's behavior: load, execute ticks, inspect, force, reload.

    Example::

        engine = Engine(bindings)           # bindings: xabsl_studio.engine.runtime.bindings.Bindings
        engine.load(program)                # LinkError lists everything missing
        engine.execute(now_ms)              # one tick; never raises
        engine.activation()                 # the tick's activation tree
        engine.root_actions.force_option("walk", {"speed": 1.0})   # debugging
    """

    def __init__(
        self, bindings: Bindings, program: Program | None = None, *, policy: Policy = Policy.B2, agent_name: str = ""
    ) -> None:
        self.bindings = bindings
        self.policy = policy
        self.agent_name = agent_name
        self.warnings: list[str] = []
        self._loaded: LoadedProgram | None = None
        self._tick = 0
        self._now: Ms = 0
        self._fault: Fault | None = None
        #: the selected agent, forced roots and input overrides (what a tick runs at its root)
        self.root_actions = RootActions(policy)
        #: the loaded program has cooperative states (only then a tick clears their bookkeeping)
        self._coop_states = False
        #: the loaded program's list of reads while decisions record them (``record_reads``), else None
        self._reads: list[object] | None = None
        self._record_reads = False
        if program is not None:
            self.load(program)

    # -- loading ----------------------------------------------------------------------------------

    def _prepare(self, program: Program) -> LoadedProgram:
        reuse = None
        if self._loaded is not None:
            reuse = dict(zip(self._loaded.linked.behavior_names, self._loaded.linked.behaviors, strict=True))
        linked = link(program, self.bindings, double_execution_is_error=self.policy is Policy.B2, reuse=reuse)
        for agent in program.agents:
            check_root(program, agent.root, self.policy)
        generated = generate(program, linked.layout, self._record_reads)  # CodegenError is a LoadError
        return LoadedProgram(linked, generated, tick=lambda: self._tick, warnings=self.warnings)

    def load(self, program: Program) -> None:
        """Load ``program`` from scratch: every option starts fresh, the first agent is selected.

        Raises:
            LinkError: the program names unregistered symbols, enum elements or behaviors.
            LoadError: the option graph of an agent has a loop (or a B2 double execution).
        """
        loaded = self._prepare(program)
        loaded.coop.agent = self.agent_name
        self._loaded = loaded
        self._fault = None
        self._coop_states = bool(loaded.coop.states)
        self._reads = loaded.reads if self._record_reads else None
        self.root_actions.load(loaded)

    def reload(self, program: Program) -> None:
        """Swap in a new version of the behavior between ticks (hot reload).

        Options and states that still exist (by name) keep their active state, times and
        parameters; everything else starts fresh; bindings are re-linked; input overrides, the
        selected agent and forced roots are kept when their names still exist.

        Raises:
            LinkError, LoadError: the new program cannot run; the running one stays in place.
        """
        old = self._require()
        new = self._prepare(program)
        new.keep(old)
        self._loaded = new
        self._coop_states = bool(new.coop.states)
        self._reads = new.reads if self._record_reads else None
        self.root_actions.reload(new)

    def _require(self) -> LoadedProgram:
        if self._loaded is None:
            raise DebugError("no program is loaded")
        return self._loaded

    @property
    def loaded(self) -> LoadedProgram:
        """The program bound to this engine's storage (raises DebugError before a load)."""
        return self._require()

    # -- ticks ----------------------------------------------------------------------------------

    def execute(self, now: Ms) -> None:
        """Run one tick at clock ``now`` (ms, taken modulo 2**32). Never raises (see ``fault``)."""
        if self._fault is not None or self._loaded is None:
            return
        now = int(now) & MS_MASK
        self._tick += 1
        tick = self._tick
        self._now = now
        if self._coop_states:
            self._loaded.coop.entering_now.clear()
        reads = self._reads
        if reads is not None:
            reads.clear()
        # One handler for the whole tick: a fault is located from its traceback (``_locate``),
        # not from which root was running.
        try:
            for action in self.root_actions.actions:
                action(now, tick)
        except Exception as error:
            self._fault = self._locate(error)

    def _locate(self, error: BaseException) -> Fault:
        loaded = self._require()
        origin = None
        for frame, line in traceback.walk_tb(error.__traceback__):
            filename = frame.f_code.co_filename
            if filename.startswith("<xabsl:"):
                found = loaded.generated.origin(filename, line)
                if found is not None:
                    origin = found
        text = f"{type(error).__name__}: {error}"
        if origin is None:
            return Fault(text, error=type(error).__name__)
        if origin.what.startswith(("call of", "assignment")) and not isinstance(error, DoubleExecutionError):
            text = f"{origin.what}: {text}"
        return Fault(text, origin.option, origin.state, origin.span, type(error).__name__)

    @property
    def fault(self) -> Fault | None:
        """Why the agent stopped, or None while it runs."""
        return self._fault

    @property
    def errored(self) -> bool:
        """Whether the agent stopped on a fault (until ``reset()``)."""
        return self._fault is not None

    def reset(self) -> None:
        """Every option restarts in its initial state on the next tick; clears a fault (§2.9)."""
        self._require().reset()
        self._fault = None

    # -- what the decisions read -----------------------------------------------------------------

    @property
    def record_reads(self) -> bool:
        """Whether each decision records what it read, for the debugger's "why" (default: off).

        While on, the engine runs a variant of the generated code whose decisions append every
        value they read to a list (see ``xabsl_studio.engine.codegen.python.generate``), read with
        :meth:`reads` after a tick: the values the decision saw, never asked of the host again.
        It computes exactly what the plain code computes; off, nothing is recorded and a tick
        costs what it always did. Set it between ticks; it stays across loads and reloads.
        """
        return self._record_reads

    @record_reads.setter
    def record_reads(self, on: bool) -> None:
        on = bool(on)
        if on == self._record_reads:
            return
        self._record_reads = on
        loaded = self._loaded
        if loaded is None:
            return
        loaded.bind(generate(loaded.program, loaded.layout, on))
        self._reads = loaded.reads if on else None
        self.root_actions.rebuild()

    def reads(self) -> tuple[object, ...]:
        """What the decisions of the last tick read (empty unless :attr:`record_reads` is on).

        In the order of the tick: an option's IR id, then the reads of its decision as tuples
        (the layout of ``xabsl_studio.engine.codegen.python.generate``; ids are the IR's, values
        raw: enums as host integers), then the next option's id. ``xabsl_studio.engine.runtime.debug``
        explains decisions from it (``decision_reads``, ``ReadValues``).
        """
        return tuple(self._reads) if self._reads is not None else ()

    # -- agents ----------------------------------------------------------------------------------

    @property
    def program(self) -> Program:
        """The loaded program."""
        return self._require().program

    @property
    def agents(self) -> tuple[Agent, ...]:
        """The agents of the loaded program (select one with ``root_actions.select_agent``)."""
        return self._require().program.agents

    @property
    def tick(self) -> int:
        """How many ticks ran since the engine was created."""
        return self._tick

    @property
    def now(self) -> Ms:
        """The clock of the last tick."""
        return self._now

    # -- symbols ---------------------------------------------------------------------------------

    def output(self, name: str) -> Value:
        """The current value of an output or internal symbol (enum values as host ints)."""
        loaded = self._require()
        slot = loaded.layout.outputs.get(name)
        if slot is None:
            raise DebugError(f"unknown output symbol {name}")
        if slot.stored:
            return loaded.outputs[slot.index]
        binding = loaded.linked.outputs[slot.index]
        assert binding is not None and binding.getter is not None
        return binding.getter()

    def outputs(self) -> dict[str, Value]:
        """Every output and internal symbol, in program order."""
        return {name: self.output(name) for name in self._require().layout.outputs}

    def set_output(self, name: str, value: Value) -> None:
        """Write an output symbol as an assignment would (hosts may reset outputs, §2.2)."""
        loaded = self._require()
        slot = loaded.layout.outputs.get(name)
        if slot is None:
            raise DebugError(f"unknown output symbol {name}")
        if slot.stored:
            loaded.outputs[slot.index] = value
        else:
            binding = loaded.linked.outputs[slot.index]
            assert binding is not None and binding.setter is not None
            binding.setter(value)

    def enum_value(self, element: str) -> int:
        """The host value of a qualified enum element."""
        return self._require().linked.enum_values[element]

    def enum_element(self, enum: str | None, value: Value) -> Value | str:
        """The first element of ``enum`` with ``value`` (the value itself if none has it)."""
        if enum is None:
            return value
        return self._require().linked.enum_names.get(enum, {}).get(int(value), value)

    # -- which options ran ---------------------------------------------------------------------------

    @property
    def option_names(self) -> tuple[str, ...]:
        """The options of the loaded program in index order (the order of ``ran_options``)."""
        return tuple(self._require().linked.option_names)

    def ran_options(self) -> bytes:
        """Per option (``option_names`` order): 1 if it ran in the last tick, else 0.

        The cheap per-tick view for statistics and trace hashes: built in C from the engine's
        tick stamps (no walk, no objects), unlike :meth:`snapshot` / :meth:`activation`.
        """
        return bytes(map(self._tick.__eq__, self._require().last_tick))

    def active_states(self) -> tuple[int, ...]:
        """Per option (``option_names`` order): the index of its active state.

        Options that did not run keep the state they were left in (§2.2); read it together
        with :meth:`ran_options`.
        """
        return tuple(self._require().states)

    # -- activation tree ---------------------------------------------------------------------------

    def snapshot(self) -> Snapshot:
        """The storage after the last tick, copied (cheap); build the tree later."""
        loaded = self._require()
        lists = loaded.snapshot_lists  # the snapshot lists of STORAGE, in Snapshot order
        calls = loaded.calls_of_tick(self._tick)  # B1's double calls; None under B2
        # tuple.__new__ directly: the NamedTuple's own __new__ is a Python function that parses
        # 15 arguments; this is half the cost, and recorders snapshot every tick.
        return _new_tuple(Snapshot, (self._now, self._tick, self.root_actions.roots, *map(tuple, lists), calls))

    def assignment_values(self) -> tuple[Value | None, ...]:
        """The values the last tick's output assignments wrote, per site: ``snapshot().assignments`` alone.

        For recorders, which need only this part of a snapshot every tick (one list copy, not 15).
        """
        return tuple(self._require().assignments)

    def path(self) -> list[list[Any]]:
        """The last tick's compact activation path (:func:`~xabsl_studio.engine.runtime.activation.compact_path`).

        The cheap alternative to :meth:`activation` for recording every tick: flat lists with
        integer ids, read straight from the engine's storage.
        """
        loaded = self._require()
        plan = loaded.path_plan
        if plan is None:
            plan = loaded.path_plan = PathPlan.of(loaded.program, loaded.layout)
        calls = loaded.calls_of_tick(self._tick)  # B1's double calls; None under B2
        return compact_path(plan, self.root_actions.roots, self._tick, self._now, loaded.path_storage, calls)

    def activation(self, snapshot: Snapshot | None = None) -> list[Node]:
        """The activation tree of the last tick (or of ``snapshot``)."""
        loaded = self._require()
        return build_tree(snapshot or self.snapshot(), loaded.program, loaded.layout, loaded.behavior_declared)

    def activation_dict(self) -> list[dict[str, Any]]:
        """The activation tree as JSON-ready dicts, enum values as element names."""
        return [node_to_dict(node, self.enum_element) for node in self.activation()]

    # -- inspection --------------------------------------------------------------------------------

    def source(self, option: str) -> str:
        """The generated Python source of ``option`` (compiled as ``<xabsl:option>``)."""
        return self._require().generated.options[option].source

    @property
    def coop(self) -> CoopStates:
        """The cooperative-state team-message interface of this agent (§2.11)."""
        return self._require().coop

    @property
    def input_reads(self) -> Mapping[str, Callable[..., Value]]:
        """Per input symbol the callable the behavior reads it through (an override replaces it).

        A live, read-only view for samplers: call ``input_reads[name]()`` for a plain input's value.
        """
        return MappingProxyType(self._require().input_reads)

    def input_sampler(self, names: Sequence[str]) -> Callable[[], tuple[Value, ...]]:
        """A function that reads the plain input symbols ``names`` as one tuple, in that order.

        For recording every tick: inputs bound with :meth:`Bindings.input_attribute` (or
        :meth:`Bindings.input_item`) are read with one ``operator.attrgetter`` (``itemgetter``)
        call per host object (all in C), the others through their
        getters. While the debugger overrides any input, the sampler reads through
        :attr:`input_reads` instead, so overridden values are what it returns. Valid until the
        next load or reload.
        """
        loaded = self._require()
        groups: dict[tuple[int, bool], tuple[object, list[str], list[int], list[Callable[..., Value]]]] = {}
        getters: list[tuple[Callable[..., Value], int]] = []
        for position, name in enumerate(names):
            binding = loaded.linked.inputs[loaded.layout.inputs[name].index]
            field = binding.attribute if binding.attribute is not None else binding.key
            if field is not None and binding.source is not None:
                by_key = binding.attribute is None
                group = groups.setdefault((id(binding.source), by_key), (binding.source, [], [], []))
                group[1].append(field)
                group[2].append(position)
                group[3].append(binding.read)
            else:
                getters.append((binding.read, position))
        readers: list[tuple[Callable[[object], tuple[Value, ...]], object]] = []
        order: list[int] = []
        for (_, by_key), (source, attributes, positions, single_reads) in groups.items():
            if len(attributes) > 1:  # one C call reads them all (attrgetter of several names -> tuple)
                getter: Callable[[Any], tuple[Value, ...]] = (
                    itemgetter(*attributes) if by_key else attrgetter(*attributes)
                )
                readers.append((getter, source))
                order.extend(positions)
            else:
                getters.append((single_reads[0], positions[0]))
        order.extend(p for _, p in getters)
        where = [0] * len(names)  # requested position -> position in the read order
        for slot, position in enumerate(order):
            where[position] = slot
        reads = loaded.input_reads
        overrides = loaded.overrides
        plain = [g for g, _ in getters]
        names = tuple(names)
        if len(readers) == 1 and not plain and where == list(range(len(names))):
            # One host object holds them all, in sample order (a bench robot's values): one C call.
            read_all, source = readers[0]

            def sample_one() -> tuple[Value, ...]:
                if overrides:
                    return tuple([reads[name]() for name in names])
                return read_all(source)

            return sample_one

        def sample() -> tuple[Value, ...]:
            if overrides:
                return tuple([reads[name]() for name in names])
            values: list[Value] = []
            for read, source in readers:
                values.extend(read(source))
            values.extend([read() for read in plain])
            return tuple(map(values.__getitem__, where))

        return sample

    def output_sampler(self, names: Sequence[str]) -> Callable[[], tuple[Value, ...]]:
        """A function that reads the output and internal symbols ``names`` as one tuple, in order.

        The recording counterpart of :meth:`input_sampler`: engine-stored symbols are picked from
        the storage list in C, host symbols read through their getters. Valid until the next load
        or reload.
        """
        loaded = self._require()
        slots = [loaded.layout.outputs[name] for name in names]
        storage = loaded.outputs
        indices = [slot.index for slot in slots if slot.stored]
        if len(indices) == len(slots):
            if len(indices) > 1:  # one C call picks them all (itemgetter of several -> tuple)
                pick_all = itemgetter(*indices)
                return lambda: pick_all(storage)
            pick = storage.__getitem__
            return lambda: tuple(map(pick, indices))
        # Host symbols through their own getters (not Engine.output, which looks each name up
        # again), stored ones picked from storage, then put back in the order asked.
        getters: list[Callable[[], Value]] = []
        for slot in slots:
            if not slot.stored:
                binding = loaded.linked.outputs[slot.index]
                assert binding is not None and binding.getter is not None
                getters.append(binding.getter)
        picked = itemgetter(*indices) if len(indices) > 1 else None
        order = [p for p, slot in enumerate(slots) if slot.stored]
        order += [p for p, slot in enumerate(slots) if not slot.stored]
        where = [0] * len(slots)  # requested position -> position in the read order
        for at, position in enumerate(order):
            where[position] = at

        def sample() -> tuple[Value, ...]:
            if picked is not None:
                values = list(picked(storage))
            else:
                values = [storage[i] for i in indices]
            values.extend([read() for read in getters])
            return tuple(map(values.__getitem__, where))

        return sample
