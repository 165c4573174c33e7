"""The errands robot: Dual Dynamics behaviors, a GRAPHPLAN plan and an XABSL plan monitor (dual-dynamics.md).

Modules: :mod:`.arena` (pymunk ground truth and raw sensors), :mod:`.facts` (fact rules, truth,
agreement), :mod:`.plan` (the host side of the plan: queue, replanning), :mod:`.world` (the
host contract: one tick of §4.1), :mod:`.run` (``xabsl run examples/errands``). The plan monitor
itself is ``behavior/execute_plan.xabsl``; the DD model is ``model/errands_dd.json``.
"""
