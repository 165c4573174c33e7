"""The Engine: load a program against host bindings and execute it tick by tick (§2).

One :class:`Engine` runs one agent. ``load`` links the program (§2.10), checks the option
graph of every agent root, generates Python code for it once (:mod:`engine.codegen.python`)
and binds that code to this engine's storage. ``execute(now_ms)`` runs one tick exactly as
§2.2 says: one clock value for the whole tick, the root actions in order, decision before
actions in every option, outputs written through at once.

Persistent per-option state lives in flat lists indexed by option index (active state, tick
stamps of the last two executions, activation times, the tick's decision record): a tick stamp
replaces the original's per-tick ``wasActive``/``isActive`` flag swap, so nothing is reset at
the end of a tick.

Faults (§2.9, architecture "Engine"): a host callable or basic behavior that raises, a ``%`` by
zero or (policy B2) a double execution marks the engine as errored with a :class:`Fault`
naming the option, state and XABSL span; ``execute`` then does nothing until ``reset()``.

Hot reload: ``reload(program)`` swaps programs between ticks, keeping the active state and
times of options and states that still exist by name; a program that fails to link or check
leaves the running one untouched and raises.
"""

from __future__ import annotations

import traceback
from collections.abc import Callable, Mapping, Sequence
from operator import attrgetter
from types import MappingProxyType, SimpleNamespace
from typing import TYPE_CHECKING, Any

from engine.codegen.python import CodegenError, generate
from engine.codegen.support import MS_MASK
from engine.ir.model import Agent, Program
from engine.runtime.activation import Node, PathPlan, Root, Snapshot, build_tree, compact_path, node_to_dict
from engine.runtime.bindings import Bindings
from engine.runtime.checks import Policy, check_root
from engine.runtime.coop import CoopStates
from engine.runtime.errors import DebugError, DoubleExecutionError, Fault, LoadError
from engine.runtime.linker import link
from engine.runtime.storage import NEVER, LoadedProgram, RootAction
from engine.types import Ms, Value

if TYPE_CHECKING:
    from engine.runtime.debug import Debugger

__all__ = ["Engine"]


class Engine:
    """Runs one agent's behavior: load, execute ticks, inspect, force, reload.

    Example::

        engine = Engine(bindings)           # bindings: engine.runtime.bindings.Bindings
        engine.load(program)                # LinkError lists everything missing
        engine.execute(now_ms)              # one tick; never raises
        engine.activation()                 # the tick's activation tree
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
        self._agent: Agent | None = None
        #: root actions the debugger installed instead of the agent's root (None: the agent's)
        self._forced: list[tuple[Root, dict[str, Value]]] | None = None
        self._overrides: dict[str, Value] = {}
        self._roots: list[RootAction] = []
        self._root_names: tuple[Root, ...] = ()
        #: the loaded program has cooperative states (only then a tick clears their bookkeeping)
        self._coop_states = False
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
        try:
            generated = generate(program, linked.layout)
        except CodegenError as error:
            raise LoadError(str(error)) from None
        return LoadedProgram(linked, generated, self)

    def load(self, program: Program) -> None:
        """Load ``program`` from scratch: every option starts fresh, the first agent is selected.

        Raises:
            LinkError: the program names unregistered symbols, enum elements or behaviors.
            LoadError: the option graph of an agent has a loop (or a B2 double execution).
        """
        loaded = self._prepare(program)
        self._loaded = loaded
        self._loaded.coop.agent = self.agent_name
        self._fault = None
        self._forced = None
        self._overrides = {}
        self._agent = program.agents[0] if program.agents else None
        self._install_roots()

    def reload(self, program: Program) -> None:
        """Swap in a new version of the behavior between ticks (hot reload).

        Options and states that still exist (by name) keep their active state, times and
        parameters; everything else starts fresh; bindings are re-linked; input overrides, the
        selected agent and a forced root are kept when their names still exist.

        Raises:
            LinkError, LoadError: the new program cannot run; the running one stays in place.
        """
        old = self._require()
        new = self._prepare(program)
        for name in program.options:
            if name not in old.layout.options:
                continue
            oi = old.layout.options[name].index
            ni = new.layout.options[name].index
            old_option = old.program.options[name]
            new_option = program.options[name]
            state = old_option.states[old.S[oi]].name
            if state not in {s.name for s in new_option.states}:
                continue  # its active state is gone: the option restarts when next called
            new.S[ni] = new_option.state(state).index
            new.LT[ni], new.PV[ni] = old.LT[oi], old.PV[oi]
            new.TA[ni], new.TS[ni], new.SD[ni] = old.TA[oi], old.TS[oi], old.SD[oi]
            old_slot, new_slot = old.layout.options[name], new.layout.options[name]
            old_params = {p: (k, kind) for k, (p, kind) in enumerate(old_slot.params)}
            for k, (p, kind) in enumerate(new_slot.params):
                if p in old_params and old_params[p][1] is kind:
                    new.PP[new_slot.offset + k] = old.PP[old_slot.offset + old_params[p][0]]
        for name, slot in new.layout.behaviors.items():
            if name in old.layout.behaviors:
                o = old.layout.behaviors[name].index
                new.BLT[slot.index], new.BPV[slot.index], new.BTA[slot.index] = old.BLT[o], old.BPV[o], old.BTA[o]
        for name, slot in new.layout.outputs.items():
            old_slot_out = old.layout.outputs.get(name)
            if (
                old_slot_out is not None
                and slot.stored
                and old_slot_out.stored
                and program.outputs[name].kind is old.program.outputs[name].kind
            ):
                new.OV[slot.index] = old.OV[old_slot_out.index]
        new.coop.agent = old.coop.agent
        new.coop.agent_priority = old.coop.agent_priority
        new.coop.synchronization_ticks = old.coop.synchronization_ticks
        self._loaded = new
        agent_name = self._agent.name if self._agent is not None else None
        self._agent = next((a for a in program.agents if a.name == agent_name), None) or (
            program.agents[0] if program.agents else None
        )
        if self._forced is not None:
            kept = [(root, params) for root, params in self._forced if self._root_exists(root)]
            self._forced = kept or None
        overrides = self._overrides
        self._overrides = {}
        for symbol, value in overrides.items():
            if symbol in program.inputs and symbol in new.layout.inputs:
                self._apply_override(symbol, value)
        self._install_roots()

    def _require(self) -> LoadedProgram:
        if self._loaded is None:
            raise DebugError("no program is loaded")
        return self._loaded

    def _root_exists(self, root: Root) -> bool:
        loaded = self._require()
        if root.kind == "output":
            return root.name in loaded.layout.outputs
        table = loaded.layout.options if root.kind == "option" else loaded.layout.behaviors
        return root.name in table

    def _install_roots(self) -> None:
        loaded = self._require()
        self._coop_states = bool(loaded.coop.states)
        if self._forced is not None:
            self._root_names = tuple(root for root, _ in self._forced)
            self._roots = [loaded.root_action(root, params) for root, params in self._forced]
        elif self._agent is not None:
            root = Root("option", self._agent.root)
            self._root_names = (root,)
            self._roots = [loaded.root_action(root, {})]
        else:
            self._root_names = ()
            self._roots = []

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
        # One handler for the whole tick: a fault is located from its traceback (``_locate``),
        # not from which root was running.
        try:
            for action in self._roots:
                action(now, tick)
        except Exception as error:
            self._fault = self._locate(error)

    def _double_execution(self, option: int, tick: int) -> bool:
        loaded = self._require()
        name = loaded.linked.option_names[option]
        message = f"option {name} is contained in the activation tree more than once"
        if self.policy is Policy.B2:
            raise DoubleExecutionError(message)
        self.warnings.append(message)
        return loaded.PV[option] == tick - 1

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
        return self._fault is not None

    def reset(self) -> None:
        """Every option restarts in its initial state on the next tick; clears a fault (§2.9)."""
        loaded = self._require()
        for table in (loaded.LT, loaded.PV, loaded.BLT, loaded.BPV):
            table[:] = [NEVER] * len(table)
        self._fault = None

    # -- agents ----------------------------------------------------------------------------------

    @property
    def program(self) -> Program:
        return self._require().program

    @property
    def agents(self) -> tuple[Agent, ...]:
        return self._require().program.agents

    @property
    def selected_agent(self) -> str | None:
        return self._agent.name if self._agent is not None else None

    def select_agent(self, name: str) -> None:
        """Select agent ``name`` (§2.9): a fresh root action, no option state is reset."""
        loaded = self._require()
        agent = next((a for a in loaded.program.agents if a.name == name), None)
        if agent is None:
            raise DebugError(f"unknown agent {name}")
        if self._agent is not None and self._agent.name == name:
            return
        self._agent = agent
        self._install_roots()

    @property
    def roots(self) -> tuple[Root, ...]:
        """The current root actions (the agent's root option, or a forced root)."""
        return self._root_names

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
            return loaded.OV[slot.index]
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
            loaded.OV[slot.index] = value
        else:
            binding = loaded.linked.outputs[slot.index]
            assert binding is not None and binding.setter is not None
            binding.setter(value)

    def enum_value(self, element: str) -> int:
        """The host value of a qualified enum element."""
        return self._require().linked.enum_values[element]

    def enum_element(self, enum: str | None, value: Value) -> Value:
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
        return bytes(map(self._tick.__eq__, self._require().LT))

    def active_states(self) -> tuple[int, ...]:
        """Per option (``option_names`` order): the index of its active state.

        Options that did not run keep the state they were left in (§2.2); read it together
        with :meth:`ran_options`.
        """
        return tuple(self._require().S)

    # -- activation tree ---------------------------------------------------------------------------

    def snapshot(self) -> Snapshot:
        """The storage after the last tick, copied (cheap); build the tree later."""
        loaded = self._require()
        return Snapshot(
            self._now,
            self._tick,
            self._root_names,
            tuple(loaded.S),
            tuple(loaded.LT),
            tuple(loaded.TA),
            tuple(loaded.TS),
            tuple(loaded.LF),
            tuple(loaded.SD),
            tuple(loaded.PP),
            tuple(loaded.BP),
            tuple(loaded.BLT),
            tuple(loaded.BTA),
            tuple(loaded.AV),
            tuple(loaded.OV),
        )

    def path(self) -> list[list[Any]]:
        """The activation path of the last tick, compact (see :func:`~engine.runtime.activation.compact_path`).

        The cheap alternative to :meth:`activation` for recording every tick: flat lists with
        integer ids, read straight from the engine's storage.
        """
        loaded = self._require()
        plan = loaded.path_plan
        if plan is None:
            plan = loaded.path_plan = PathPlan.of(loaded.program, loaded.layout)
        return compact_path(plan, self._root_names, self._tick, self._now, loaded.path_storage)

    def activation(self, snapshot: Snapshot | None = None) -> list[Node]:
        """The activation tree of the last tick (or of ``snapshot``)."""
        loaded = self._require()
        return build_tree(snapshot or self.snapshot(), loaded.program, loaded.layout, loaded.behavior_params)

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
    def debug(self) -> Debugger:
        """The debug interface (:class:`engine.runtime.debug.Debugger`)."""
        from engine.runtime.debug import Debugger

        return Debugger(self)

    # -- used by the debugger ---------------------------------------------------------------------

    def _loaded_program(self) -> LoadedProgram:
        return self._require()

    def _force(self, root: Root | None, params: dict[str, Value], add: bool = False) -> None:
        """Replace the root actions by ``root`` (``setRootAction``), or append it (``addRootAction``).

        ``root=None`` releases every forced root: the selected agent's root option runs again.
        """
        if root is not None and root.kind == "option":
            check_root(self._require().program, root.name, self.policy)
        if root is None:
            self._forced = None
        elif add and self._forced is not None:
            self._forced = [*self._forced, (root, params)]
        elif add and self._agent is not None:
            self._forced = [(Root("option", self._agent.root), {}), (root, params)]
        else:
            self._forced = [(root, params)]
        self._install_roots()

    def _apply_override(self, symbol: str, value: Value | None) -> None:
        loaded = self._require()
        slot = loaded.layout.inputs[symbol]
        key = f"I{slot.index}"
        binding = loaded.linked.inputs[slot.index]
        if value is None:
            self._overrides.pop(symbol, None)
            loaded.globals[key] = binding.read
            if slot.attribute is not None:
                loaded.globals[f"IA{slot.index}"] = binding.source
        else:
            self._overrides[symbol] = value
            loaded.globals[key] = lambda *_args, _value=value: _value
            if slot.attribute is not None:
                # Generated code reads ``IA{k}.<attribute>``: give it an object that has the value.
                loaded.globals[f"IA{slot.index}"] = SimpleNamespace(**{slot.attribute: value})
        loaded.input_reads[symbol] = loaded.globals[key]

    @property
    def forced(self) -> Root | None:
        """The root the debugger forced in place of the agent's root option, if any."""
        return self._forced[0][0] if self._forced is not None else None

    @property
    def forced_roots(self) -> tuple[Root, ...]:
        """Every root action the debugger installed, in execution order (empty: the agent's root)."""
        return tuple(root for root, _ in self._forced) if self._forced is not None else ()

    @property
    def input_reads(self) -> Mapping[str, Callable[..., Value]]:
        """Per input symbol the callable the behavior reads it through (an override replaces it).

        A live, read-only view for samplers: call ``input_reads[name]()`` for a plain input's value.
        """
        return MappingProxyType(self._require().input_reads)

    def input_sampler(self, names: Sequence[str]) -> Callable[[], tuple[Value, ...]]:
        """A function that reads the plain input symbols ``names`` as one tuple, in that order.

        For recording every tick: inputs bound with :meth:`Bindings.input_attribute` are read with
        one ``operator.attrgetter`` call per host object (all in C), the others through their
        getters. While the debugger overrides any input, the sampler reads through
        :attr:`input_reads` instead, so overridden values are what it returns. Valid until the
        next load or reload.
        """
        loaded = self._require()
        groups: dict[int, tuple[object, list[str], list[int], list[Callable[..., Value]]]] = {}
        getters: list[tuple[Callable[..., Value], int]] = []
        for position, name in enumerate(names):
            binding = loaded.linked.inputs[loaded.layout.inputs[name].index]
            if binding.attribute is not None and binding.source is not None:
                group = groups.setdefault(id(binding.source), (binding.source, [], [], []))
                group[1].append(binding.attribute)
                group[2].append(position)
                group[3].append(binding.read)
            else:
                getters.append((binding.read, position))
        readers: list[tuple[Callable[[object], tuple[Value, ...]], object]] = []
        order: list[int] = []
        for source, attributes, positions, single_reads in groups.values():
            if len(attributes) > 1:  # one C call reads them all (attrgetter of several names -> tuple)
                readers.append((attrgetter(*attributes), source))
                order.extend(positions)
            else:
                getters.append((single_reads[0], positions[0]))
        order.extend(p for _, p in getters)
        where = [0] * len(names)  # requested position -> position in the read order
        for slot, position in enumerate(order):
            where[position] = slot
        reads = loaded.input_reads
        plain = [g for g, _ in getters]
        names = tuple(names)

        def sample() -> tuple[Value, ...]:
            if self._overrides:
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
        stored = all(loaded.layout.outputs[name].stored for name in names)
        if stored:
            indices = [loaded.layout.outputs[name].index for name in names]
            pick = loaded.OV.__getitem__
            return lambda: tuple(map(pick, indices))
        output = self.output
        names = tuple(names)
        return lambda: tuple([output(name) for name in names])

    @property
    def overrides(self) -> dict[str, Value]:
        """Input symbols currently overridden by the debugger, with their values."""
        return dict(self._overrides)
