"""What an engine runs at its root, and what a debugger forced: the one owner of both (§2.9).

A tick runs the engine's *root actions* in order. Normally that is the selected agent's root
option; a debugger (or the studio) may force any option or basic behavior with constant
parameters in its place (``setRootAction``), add one after the current roots (``addRootAction``),
add an assignment of a constant to an output symbol (``addRootActionDecimalOutputSymbol`` and
siblings), and override input symbols with constant values. :class:`RootActions` holds all of
it, converts every value given from outside once (:func:`xabsl_studio.engine.runtime.values.coerce`), keeps it
across a hot reload while the names still exist, and builds the callables a tick runs.

Forcing never corrupts state: a forced root is just another root action, so options that stop
being called become inactive after one tick and restart when called again, exactly as after an
agent switch; overriding an input swaps the host callable the generated code calls and releasing
puts the host's back.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from xabsl_studio.engine.errors import DebugError
from xabsl_studio.engine.ir.model import Agent, Parameter, short_name
from xabsl_studio.engine.runtime.activation import Root
from xabsl_studio.engine.runtime.checks import Policy, check_root
from xabsl_studio.engine.runtime.storage import LoadedProgram, RootAction
from xabsl_studio.engine.runtime.values import coerce
from xabsl_studio.engine.types import Value

__all__ = ["RootActions"]


class RootActions:
    """The root actions of one engine: the selected agent, forced roots, overridden inputs.

    ``engine.root_actions`` of an :class:`~xabsl_studio.engine.runtime.engine.Engine`. Names of parameters
    are qualified (``"walk.speed"``) or the IR's short name (``"speed"``); values are converted
    by :func:`~xabsl_studio.engine.runtime.values.coerce` (``by_index``: enum ints are element indices).
    """

    def __init__(self, policy: Policy) -> None:
        self.policy = policy
        self._loaded: LoadedProgram | None = None
        self._agent: Agent | None = None
        #: root actions forced instead of the agent's root (None: the agent's root runs)
        self._forced: list[tuple[Root, dict[str, Value]]] | None = None
        #: the root actions a tick runs, in order (the agent's root option, or the forced ones);
        #: read it, change it through the methods (an attribute: snapshots read it every tick)
        self.roots: tuple[Root, ...] = ()
        #: what a tick calls, in order (rebuilt whenever the roots or the program change)
        self.actions: list[RootAction] = []

    # -- the program ---------------------------------------------------------------------------------

    def load(self, loaded: LoadedProgram) -> None:
        """Run a freshly loaded program: its first agent, nothing forced or overridden."""
        self._loaded = loaded
        self._forced = None
        agents = loaded.program.agents
        self._agent = agents[0] if agents else None
        self._install()

    def reload(self, loaded: LoadedProgram) -> None:
        """Run a new version of the program (hot reload).

        The selected agent, forced roots and input overrides are kept where their names still exist.
        """
        old = self._require()
        self._loaded = loaded
        program = loaded.program
        name = self._agent.name if self._agent is not None else None
        self._agent = next((a for a in program.agents if a.name == name), None) or (
            program.agents[0] if program.agents else None
        )
        if self._forced is not None:
            self._forced = [(root, params) for root, params in self._forced if self._exists(root)] or None
        for symbol, value in old.overrides.items():
            if symbol in program.inputs and symbol in loaded.layout.inputs:
                loaded.override_input(symbol, value)
        self._install()

    def _require(self) -> LoadedProgram:
        if self._loaded is None:
            raise DebugError("no program is loaded")
        return self._loaded

    def _exists(self, root: Root) -> bool:
        layout = self._require().layout
        if root.kind == "output":
            return root.name in layout.outputs
        return root.name in (layout.options if root.kind == "option" else layout.behaviors)

    def _chosen(self) -> list[tuple[Root, dict[str, Value]]]:
        if self._forced is not None:
            return list(self._forced)
        if self._agent is not None:
            return [(Root("option", self._agent.root), {})]
        return []

    def _install(self) -> None:
        loaded = self._require()
        chosen = self._chosen()
        self.roots = tuple(root for root, _ in chosen)
        self.actions = [loaded.root_action(root, params) for root, params in chosen]

    def rebuild(self) -> None:
        """Build what a tick calls again, for the same roots (the program's functions were bound anew)."""
        loaded = self._require()
        self.actions = [loaded.root_action(root, params) for root, params in self._chosen()]

    # -- reading -------------------------------------------------------------------------------------

    @property
    def agent(self) -> str | None:
        """The selected agent (None: the program has none)."""
        return self._agent.name if self._agent is not None else None

    @property
    def forced(self) -> tuple[Root, ...]:
        """The forced root actions in execution order (empty: the selected agent's root runs)."""
        return tuple(root for root, _ in self._forced) if self._forced is not None else ()

    @property
    def overrides(self) -> Mapping[str, Value]:
        """Input symbols currently overridden, with their values (a read-only live view)."""
        return MappingProxyType(self._require().overrides)

    # -- steering ------------------------------------------------------------------------------------

    def select_agent(self, name: str) -> None:
        """Select agent ``name`` (§2.9): its root option runs from the next tick, no option state is reset.

        Raises:
            DebugError: the program has no agent ``name``.
        """
        agent = next((a for a in self._require().program.agents if a.name == name), None)
        if agent is None:
            raise DebugError(f"unknown agent {name}")
        if self._agent is not None and self._agent.name == name:
            return
        self._agent = agent
        self._install()

    def force_option(
        self, name: str, params: Mapping[str, object] | None = None, *, add: bool = False, by_index: bool = False
    ) -> None:
        """Run option ``name`` as the root with ``params`` (others default) until :meth:`release`.

        With ``add=True`` the option runs after the current root actions instead of replacing
        them (``addRootAction``).

        Raises:
            DebugError: unknown option or parameter (ValueConversionError: a wrong value).
            LoadError: the option's graph fails the load-time checks.
        """
        loaded = self._require()
        option = loaded.program.options.get(name)
        if option is None or name not in loaded.layout.options:
            raise DebugError(f"unknown option {name}")
        values = self._parameters(name, option.params, params or {}, by_index)
        check_root(loaded.program, name, self.policy)
        self._force(Root("option", name), values, add)

    def force_behavior(
        self, name: str, params: Mapping[str, object] | None = None, *, add: bool = False, by_index: bool = False
    ) -> None:
        """Run basic behavior ``name`` as the root with ``params`` until :meth:`release` (``add``: append).

        Raises:
            DebugError: unknown basic behavior or parameter (ValueConversionError: a wrong value).
        """
        loaded = self._require()
        if name not in loaded.layout.behaviors:
            raise DebugError(f"unknown basic behavior {name}")
        values = self._parameters(name, loaded.behavior_declared[name], params or {}, by_index)
        self._force(Root("behavior", name), values, add)

    def add_output(self, name: str, value: object, *, by_index: bool = False) -> None:
        """Append a root action that assigns ``value`` to output symbol ``name`` every tick (§2.9).

        Raises:
            DebugError: unknown output symbol (ValueConversionError: a wrong value).
        """
        loaded = self._require()
        symbol = loaded.program.outputs.get(name)
        if symbol is None or name not in loaded.layout.outputs:
            raise DebugError(f"unknown output symbol {name}")
        enum = loaded.enum_values(symbol.enum)
        converted = coerce(symbol.kind, enum, value, name=f"output symbol {name}", by_index=by_index)
        self._force(Root("output", name), {"value": converted}, True)

    def release(self) -> None:
        """Return to the selected agent's root option (releases every forced root action)."""
        self._forced = None
        self._install()

    def override_input(self, name: str, value: object, *, by_index: bool = False) -> None:
        """Make input symbol ``name`` read ``value`` (for any parameters) until released.

        Raises:
            DebugError: unknown input symbol (ValueConversionError: a wrong value).
        """
        loaded = self._require()
        symbol = loaded.program.inputs.get(name)
        if symbol is None or name not in loaded.layout.inputs:
            raise DebugError(f"unknown input symbol {name}")
        enum = loaded.enum_values(symbol.enum)
        loaded.override_input(name, coerce(symbol.kind, enum, value, name=f"input symbol {name}", by_index=by_index))

    def release_input(self, name: str) -> None:
        """Read input symbol ``name`` from the host again."""
        loaded = self._require()
        if name not in loaded.layout.inputs:
            raise DebugError(f"unknown input symbol {name}")
        loaded.override_input(name, None)

    def release_inputs(self) -> None:
        """Release every input override."""
        loaded = self._require()
        for name in list(loaded.overrides):
            loaded.override_input(name, None)

    # -- helpers -------------------------------------------------------------------------------------

    def _force(self, root: Root, values: dict[str, Value], add: bool) -> None:
        if add and self._forced is not None:
            self._forced = [*self._forced, (root, values)]
        elif add and self._agent is not None:
            self._forced = [(Root("option", self._agent.root), {}), (root, values)]
        else:
            self._forced = [(root, values)]
        self._install()

    def _parameters(
        self, owner: str, declared: tuple[Parameter, ...], given: Mapping[str, object], by_index: bool
    ) -> dict[str, Value]:
        """``given`` (qualified or short names) converted: qualified name -> engine value."""
        loaded = self._require()
        by_name = {p.name: p for p in declared}
        # the declared name: only the owner's prefix goes (dots kept: "robot.x" of "walk.to")
        by_name.update((short, p) for p in declared if (short := short_name(p.name, owner)) not in by_name)
        values: dict[str, Value] = {}
        for key, value in given.items():
            param = by_name.get(key)
            if param is None:
                raise DebugError(f"{owner} has no parameter {key}")
            enum = loaded.enum_values(param.enum)
            values[param.name] = coerce(param.kind, enum, value, name=f"parameter {param.name}", by_index=by_index)
        return values
