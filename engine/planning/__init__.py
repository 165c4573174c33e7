"""The plan side of the errands example: STRIPS grounding, GRAPHPLAN, plan monitoring, facts.

See dual-dynamics.md §1.6 (facts from histories), §2 (GRAPHPLAN) and §4.1 (PlanLayer). Modules:

* :mod:`xabsl_studio.engine.planning.strips`     PDDL (via the MIT ``pddl`` package) -> grounded STRIPS task
* :mod:`xabsl_studio.engine.planning.graphplan`  planning graph, mutexes, extraction, layered plan + statistics
* :mod:`xabsl_studio.engine.planning.monitor`    the plan board a plan monitor reads: queue, done marks, replanning
* :mod:`xabsl_studio.engine.planning.facts`      table-driven history predicates -> derived facts + FactEvents

Nothing here knows about XABSL, pymunk or the Dual Dynamics behavior system; the errands world and
the XABSL plan monitor configure and drive these as plain data.
"""
