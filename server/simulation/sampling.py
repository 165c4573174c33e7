"""Sampling after a tick (simulation process): one robot's activation path and symbols, raw.

The engine is read through the project's one sampler (``xabsl_studio.engine.record.sampler.AgentSampler``,
the recorder's too): the compact ``path`` of docs/protocol.md (integer ids), the input and
output symbols, and what the tick's decisions read (exact, as JSON: the server's ring keeps it
so that "why" at any past tick uses the values the decision saw). This module builds the id
tables of a program (:class:`ProgramCodec`) and a robot's part of a sample; the path's
parameters and the symbols go to the server process raw, exactly as the sampler read them: the
server turns them into the values frames carry (``xabsl_studio.server.protocol.display.SampleDisplay``:
decimals rounded, enums as element indices), so that converting them costs the simulation
process (or an attached robot's program) nothing, and keeps and encodes the sample
(``xabsl_studio.server.session.frames``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import orjson

from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.record.sampler import AgentSampler, ProgramTables, reads_json
from xabsl_studio.engine.runtime import Engine
from xabsl_studio.engine.runtime.activation import BEHAVIOR_NODE, OPTION_NODE
from xabsl_studio.engine.types import Kind, Value
from xabsl_studio.server.protocol.display import converter

_OPT = orjson.OPT_NON_STR_KEYS


@dataclass(slots=True)
class ProgramCodec:
    """Name -> id tables of one program and host value -> element index per enumeration."""

    key: str
    program: Program
    option_ids: dict[str, int]
    state_ids: dict[str, dict[str, int]]
    behavior_ids: dict[str, int]
    behavior_params: dict[str, tuple[str, ...]]
    inputs: tuple[tuple[int, str, Kind, str | None], ...]
    outputs: tuple[tuple[int, str, Kind, str | None], ...]
    enum_index: dict[str, dict[int, int]]
    #: what the shared sampler needs to read the program's engines (symbols in the order above)
    tables: ProgramTables

    @classmethod
    def build(cls, key: str, program: Program, engine: Engine) -> ProgramCodec:
        """Tables for ``program``; ``engine`` (one that runs it) gives the enums' host values."""
        enum_index: dict[str, dict[int, int]] = {}
        for name, enum in program.enums.items():
            table: dict[int, int] = {}
            for i, element in enumerate(enum.elements):
                try:
                    table.setdefault(int(engine.enum_value(element)), i)
                except KeyError:
                    continue
            enum_index[name] = table
        return cls(
            key=key,
            program=program,
            option_ids={name: o.index for name, o in program.options.items()},
            state_ids={name: {s.name: s.index for s in o.states} for name, o in program.options.items()},
            behavior_ids={name: b.index for name, b in program.behaviors.items()},
            behavior_params={name: tuple(p.name for p in b.params) for name, b in program.behaviors.items()},
            inputs=tuple((s.index, s.name, s.kind, s.enum) for s in program.inputs.values() if not s.params),
            outputs=tuple((s.index, s.name, s.kind, s.enum) for s in program.outputs.values()),
            enum_index=enum_index,
            tables=ProgramTables.of(engine),
        )

    def display(self, kind: Kind, enum: str | None, value: Any) -> Value | None:
        """A value as frames carry it (docs/protocol.md "Values"; the server's rules, None: no display value)."""
        try:
            return converter(kind, self.enum_index.get(enum or "", {}))(value)
        except (TypeError, ValueError, OverflowError):
            return None

    def element(self, enum: str | None, index: int) -> str | None:
        """The qualified element name at ``index`` of ``enum`` (for commands that take indices)."""
        if enum is None or enum not in self.program.enums:
            return None
        elements = self.program.enums[enum].elements
        return elements[index] if 0 <= index < len(elements) else None


class FrameSampler:
    """One robot's part of a sample after a tick: its path, input and output values (raw), extras.

    The engine is read by the one sampler of the project, :class:`xabsl_studio.engine.record.sampler.AgentSampler`
    (the recorder's too); the values go to the server raw (see the module docstring), the
    overrides in the extras as display values (docs/protocol.md "Values").
    """

    __slots__ = ("codec", "engine", "index", "reader")

    def __init__(self, index: int, engine: Engine, codec: ProgramCodec) -> None:
        self.index = index
        self.engine = engine
        self.codec = codec
        #: the shared sampler (assignment values are not part of frames)
        self.reader = AgentSampler(engine, codec.tables, assignments=False)

    def path(self) -> list[list[Any]]:
        """The robot's activation path in the frame format (docs/protocol.md "path"), parameters raw.

        The engine's compact path already has the frame's node layout and the JSON ids; the
        server turns the parameter values into display values (``SampleDisplay``).
        """
        return self.reader.path()

    def inputs(self) -> tuple[Value | None, ...]:
        """The raw values of the plain input symbols, in the codec's order (None: the host getter failed)."""
        return self.reader.inputs()[0]

    def outputs(self) -> tuple[Value | None, ...]:
        """The raw values of the output and internal symbols, in the codec's order (None: unread)."""
        return self.reader.outputs()[0]

    def reads(self) -> bytes:
        """What the robot's decisions read in the tick, exact, as JSON (docs/recordings.md ``reads``).

        b'' (unknown) when the engine does not record reads (an attach host with no studio until
        this tick).
        """
        return reads_json(self.reader.reads()) if self.engine.record_reads else b""

    def extras(self) -> bytes:
        """``,"fault":...,"forced":...,"overrides":...`` for the robot's object, or b''."""
        engine = self.engine
        fault = engine.fault
        actions = engine.root_actions
        if fault is None and not actions.forced and not actions.overrides:
            return b""  # the common case, every tick of every robot: nothing to build
        parts: dict[str, Any] = {}
        if fault is not None:
            parts["fault"] = {"message": fault.message, "option": fault.option, "state": fault.state}
        forced = actions.forced
        if forced:
            root = forced[0]
            if root.kind == "option":
                parts["forced"] = [OPTION_NODE, self.codec.option_ids.get(root.name, -1)]
            else:
                parts["forced"] = [BEHAVIOR_NODE, self.codec.behavior_ids.get(root.name, -1)]
        overrides = actions.overrides
        if overrides:
            program = self.codec.program
            parts["overrides"] = {
                program.inputs[name].index: self.codec.display(program.inputs[name].kind, program.inputs[name].enum, v)
                for name, v in overrides.items()
                if name in program.inputs
            }
        if not parts:
            return b""
        return b"," + orjson.dumps(parts, option=_OPT)[1:-1]
