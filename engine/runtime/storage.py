"""A program bound to one engine: flat storage lists, generated functions, host objects (§2.1).

:class:`LoadedProgram` is what :meth:`engine.runtime.engine.Engine.load` builds: the linker's
layout turned into lists (active states, tick stamps, activation times, decision records,
parameters, outputs), the generated option functions bound to them as globals, and the root
actions that call options and basic behaviors with constant parameters (§2.5, §2.9). The
Engine owns the lifecycle (load, reload, ticks, faults); this module owns the storage.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from engine.codegen.layout import default_value, engine_order
from engine.codegen.python import GeneratedProgram
from engine.codegen.support import MS_MASK, SUPPORT_GLOBALS
from engine.runtime.activation import PathPlan, Root
from engine.runtime.coop import CoopStates
from engine.runtime.linker import Linked
from engine.types import Kind, Value

if TYPE_CHECKING:
    from engine.runtime.engine import Engine

__all__ = ["NEVER", "LoadedProgram", "RootAction"]

#: Tick stamp of "never executed": never equal to ``tick - 1`` for a real tick (ticks start at 1).
NEVER = -10

RootAction = Callable[[int, int], None]


class LoadedProgram:
    """One program bound to one engine: storage lists, generated functions, host objects."""

    def __init__(self, linked: Linked, generated: GeneratedProgram, engine: Engine) -> None:
        self.linked = linked
        self.program = linked.program
        self.layout = linked.layout
        self.generated = generated
        n = len(linked.option_names)
        self.LT = [NEVER] * n
        self.PV = [NEVER] * n
        self.TA = [0] * n
        self.S = [linked.layout.options[name].initial for name in linked.option_names]
        self.TS = [0] * n
        self.LF: list[tuple[int, int, int] | None] = [None] * n
        self.SD = [0.0] * n
        self.PP: list[Value] = [0.0] * linked.n_option_params
        for name, slot in linked.layout.options.items():
            for k, (_, kind) in enumerate(slot.params):
                self.PP[slot.offset + k] = default_value(kind)
            del name
        self.BP: list[Value] = [0.0] * linked.n_behavior_params
        self.behavior_params: dict[str, tuple[tuple[str, Kind, str | None], ...]] = {}
        for name, bslot in linked.layout.behaviors.items():
            instance = linked.behaviors[bslot.index]
            declared = type(instance).declared_parameters()
            self.behavior_params[name] = tuple((p.name, p.kind, p.enum) for p in declared)
            for k, (_, kind) in enumerate(bslot.params):
                self.BP[bslot.offset + k] = default_value(kind)
            instance._attach(self.BP, bslot.offset, [p[0] for p in bslot.params])
        nb = len(linked.behaviors)
        self.BLT = [NEVER] * nb
        self.BPV = [NEVER] * nb
        self.BTA = [0] * nb
        self.OV: list[Value] = list(linked.output_initial)
        self.AV: list[Value | None] = [None] * len(linked.layout.sites)
        self.coop = CoopStates.of(self.program)
        self.coop.tick = lambda: engine._tick
        self.coop.executing = self.executing_coop_states
        g: dict[str, Any] = dict(SUPPORT_GLOBALS)
        g.update(
            LT=self.LT,
            PV=self.PV,
            TA=self.TA,
            S=self.S,
            TS=self.TS,
            LF=self.LF,
            SD=self.SD,
            PP=self.PP,
            BP=self.BP,
            BLT=self.BLT,
            BPV=self.BPV,
            BTA=self.BTA,
            OV=self.OV,
            AV=self.AV,
            DX=engine._double_execution,
            RB=self.run_behavior,
            CC=self.coop.check,
            CF=self.coop.conflict,
        )
        for k, behavior in enumerate(linked.behaviors):
            # Generated basic-behavior calls do the bookkeeping of ``run_behavior`` inline.
            g[f"BB{k}"] = behavior
            g[f"BE{k}"] = behavior.execute
        for k, binding in enumerate(linked.inputs):
            g[f"I{k}"] = binding.read
            if binding.attribute is not None:
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
        generated.bind(g)
        self.functions: list[Callable[[int, int], None]] = [g[f"O{i}"] for i in range(n)]
        self.input_reads = {name: g[f"I{slot.index}"] for name, slot in linked.layout.inputs.items()}
        #: built on the first :meth:`Engine.path` call (hosts that never record pay nothing)
        self.path_plan: PathPlan | None = None
        self.path_storage = (self.LT, self.S, self.TA, self.TS, self.LF, self.PP, self.BP, self.BLT, self.BTA)

    def run_behavior(self, k: int, now: int, tick: int, changed: bool) -> None:
        """One call of basic behavior ``k`` (§2.2 ``ActionBehavior.execute``), parameters already set.

        Used for root actions; generated calls inline the same steps (``engine.codegen.python``).
        """
        lt = self.BLT[k]
        if lt != tick:
            self.BPV[k] = lt
            self.BLT[k] = tick
            was = lt == tick - 1
        else:
            was = self.BPV[k] == tick - 1
        behavior = self.linked.behaviors[k]
        if changed:
            behavior.parameters_changed()
        if not was:
            self.BTA[k] = now
        behavior.time_of_execution = (now - self.BTA[k]) & MS_MASK
        behavior.execute()

    def executing_coop_states(self) -> list[tuple[int, int]]:
        tick = self.coop.tick()
        return [key for key in self.coop.states if self.LT[key[0]] == tick and self.S[key[0]] == key[1]]

    def root_action(self, root: Root, params: Mapping[str, Value]) -> RootAction:
        """A root action calling ``root`` with constant ``params`` (others get defaults, §2.5).

        A root of kind ``"output"`` assigns ``params["value"]`` to that output symbol on every
        tick (``addRootActionDecimalOutputSymbol`` and siblings, §2.9).
        """
        if root.kind == "output":
            oslot = self.layout.outputs[root.name]
            value = params["value"]
            if oslot.stored:
                outputs, position = self.OV, oslot.index

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
            store = self.PP

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
        bstore = self.BP
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
