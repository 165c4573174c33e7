"""The Engine: symbol bindings, basic behaviors, tick, activation tree, debug interface (§2).

* :mod:`xabsl_studio.engine.runtime.bindings`   host registration (symbols, enums, BasicBehavior hooks)
* :mod:`xabsl_studio.engine.runtime.linker`     program + bindings -> storage layout, every missing name at once
* :mod:`xabsl_studio.engine.runtime.checks`     option-graph checks at load time (B1/B2 policy, §2.10)
* :mod:`xabsl_studio.engine.runtime.engine`     Engine: load, execute(now_ms), faults, hot reload
* :mod:`xabsl_studio.engine.runtime.storage`    a program bound to an engine: storage lists, generated functions
* :mod:`xabsl_studio.engine.runtime.roots`      RootActions: the selected agent, forced roots, input overrides
* :mod:`xabsl_studio.engine.runtime.values`     coerce: the one conversion of values given from outside
* :mod:`xabsl_studio.engine.runtime.activation` cheap per-tick snapshots and the activation tree
* :mod:`xabsl_studio.engine.runtime.debug`      Debugger: input values, explaining decisions
* :mod:`xabsl_studio.engine.runtime.coop`       cooperative states and team messages (§2.11)
* :mod:`xabsl_studio.engine.runtime.fault`      Fault (errors: :mod:`xabsl_studio.engine.errors`)

Import order is one way: engine -> roots -> storage -> activation/linker/bindings; debug -> engine.
"""

from xabsl_studio.engine.errors import DebugError, EngineError, LinkError, LoadError, ValueConversionError
from xabsl_studio.engine.runtime.activation import AssignmentNode, BehaviorNode, OptionNode, Root, Snapshot
from xabsl_studio.engine.runtime.bindings import BasicBehavior, Bindings
from xabsl_studio.engine.runtime.checks import Policy
from xabsl_studio.engine.runtime.debug import Debugger
from xabsl_studio.engine.runtime.engine import Engine
from xabsl_studio.engine.runtime.fault import Fault
from xabsl_studio.engine.runtime.roots import RootActions
from xabsl_studio.engine.runtime.values import EnumValues, coerce

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
