"""The errands robot of Hertzberg et al. (1998): Dual Dynamics behaviors biased by a GRAPHPLAN plan.

Watch for: with --plan the XABSL monitor runs the plan goto a c, load mug c, goto c b, load
book b, goto b a, then the two parallel unloads one after the other, each operator only biasing
the behaviors' activations (roam still avoids walls); the run ends when the derived facts say
both objects are at a (about a minute). With --no-plan the same behaviors roam and visit novel
beacons but never pick anything up. --perturb teleport-mug / remove-book / block-cb shows the
monitor replanning from derived facts, or failing with a reason.

Usage: ``xabsl run examples/errands [--plan|--no-plan] [--seed N] [--duration S] [--json]``.
Without ``--json`` it prints the plan, the operator timeline and how the derived facts compared
with the ground truth; with ``--json`` one line of JSON (``completed``, ``time_s``,
``fact_agreement``, ``operators`` and more).
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from xabsl_studio.engine.cli import UsageError, recording
from xabsl_studio.engine.files import write_atomically
from xabsl_studio.examples.errands.world import AGENTS_PATH, ErrandsWorld, build_world, physics_rate, run_world, summary

PERTURBATIONS = ("none", "teleport-mug", "remove-book", "block-cb")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The example's flags (hook of ``xabsl run``, see engine/cli/run.py)."""
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument(
        "--plan",
        dest="plan",
        action="store_true",
        default=True,
        help="execute the GRAPHPLAN plan with the XABSL monitor (default)",
    )
    mode.add_argument(
        "--no-plan",
        dest="plan",
        action="store_false",
        help="only the Dual Dynamics behaviors, no operator ever selected",
    )
    parser.add_argument("--seed", type=int, default=1, help="noise seed (default 1)")
    parser.add_argument(
        "--duration",
        type=float,
        default=None,
        metavar="S",
        help="simulated seconds at most (default 180 with a plan, 300 without)",
    )
    parser.add_argument("--dt", type=float, default=0.02, help="behavior tick in seconds (default 0.02)")
    parser.add_argument("--noise", type=float, default=1.0, help="multiplies the DD noise (0 = none)")
    recording.add_arguments(parser, "run")
    parser.add_argument(
        "--perturb",
        choices=PERTURBATIONS,
        default="none",
        help="teleport the mug from c to b during goto a c; remove the book at 10 s; wall between c and b",
    )
    parser.add_argument("--json", action="store_true", help="print one line of JSON")
    parser.add_argument("--render", metavar="FILE.dot", help="also write the plan monitor's option graph (DOT)")


def perturb(world: ErrandsWorld, kind: str) -> None:
    """Arm one of the named perturbations on ``world`` (they fire from a sense hook)."""
    if kind == "none":
        return
    if kind == "block-cb":
        world.block_path("c", "b")
        return
    fired = False

    def hook(w: ErrandsWorld) -> None:
        nonlocal fired
        if fired:
            return
        if kind == "teleport-mug" and w.operator == "goto a c" and w.t >= 5.0:
            w.teleport("mug", "b")
            fired = True
        elif kind == "remove-book" and w.t >= 10.0:
            w.remove("book")
            fired = True

    world.sense_hooks.append(hook)


def main(args: argparse.Namespace) -> int:
    """Run one errand headless and print its outcome (hook of ``xabsl run``)."""
    duration = args.duration if args.duration is not None else (180.0 if args.plan else 300.0)
    if duration <= 0:
        raise UsageError("--duration must be positive")
    try:
        world = build_world(args.seed, plan=args.plan, dt=args.dt, noise=args.noise)
    except ValueError as error:  # a bad model file (ModelError), a tick the stability check rejects, or
        raise UsageError(str(error)) from None  # one that does not divide 1 s
    except OSError as error:  # an unreadable model or PDDL file
        raise UsageError(f"{error.filename or ''}: {error.strerror or error}") from None
    perturb(world, args.perturb)
    assert world.engine is not None  # build_world compiles and attaches the monitor
    if args.render:
        from xabsl_studio.engine.emit.dot import option_graph, state_machine

        program = world.engine.program
        text = option_graph(program, "execute_plan") + "\n" + state_machine(program.options["execute_plan"])
        try:
            write_atomically(args.render, text.encode("utf-8"))
        except OSError as error:
            raise UsageError(f"cannot write {args.render}: {error.strerror or error}") from None
    recorder = None
    target = recording.target(args, [AGENTS_PATH], "errands")
    if target.path is not None:
        from xabsl_studio.engine.record import Recorder

        hz = physics_rate(world.dt)
        recorder = Recorder.for_world(
            target.path,
            world,
            lambda _: AGENTS_PATH.parent.name,
            example="errands",
            behavior_hz=hz[0],
            physics_hz=hz[1],
        )
    stats = run_world(world, duration, on_tick=recorder.on_tick if recorder is not None else None)
    if recorder is not None:
        recorder.close()
    target.finish()
    out = summary(world)
    out["real_time_factor"] = round(stats.real_time_factor, 1)
    if args.json:
        kept = str(target.path) if target.path is not None else None
        print(json.dumps({**out, "recording": kept}, ensure_ascii=False))
    else:
        print(_report(world, out))
        if target.path is not None:
            print(f"recorded to {target.path}" + ("" if args.record else " (--no-record: not recorded)"))
    if world.engine.fault is not None:
        print(f"behavior fault: {world.engine.fault}", file=sys.stderr)
        return 1
    return 0


def _report(world: ErrandsWorld, out: dict[str, Any]) -> str:
    lines = [
        f"errands robot, seed {world.seed}, {'with' if world.with_plan else 'without'} a plan"
        f" ({AGENTS_PATH.parent.name}/execute_plan.xabsl)"
    ]
    for event in world.board.events:
        lines.append(f"  {event.t:7.2f} s  plan {event.kind}: {event.detail}")
    for t, status, op, last in world.record.monitor:
        lines.append(f"  {t:7.2f} s  monitor {status:10s} {op or '-':16s} last failure: {last}")
    lines.append(
        f"completed: {out['completed']} at {out['time_s']} s; plan status {out['plan_status']}"
        + (f" ({out['reason']})" if out["reason"] else "")
    )
    lines.append(
        f"derived facts = truth on {100 * float(out['fact_agreement']):.1f}% of ticks, "
        f"{100 * float(out['fact_agreement_outside_lag']):.1f}% outside the 1.2 s lag windows"
    )
    lines.append(
        f"dominant-behavior switches {out['dominant_switches']}, roam dominant {100 * float(out['roam_share']):.0f}%"
        f", beacon arrivals {out['beacon_arrivals']} {out['beacons_visited']}, ever held {out['ever_held']}"
    )
    lines.append(f"{out['sim_s']} simulated seconds at {out['real_time_factor']}x real time")
    return "\n".join(lines)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(
        prog="python -m xabsl_studio.examples.errands.run", description=__doc__.split("\n\n")[0]
    )
    add_arguments(parser)
    try:
        sys.exit(main(parser.parse_args()))
    except UsageError as error:
        print(f"errands: {error}", file=sys.stderr)
        sys.exit(2)
