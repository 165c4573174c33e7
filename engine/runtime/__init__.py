"""The Engine: symbol bindings, basic behaviors, tick, activation tree, debug interface (§2).

* :mod:`engine.runtime.bindings`   host registration (symbols, enums, BasicBehavior hooks)
* :mod:`engine.runtime.linker`     program + bindings -> storage layout, every missing name at once
* :mod:`engine.runtime.checks`     option-graph checks at load time (B1/B2 policy, §2.10)
* :mod:`engine.runtime.engine`     Engine: load, execute(now_ms), faults, agents, hot reload
* :mod:`engine.runtime.storage`    a program bound to an engine: storage lists, generated functions
* :mod:`engine.runtime.activation` cheap per-tick snapshots and the activation tree
* :mod:`engine.runtime.debug`      forcing roots, overriding inputs, explaining decisions
* :mod:`engine.runtime.coop`       cooperative states and team messages (§2.11)
* :mod:`engine.runtime.errors`     LinkError, LoadError, Fault
"""

from engine.runtime.activation import AssignmentNode, BehaviorNode, OptionNode, Root, Snapshot
from engine.runtime.bindings import BasicBehavior, Bindings
from engine.runtime.checks import Policy
from engine.runtime.engine import Engine
from engine.runtime.errors import DebugError, EngineError, Fault, LinkError, LoadError

__all__ = [
    "AssignmentNode",
    "BasicBehavior",
    "BehaviorNode",
    "Bindings",
    "DebugError",
    "Engine",
    "EngineError",
    "Fault",
    "LinkError",
    "LoadError",
    "OptionNode",
    "Policy",
    "Root",
    "Snapshot",
]
