"""A set of XABSL engines by robot id: the engine commands, who forced what, and each tick's sample.

What any owner of engines answers to a studio, whether it is the studio's own simulation process
(``xabsl_studio.server.simulation.worker`` ``Simulation``, which adds the world) or a program that
runs its engines itself and attaches to studios over the network
(``xabsl_studio.server.simulation.host``):

* the robot commands (``_op_select_agent``, ``_op_force_option``, ``_op_force_behavior``,
  ``_op_release``, ``_op_override_input``, ``_op_release_input``, ``_op_reset_agent``) with the
  robot and name resolution they share (:meth:`EngineSet._robot`, :meth:`EngineSet._named`), and
  who set each force and override (:meth:`EngineSet.release_owner` undoes a client's);
* the id tables of a generation (:meth:`EngineSet.sampling_tables`: one
  :class:`~xabsl_studio.server.simulation.sampling.ProgramCodec` per program, one
  :class:`~xabsl_studio.server.simulation.sampling.FrameSampler` per robot) and the robots' part of
  a tick's sample (:meth:`EngineSet.robot_samples`);
* the breakpoints checked after a tick (:meth:`EngineSet.check_breakpoints`).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import orjson

from xabsl_studio.engine.runtime import DebugError, Engine, EngineError
from xabsl_studio.engine.runtime.breakpoints import BreakpointHit, BreakpointSet
from xabsl_studio.server.protocol.commands import (
    ForceBehavior,
    ForceOption,
    OverrideInput,
    Release,
    ReleaseInput,
    ResetAgent,
    SelectAgent,
)
from xabsl_studio.server.protocol.host import Hit, ReleaseOwner, SetBreakpoints
from xabsl_studio.server.protocol.types import WireValue
from xabsl_studio.server.simulation.sampling import FrameSampler, ProgramCodec

__all__ = ["CommandError", "EngineSet", "RobotInfo"]

#: Generations whose codecs are kept (``explain_recorded`` of a tick before a reload).
KEPT_CODECS = 8

#: What a generation's ``structure`` says of a robot besides its engine: name, team, number.
RobotInfo = tuple[str, str | None, int | None]


class CommandError(DebugError, ValueError):
    """A command that cannot be carried out (bad agent, unknown option, wrong value...)."""


class EngineSet:
    """Engines by robot id (None: a robot without one) and the behavior key each runs.

    Subclasses fill :attr:`engines` and :attr:`keys`, call :meth:`sampling_tables` when the ids
    change and :meth:`robot_samples` after every tick.
    """

    def __init__(self) -> None:
        self.engines: list[Engine | None] = []
        self.keys: list[str | None] = []
        self.samplers: list[FrameSampler | None] = []
        #: per behavior key that did not compile clean: the program JSON of what parsed (shown, not run)
        self.descriptions: dict[str, dict[str, Any]] = {}
        #: the codecs of recent generations by number (``explain_recorded`` of a tick before a reload)
        self.codecs: dict[int, dict[str, ProgramCodec]] = {}
        self._owners: dict[tuple[int, str], str] = {}  # (robot, "root" | "input:" name) -> client
        #: the breakpoints checked after every tick while any is enabled (``armed``)
        self.breakpoints = BreakpointSet()
        #: hits of the last tick, sent after its sample (``take_hits``)
        self.hits: list[Hit] = []
        self.paused = False

    # -- generations and samples ----------------------------------------------------------------------

    def sampling_tables(
        self, number: int, robots: Iterable[RobotInfo]
    ) -> tuple[list[dict[str, Any]], tuple[tuple[int, ...], ...], tuple[tuple[int, ...], ...]]:
        """New samplers for generation ``number``: the structure's robots and the symbol ids per robot."""
        codecs: dict[str, ProgramCodec] = {}
        samplers: list[FrameSampler | None] = []
        input_ids: list[tuple[int, ...]] = []
        output_ids: list[tuple[int, ...]] = []
        described = []
        rows = zip(robots, self.engines, self.keys, strict=True)
        for index, ((name, team, number_of), engine, key) in enumerate(rows):
            # A robot of a behavior that does not compile keeps its key: the studio shows what parsed.
            shown = key is not None and (engine is not None or key in self.descriptions)
            described.append(
                {
                    "id": index,
                    "name": name,
                    "team": team,
                    "number": number_of,
                    "program": key if shown else None,
                    "engine": engine is not None,
                }
            )
            if engine is None or key is None:
                samplers.append(None)
                input_ids.append(())
                output_ids.append(())
                continue
            codec = codecs.get(key)
            if codec is None or codec.program is not engine.program:
                codec = codecs[key] = ProgramCodec.build(key, engine.program, engine)
            samplers.append(FrameSampler(index, engine, codec))
            input_ids.append(tuple(i for i, *_ in codec.inputs))
            output_ids.append(tuple(i for i, *_ in codec.outputs))
        self.samplers = samplers
        self.codecs[number] = codecs
        for old in [n for n in self.codecs if n <= number - KEPT_CODECS]:
            del self.codecs[old]
        return described, tuple(input_ids), tuple(output_ids)

    def robot_samples(
        self,
    ) -> tuple[
        tuple[bytes, ...],
        tuple[bytes, ...],
        tuple[tuple[WireValue, ...], ...],
        tuple[tuple[WireValue, ...], ...],
        tuple[bytes, ...],
    ]:
        """Per robot: path (JSON bytes), extras, input and output display values, the decisions' reads.

        The reads are JSON bytes (``Engine.reads()``), b'' for a robot without an engine.
        """
        reads: list[bytes] = []
        paths: list[bytes] = []
        extras: list[bytes] = []
        inputs: list[tuple[WireValue, ...]] = []
        outputs: list[tuple[WireValue, ...]] = []
        dumps = orjson.dumps
        for sampler in self.samplers:
            if sampler is None:
                paths.append(b"[]")
                extras.append(b"")
                inputs.append(())
                outputs.append(())
                reads.append(b"")
                continue
            try:
                paths.append(dumps(sampler.path()))
            except Exception:  # a broken tree (e.g. a fault mid-tick) must not stop the simulation
                paths.append(b"[]")
            extras.append(sampler.extras())
            inputs.append(sampler.inputs())
            outputs.append(sampler.outputs())
            reads.append(sampler.reads())
        return tuple(paths), tuple(extras), tuple(inputs), tuple(outputs), tuple(reads)

    # -- breakpoints ----------------------------------------------------------------------------------

    def check_breakpoints(self) -> list[BreakpointHit]:
        """The breakpoints the tick just run hit; any hit pauses (before the sample, so that it says so)."""
        hits = self.breakpoints.check(
            (index, key, engine) for index, (key, engine) in enumerate(zip(self.keys, self.engines, strict=True))
        )
        if hits:
            self.paused = True
        return hits

    def record_hits(self, found: list[BreakpointHit], seq: int, t: int) -> None:
        """Keep the hits of the tick of sample ``seq`` for :meth:`take_hits`."""
        for hit in found:
            key = self.keys[hit.robot] or ""
            point = self.breakpoints.points.get(key, {}).get(hit.id)
            description = point.describe() if point is not None else f"breakpoint {hit.id}"
            self.hits.append(Hit(key, hit.id, hit.robot, seq, t, description))

    def take_hits(self) -> list[Hit]:
        """The hits of the ticks run since the last call (to send after their samples)."""
        hits, self.hits = self.hits, []
        return hits

    # -- helpers for commands -----------------------------------------------------------------------

    def _robot(self, index: int) -> tuple[int, Engine, ProgramCodec]:
        if not 0 <= index < len(self.engines):
            raise CommandError(f"robot must be a robot id in 0..{len(self.engines) - 1}")
        engine = self.engines[index]
        sampler = self.samplers[index]
        if engine is None or sampler is None:
            if self.keys[index] in self.descriptions:
                raise CommandError(f"robot {index} stands: its behavior has errors (it starts when it compiles)")
            raise CommandError(f"robot {index} runs no XABSL engine")
        return index, engine, sampler.codec

    @staticmethod
    def _named(value: int | str, ids: Mapping[str, int], what: str) -> str:
        if isinstance(value, str):
            if value not in ids:
                raise CommandError(f"unknown {what} {value!r}")
            return value
        for name, i in ids.items():
            if i == value:
                return name
        raise CommandError(f"unknown {what} id {value}")

    def _own(self, agent: int, what: str, owner: str | None) -> None:
        if owner is None:
            self._owners.pop((agent, what), None)
        else:
            self._owners[(agent, what)] = owner

    def owned(self) -> dict[tuple[int, str], str]:
        """Who set each force and override still in place: (robot, ``root`` | ``input:NAME``) -> owner."""
        return dict(self._owners)

    def release_owner(self, owner: str, prefix: bool = False) -> int:
        """Release every force and override ``owner`` made and nobody changed since.

        ``prefix``: every owner whose name starts with ``owner`` (all the clients of one studio).
        """
        released = 0
        for (agent, what), who in list(self._owners.items()):
            if who != owner and not (prefix and who.startswith(owner)):
                continue
            del self._owners[(agent, what)]
            engine = self.engines[agent]
            if engine is None:
                continue
            try:
                if what == "root":
                    engine.root_actions.release()
                else:
                    engine.root_actions.release_input(what.removeprefix("input:"))
                released += 1
            except (DebugError, EngineError):
                continue
        return released

    # -- commands ---------------------------------------------------------------------------------

    def _op_select_agent(self, command: SelectAgent, owner: str | None) -> Any:
        _, engine, _ = self._robot(command.robot)
        engine.root_actions.select_agent(command.agent)
        return None

    def _op_force_option(self, command: ForceOption, owner: str | None) -> Any:
        index, engine, codec = self._robot(command.robot)
        option = self._named(command.option, codec.option_ids, "option")
        engine.root_actions.force_option(option, command.params, by_index=True)
        self._own(index, "root", owner)
        return None

    def _op_force_behavior(self, command: ForceBehavior, owner: str | None) -> Any:
        index, engine, codec = self._robot(command.robot)
        behavior = self._named(command.behavior, codec.behavior_ids, "basic behavior")
        engine.root_actions.force_behavior(behavior, command.params, by_index=True)
        self._own(index, "root", owner)
        return None

    def _op_release(self, command: Release, owner: str | None) -> Any:
        index, engine, _ = self._robot(command.robot)
        engine.root_actions.release()
        self._owners.pop((index, "root"), None)
        return None

    def _op_override_input(self, command: OverrideInput, owner: str | None) -> Any:
        index, engine, codec = self._robot(command.robot)
        ids = {s.name: s.index for s in codec.program.inputs.values()}
        name = self._named(command.symbol, ids, "input symbol")
        engine.root_actions.override_input(name, command.value, by_index=True)
        self._own(index, "input:" + name, owner)
        return None

    def _op_release_input(self, command: ReleaseInput, owner: str | None) -> Any:
        index, engine, codec = self._robot(command.robot)
        if command.symbol is None:
            engine.root_actions.release_inputs()
            for key in [k for k in self._owners if k[0] == index and k[1].startswith("input:")]:
                del self._owners[key]
            return None
        ids = {s.name: s.index for s in codec.program.inputs.values()}
        name = self._named(command.symbol, ids, "input symbol")
        engine.root_actions.release_input(name)
        self._owners.pop((index, "input:" + name), None)
        return None

    def _op_reset_agent(self, command: ResetAgent, owner: str | None) -> Any:
        _, engine, _ = self._robot(command.robot)
        engine.reset()
        return None

    def _op_set_breakpoints(self, command: SetBreakpoints, owner: str | None) -> Any:
        """Internal: the breakpoints of one behavior (all of them, from the server)."""
        self.breakpoints.replace(command.key, command.points)
        return None

    def _op_release_owner(self, command: ReleaseOwner, owner: str | None) -> Any:
        """Internal: release what the client ``owner`` forced and overrode (it disconnected)."""
        return self.release_owner(str(owner))
