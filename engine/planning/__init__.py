"""The plan side of the errands example: STRIPS grounding, GRAPHPLAN, plan monitoring, facts.

See dual-dynamics.md §1.6 (facts from histories), §2 (GRAPHPLAN) and §4.1 (PlanLayer). Modules:

* :mod:`engine.planning.strips`     PDDL (via the MIT ``pddl`` package) -> grounded STRIPS task
* :mod:`engine.planning.graphplan`  planning graph, mutexes, extraction, layered plan + statistics
* :mod:`engine.planning.monitor`    the plan board an XABSL plan monitor reads: queue, done marks, replanning
* :mod:`engine.planning.facts`      table-driven history predicates -> derived facts + FactEvents

Nothing here knows about XABSL, pymunk or the Dual Dynamics behavior system; the errands world and
the XABSL plan monitor configure and drive these as plain data.
"""
