"""The Engine: symbol bindings, basic behaviors, tick, activation tree, debug interface (§2).

* :mod:`engine.runtime.bindings`   host registration (symbols, enums, BasicBehavior hooks)
* :mod:`engine.runtime.linker`     program + bindings -> storage layout, every missing name at once
* :mod:`engine.runtime.checks`     option-graph checks at load time (B1/B2 policy, §2.10)
* :mod:`engine.runtime.engine`     Engine: load, execute(now_ms), faults, hot reload
* :mod:`engine.runtime.storage`    a program bound to an engine: storage lists, generated functions
* :mod:`engine.runtime.roots`      RootActions: the selected agent, forced roots, input overrides
* :mod:`engine.runtime.values`     coerce: the one conversion of values given from outside
* :mod:`engine.runtime.activation` cheap per-tick snapshots and the activation tree
* :mod:`engine.runtime.debug`      Debugger: input values, explaining decisions
* :mod:`engine.runtime.coop`       cooperative states and team messages (§2.11)
* :mod:`engine.runtime.fault`      Fault (errors: :mod:`engine.errors`)

Import order is one way: engine -> roots -> storage -> activation/linker/bindings; debug -> engine.
"""

from engine.errors import DebugError, EngineError, LinkError, LoadError, ValueConversionError
from engine.runtime.activation import AssignmentNode, BehaviorNode, OptionNode, Root, Snapshot
from engine.runtime.bindings import BasicBehavior, Bindings
from engine.runtime.checks import Policy
from engine.runtime.debug import Debugger
from engine.runtime.engine import Engine
from engine.runtime.fault import Fault
from engine.runtime.roots import RootActions
from engine.runtime.values import EnumValues, coerce

__all__ = [
    "AssignmentNode",
    "BasicBehavior",
    "BehaviorNode",
    "Bindings",
    "DebugError",
    "Debugger",
    "Engine",
    "EngineError",
    "EnumValues",
    "Fault",
    "LinkError",
    "LoadError",
    "OptionNode",
    "Policy",
    "Root",
    "RootActions",
    "Snapshot",
    "ValueConversionError",
    "coerce",
]
