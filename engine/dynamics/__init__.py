"""Dual Dynamics behavior systems (numpy), after Jaeger & Christaller and Hertzberg et al. (doc §1).

* :mod:`xabsl_studio.engine.dynamics.expr`    the safe expression language of model files
* :mod:`xabsl_studio.engine.dynamics.model`   the JSON model format: validation, stability check, compilation
* :mod:`xabsl_studio.engine.dynamics.system`  the running system: synchronous Euler(-Maruyama) tick, OCTs,
  switch variables, per-tick debug records

Nothing here imports pymunk, XABSL or the planner: the plan side reaches a DD system only through
:meth:`~xabsl_studio.engine.dynamics.system.DDSystem.set_current_operator` (σ_OP) and reads it back through
:meth:`~xabsl_studio.engine.dynamics.system.DDSystem.signals`.
"""
