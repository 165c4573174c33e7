"""Sampling one engine after a tick: the cheap per-tick read shared by recordings and the studio.

:class:`AgentSampler` reads, right after ``Engine.execute``, everything a tick changed, through
the engine's public per-tick views only and without converting anything:

* the activation path (``Engine.path()``: flat lists with IR ids and raw parameter values);
* the values the tick's output assignments wrote (``Engine.assignment_values()``), so the
  activation *tree* (assignment nodes included) can be rebuilt from a recording;
* the input symbols without parameters (``Engine.input_sampler``, overrides included) and the
  output/internal symbols (``Engine.output_sampler``), as tuples of raw values (exact floats,
  enums as host integers);
* the root actions (``Engine.root_actions.roots``) and the fault;
* what each decision of the tick read (``Engine.reads()``: inputs, input function calls with
  their arguments and results, outputs, parameters, times, ``action_done``), recorded by the
  engine's own generated code as the decisions ran (``Engine.record_reads``, which the sampler
  turns on), so "why" at any tick uses the values the decision saw.

Converting for display (rounding, enum names) and comparing with the previous tick are left to
the consumer: the recorder's encoder rounds and encodes deltas, the studio's
``xabsl_studio.server.simulation.sampling.FrameSampler`` converts to the frames' display values. :class:`ProgramTables`
holds what a consumer needs to interpret the raw values of one program (symbol names in sample
order, enum host values, basic-behavior parameter names in path order, assignment sites).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

import orjson

from xabsl_studio.engine.codegen.layout import assignment_sites
from xabsl_studio.engine.ir.model import Assignment, Program
from xabsl_studio.engine.runtime import Engine, Fault, Root
from xabsl_studio.engine.types import Kind, Value

__all__ = ["AgentSample", "AgentSampler", "ProgramTables", "reads_json"]

_new_tuple = tuple.__new__


def _unknown(value: object) -> None:
    """A value JSON cannot hold: written as null (unknown), never a guess."""
    return None


def reads_json(reads: tuple[object, ...]) -> bytes:
    """``Engine.reads()`` as JSON, in C.

    Floats exact (their shortest round-trip form); NaN, infinities and values of other types
    null (unknown); numpy scalars as numbers.
    """
    return orjson.dumps(reads, default=_unknown, option=orjson.OPT_SERIALIZE_NUMPY)


class AgentSample(NamedTuple):
    """What one agent's tick left behind (raw; see the module docstring)."""

    tick: int
    roots: tuple[Root, ...]
    path: list[list[Any]]
    assignments: tuple[Value | None, ...]
    inputs: tuple[Value | None, ...]
    outputs: tuple[Value | None, ...]
    fault: Fault | None
    #: names of symbols whose host getter raised (their value is None in ``inputs``/``outputs``)
    unread: tuple[str, ...] = ()
    #: what the tick's decisions read (``Engine.reads()``; empty unless the sampler records reads)
    reads: tuple[object, ...] = ()


@dataclass(frozen=True, slots=True)
class ProgramTables:
    """How to read the raw samples of one program run by one host (names, enums, parameters).

    ``inputs``/``outputs`` are the symbol names in sample order; ``input_enums``/``output_enums``
    the enum of each (None for decimals and booleans), ``input_decimals``/``output_decimals``
    whether each is a decimal; ``enums`` maps enum name -> host value ->
    element; ``behavior_params`` gives each basic behavior's parameters as ``(name, enum)`` in path
    order (the host's declaration order); ``assignment_sites`` numbers every output assignment as
    ``(option id, state id, action position, output symbol, kind, enum)``.
    """

    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    input_enums: tuple[str | None, ...]
    output_enums: tuple[str | None, ...]
    input_decimals: tuple[bool, ...]
    output_decimals: tuple[bool, ...]
    enums: dict[str, dict[int, str]]
    behavior_params: dict[str, tuple[tuple[str, str | None], ...]]
    assignment_sites: tuple[tuple[int, int, int, str, str, str | None], ...]

    @classmethod
    def of(cls, engine: Engine) -> ProgramTables:
        """The tables of the program ``engine`` runs (the engine gives the host's enum values)."""
        program = engine.program
        inputs = tuple(s for s in program.inputs.values() if not s.params)
        outputs = tuple(program.outputs.values())
        enums: dict[str, dict[int, str]] = {}
        for name, enum in program.enums.items():
            table: dict[int, str] = {}
            for element in enum.elements:
                try:
                    table.setdefault(int(engine.enum_value(element)), element)
                except KeyError:
                    continue
            enums[name] = table
        behavior_params: dict[str, tuple[tuple[str, str | None], ...]] = {}
        for name, behavior in program.behaviors.items():
            registered = engine.bindings.behaviors.get(name)
            declared = registered.declared_parameters() if registered is not None else behavior.params
            behavior_params[name] = tuple((p.name, p.enum) for p in declared)
        sites = sorted(assignment_sites(program).items(), key=lambda item: item[1])
        site_rows = []
        for (option, state, position), _ in sites:
            action = program.options[option].states[state].actions[position]
            assert isinstance(action, Assignment)
            output = program.outputs.get(action.symbol)
            site_enum = output.enum if output is not None else action.enum
            site_rows.append(
                (program.options[option].index, state, position, action.symbol, action.kind.value, site_enum)
            )
        return cls(
            inputs=tuple(s.name for s in inputs),
            outputs=tuple(s.name for s in outputs),
            input_enums=tuple(s.enum if s.kind is Kind.ENUM else None for s in inputs),
            output_enums=tuple(s.enum if s.kind is Kind.ENUM else None for s in outputs),
            input_decimals=tuple(s.kind is Kind.DECIMAL for s in inputs),
            output_decimals=tuple(s.kind is Kind.DECIMAL for s in outputs),
            enums=enums,
            behavior_params=behavior_params,
            assignment_sites=tuple(site_rows),
        )

    def to_json(self) -> dict[str, Any]:
        """The tables as the recording header carries them (enum host values as strings)."""
        return {
            "inputs": list(self.inputs),
            "outputs": list(self.outputs),
            "enums": {name: {str(v): e for v, e in table.items()} for name, table in self.enums.items()},
            "behavior_params": {name: [list(p) for p in params] for name, params in self.behavior_params.items()},
            "assignment_sites": [list(site) for site in self.assignment_sites],
        }


class AgentSampler:
    """Reads one engine after each tick (see the module docstring); valid until a load or reload.

    The one sampling mechanism of the project: the recorder calls :meth:`sample` every tick; the
    studio's simulation process (``xabsl_studio.server.simulation.sampling.FrameSampler``) calls :meth:`path`,
    :meth:`inputs` and :meth:`outputs` and turns the raw values into display values. Without
    ``assignments`` the sample's ``assignments`` stay empty (the studio does not record them).

    Cost for the soccer team behavior: about 10 us per agent and tick (see
    benchmarks/record_cost.py), most of it ``Engine.path()`` and the host's input getters.
    """

    __slots__ = ("_read_inputs", "_read_outputs", "_sites", "engine", "program", "tables")

    def __init__(
        self, engine: Engine, tables: ProgramTables | None = None, assignments: bool = True, reads: bool = True
    ) -> None:
        if reads:
            engine.record_reads = True
        self.engine = engine
        self.program: Program = engine.program
        self.tables = tables if tables is not None else ProgramTables.of(engine)
        self._read_inputs: Callable[[], tuple[Value, ...]] = engine.input_sampler(self.tables.inputs)
        self._read_outputs: Callable[[], tuple[Value, ...]] = engine.output_sampler(self.tables.outputs)
        #: the program has output assignments (only then their values are copied each tick)
        self._sites = assignments and bool(self.tables.assignment_sites)

    def path(self) -> list[list[Any]]:
        """The activation path of the last tick (``Engine.path()``; empty if the tree is broken)."""
        try:
            return self.engine.path()
        except Exception:  # a tree broken by a fault mid-tick must not stop the simulation
            return []

    def inputs(self) -> tuple[tuple[Value | None, ...], tuple[str, ...]]:
        """The raw values of ``tables.inputs`` and the names whose getter raised (their value: None)."""
        try:
            return self._read_inputs(), ()
        except Exception:  # a host getter that raises: read one by one, None where it raises
            return self._inputs_one_by_one()

    def outputs(self) -> tuple[tuple[Value | None, ...], tuple[str, ...]]:
        """The raw values of ``tables.outputs`` and the names whose getter raised (their value: None)."""
        try:
            return self._read_outputs(), ()
        except Exception:
            return self._one_by_one(self.tables.outputs, self.engine.output)

    def _inputs_one_by_one(self) -> tuple[tuple[Value | None, ...], tuple[str, ...]]:
        reads = self.engine.input_reads
        return self._one_by_one(self.tables.inputs, lambda name: reads[name]())

    def sample(self) -> AgentSample:
        """The engine's state after its last tick."""
        engine = self.engine
        try:
            path = engine.path()
        except Exception:  # a tree broken by a fault mid-tick must not stop the recording
            path = []
        unread: tuple[str, ...] = ()
        try:
            inputs: tuple[Value | None, ...] = self._read_inputs()
        except Exception:  # a host getter that raises: read one by one, None where it raises
            inputs, unread = self._inputs_one_by_one()
        try:
            outputs: tuple[Value | None, ...] = self._read_outputs()
        except Exception:
            outputs, bad_out = self._one_by_one(self.tables.outputs, engine.output)
            unread += bad_out
        assignments = engine.assignment_values() if self._sites else ()
        roots = engine.root_actions.roots
        # tuple.__new__ directly: the NamedTuple's own __new__ is a Python function (it ran 10 times a tick)
        return _new_tuple(
            AgentSample, (engine.tick, roots, path, assignments, inputs, outputs, engine.fault, unread, engine.reads())
        )

    def reads(self) -> tuple[object, ...]:
        """What the decisions of the last tick read (``Engine.reads()``)."""
        return self.engine.reads()

    @staticmethod
    def _one_by_one(
        names: tuple[str, ...], read: Callable[[str], Value]
    ) -> tuple[tuple[Value | None, ...], tuple[str, ...]]:
        values: list[Value | None] = []
        bad: list[str] = []
        for name in names:
            try:
                values.append(read(name))
            except Exception:
                values.append(None)
                bad.append(name)
        return tuple(values), tuple(bad)
