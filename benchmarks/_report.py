"""The run report the world benchmarks share: rates, simulated vs wall and CPU time, phase shares."""

from __future__ import annotations

import platform

from xabsl_studio.engine.host import RunStats


def print_run(
    title: str, stats: RunStats, cpu: float, physics_hz: int, behavior_hz: int, phases: list[tuple[str, float]]
) -> None:
    """Print how a headless run went; ``phases`` are (label, seconds) in the order to show."""
    print(f"{title}, python {platform.python_version()}")
    print(
        f"rates: physics {physics_hz} Hz, behavior {behavior_hz} Hz; "
        f"{stats.ticks} ticks, {stats.physics_steps} physics steps"
    )
    print(f"simulated {stats.sim_seconds:.1f} s in {stats.wall_seconds:.2f} s wall ({cpu:.2f} s cpu)")
    print(f"real-time factor: {stats.real_time_factor:.0f}x wall, {stats.sim_seconds / cpu:.0f}x cpu")
    total = stats.phases.total
    width = max(len(label) for label, _ in phases)
    for label, seconds in phases:
        print(f"  {label:<{width}} {seconds:6.2f} s  {100 * seconds / total if total else 0.0:5.1f} %")
