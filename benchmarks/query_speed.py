"""How fast does a query answer over a 10-minute 10-robot recording? The goal is under 1 s.

Records a 5 vs 5 soccer match (``xabsl run examples/soccer --duration 600 --players 5 --record``;
skipped with ``--file``), then for each query times:

* **cold**: ``query_recording(path, condition)`` as ``xabsl query`` runs it: check the condition,
  read the columns it needs from the file (the columns the recording stores; for a query that
  calls an input function, a scan of the messages), evaluate; the figure the goal is about;
* **cold, scanned**: the same with the stored columns ignored: every tick message parsed (forked
  workers over tick ranges, one per core), what a recording without them costs;
* **cold, scanned in one pass**: that scan in a single pass (the baseline: one core, or a caller
  with threads), and the ratios;
* **warm**: ``QueryIndex.query`` on an index that already holds those columns (what the studio
  and a long-lived tool keep in memory): evaluation only;
* **brute force**: the same condition evaluated tick by tick, robot by robot, in plain Python over
  the reader's decoded ``TickView`` s (``Recording.ticks()``), the obvious way to do it.

Prints wall and CPU times (the machine is shared: CPU time is what this process and its workers used), the ratio
brute force / warm and brute force / cold, and whether both answered the same ticks. Brute force
over the whole match takes minutes; ``--brute-ticks N`` times it over the first N ticks and scales
the figure up (said so in the output).

    .venv/bin/python benchmarks/query_speed.py [--seconds 600] [--file match.mcap] [--brute-ticks 3000] [--query Q]

Never run from the test suite.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any
from unittest.mock import patch

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from xabsl_studio.engine import ir  # noqa: E402
from xabsl_studio.engine.query import QueryIndex, Selection, query_recording, scan  # noqa: E402
from xabsl_studio.engine.query.language import CompiledQuery, compile_query  # noqa: E402
from xabsl_studio.engine.record import AgentTick, Recording, stored  # noqa: E402

QUERIES = (
    "striker.state == shoot && ball.distance > 500",
    "ball.distance < 300 && game.state == playing",
    "kick.active || dribble.active",
    "go_to_position.active && go_to_position.x > 1000 && team.role == supporter",
    "team.rank(time = team.time_to_ball) == 0 && ball.seen",
)


class BruteForce:
    """A per-tick, per-robot evaluator of a checked query over one ``AgentTick`` (None: unknown)."""

    def __init__(self, query: CompiledQuery, agent: AgentTick, decimals: int) -> None:
        self.query = query
        self.agent = agent
        self.values = {**agent.inputs, **agent.outputs}
        description = agent.program.description
        self.options = {o["name"]: o for o in description["options"]}
        self.behaviors = {b["name"]: b for b in description["behaviors"]}
        self.inputs = {s["name"]: s for s in description["inputs"]}
        self.scale = 10.0**decimals

    def node(self, kind: int, ident: int) -> list[Any] | None:
        return next((n for n in self.agent.path if n[0] == kind and n[2] == ident), None)

    def predicate(self, name: str) -> Any:
        p = self.query.predicates[name]
        if p.kind.startswith("behavior"):
            node = self.node(1, self.behaviors[p.target]["id"])
            if p.kind == "behavior_active":
                return node is not None
            return None if node is None or p.position >= len(node[4]) else node[4][p.position]
        option = self.options[p.target]
        node = self.node(0, option["id"])
        if p.kind == "active":
            return node is not None
        if p.kind in ("state", "decided_in"):
            if node is None:
                return ""
            return f"{option['name']}.state.{option['states'][node[3] if p.kind == 'state' else node[6]]['name']}"
        if node is None:
            return None
        index = {"leaf": 7, "option_time": 4, "state_time": 5}.get(p.kind)
        if index is not None:
            return node[index]
        return node[8][p.position] if p.position < len(node[8]) else None

    def call(self, node: ir.InputRef) -> Any:
        if self.agent.reads is None:
            return None
        symbol = self.inputs[node.symbol]
        given = {a.param: self(a.value) for a in node.args}
        args = [given.get(p["name"], 0.0) for p in symbol["params"]]
        if any(a is None for a in args):
            return None
        wanted = [round(float(a) * self.scale) / self.scale for a in args]
        results = {
            e[-1]
            for e in self.agent.reads
            if isinstance(e, list)
            and e[:1] == [symbol["id"]]
            and len(e) == len(args) + 2
            and [round(float(x) * self.scale) / self.scale for x in e[1:-1]] == wanted
        }
        return results.pop() if len(results) == 1 else None

    def __call__(self, e: ir.Expression) -> Any:
        match e:
            case ir.Number(value=v) | ir.Constant(value=v) | ir.BooleanLiteral(value=v):
                return v
            case ir.EnumLiteral(element=element):
                return element
            case ir.InputRef(symbol=s) if s in self.query.predicates:
                return self.predicate(s)
            case ir.InputRef(symbol=s) if s in self.query.functions:
                return self.call(e)
            case ir.InputRef(symbol=s) | ir.OutputRef(symbol=s):
                return self.values.get(s)
            case ir.Unary(op=op, operand=operand):
                v = self(operand)
                return None if v is None else (not v if op == "!" else -v)
            case ir.Logical(op=op, operands=operands):
                values = [self(o) for o in operands]
                deciding = op == "||"
                if any(v is not None and bool(v) == deciding for v in values):
                    return deciding
                return None if any(v is None for v in values) else not deciding
            case ir.Conditional(condition=c, then=a, otherwise=b):
                chosen = self(c)
                return None if chosen is None else self(a if chosen else b)
            case ir.Binary(op=op, left=left, right=right):
                x, y = self(left), self(right)
                if x is None or y is None:
                    return None
                op = op.removeprefix("enum")
                table = {
                    "==": lambda: x == y,
                    "!=": lambda: x != y,
                    "<": lambda: x < y,
                    "<=": lambda: x <= y,
                    ">": lambda: x > y,
                    ">=": lambda: x >= y,
                    "+": lambda: x + y,
                    "-": lambda: x - y,
                    "*": lambda: x * y,
                    "/": lambda: x / (y if y != 0 else 1e-7),
                }
                return table[op]()
        raise AssertionError(f"the benchmark's evaluator has no {type(e).__name__}")


def brute_force(path: Path, condition: str, stop: int | None) -> tuple[int, int]:
    """(matching robot ticks, robot ticks evaluated) over ticks ``0 .. stop - 1``."""
    matched = evaluated = 0
    compiled: dict[tuple[str, int], CompiledQuery] = {}
    with Recording(path) as recording:
        decimals = int(recording.header["decimals"])
        for view in recording.ticks(0, stop):
            for agent in view.agents.values():
                key = (agent.program.key, agent.gen)
                query = compiled.get(key)
                if query is None:
                    query = compiled[key] = compile_query(agent.program.description, condition)
                if query.expression is None:
                    continue
                evaluated += 1
                matched += BruteForce(query, agent, decimals)(query.expression) is True
    return matched, evaluated


def _cpu() -> float:
    """CPU seconds of this process and of its children that ended (the query's workers)."""
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + children.ru_utime + children.ru_stime


def timed(function: Any) -> tuple[Any, float, float]:
    """(result, wall s, cpu s) of calling ``function``."""
    wall, cpu = time.perf_counter(), _cpu()
    result = function()
    return result, time.perf_counter() - wall, _cpu() - cpu


def scanned(path: Path, condition: str, workers: int | None = None) -> Any:
    """``query_recording`` scanning the tick messages (the stored columns ignored), in ``workers`` processes."""
    with patch.object(scan, "stored_columns", lambda *_args: None):
        if workers is None:
            return query_recording(path, condition)
        with patch.object(scan, "_workers", lambda _ticks: workers):
            return query_recording(path, condition)


def main() -> int:
    """Record (unless given a file), then time every query cold, warm and by brute force."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=600.0, help="simulated seconds to record")
    parser.add_argument("--file", default=None, help="an existing recording (skips recording)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--brute-ticks", type=int, default=None, help="brute force over the first N ticks only")
    parser.add_argument("--warm-runs", type=int, default=5, help="warm queries to time (best is printed)")
    parser.add_argument("--query", action="append", help="a query to time (repeatable; default: five of soccer)")
    args = parser.parse_args()
    path = Path(args.file) if args.file else Path(tempfile.mkdtemp(prefix="query-speed-")) / "match.mcap"
    if not args.file:
        started = time.perf_counter()
        command = [sys.executable, "-m", "xabsl_studio.engine.cli", "run", "examples/soccer", "--players", "5"]
        command += ["--duration", f"{args.seconds:g}", "--seed", str(args.seed), "--record", str(path)]
        subprocess.run(command, cwd=ROOT, env=dict(os.environ, PYTHONPATH=str(ROOT)), check=True, capture_output=True)
        print(f"recorded {args.seconds:g} s of 5 v 5 in {time.perf_counter() - started:.1f} s")
    with Recording(path) as recording:
        ticks, robots = len(recording), len(recording.agents)
        # an index that holds no column yet: each query below reads what it needs into it once
        index = QueryIndex.from_recording(recording, recording.agents, selection=Selection.nothing())
        parts = len(recording.attachments(stored.NAME, stored.MEDIA_TYPE))
    print(f"{path}: {ticks} ticks, {robots} robots, {path.stat().st_size / 1e6:.1f} MB (load {os.getloadavg()[0]:.1f})")
    print(f"  stored columns: {parts} parts" if parts else "  no stored columns (an older recording): scanned")
    for condition in args.query or QUERIES:
        cold, cold_wall, cold_cpu = timed(lambda c=condition: query_recording(path, c))
        parallel, parallel_wall, parallel_cpu = timed(lambda c=condition: scanned(path, c))
        single, single_wall, single_cpu = timed(lambda c=condition: scanned(path, c, workers=1))
        assert single == cold == parallel
        index.query(condition)  # reads the columns this query needs into the index
        warm_wall = warm_cpu = float("inf")
        warm = None
        for _ in range(args.warm_runs):
            warm, wall, cpu = timed(lambda c=condition: index.query(c))
            warm_wall, warm_cpu = min(warm_wall, wall), min(warm_cpu, cpu)
        assert warm is not None and warm.intervals == cold.intervals
        stop = args.brute_ticks
        (matched, evaluated), brute_wall, brute_cpu = timed(lambda c=condition, s=stop: brute_force(path, c, s))
        whole = stop is None or stop >= ticks
        scale = 1.0 if whole else ticks / stop  # type: ignore[operator]
        same = "(partial run, not compared)"
        if whole:
            same = "yes" if (matched, evaluated) == (cold.matched, cold.ticks) else f"NO: {matched} vs {cold.matched}"
        print(f"\n{condition}\n  {len(cold.intervals)} intervals, {cold.matched} of {cold.ticks} robot ticks")
        print(f"  cold  (read + evaluate): {cold_wall:7.3f} s wall {cold_cpu:7.3f} s cpu   goal < 1 s")
        print(
            f"  cold, scanned          : {parallel_wall:7.3f} s wall {parallel_cpu:7.3f} s cpu   "
            f"stored columns {parallel_wall / max(cold_wall, 1e-9):.1f}x faster"
        )
        print(
            f"  cold, scanned, one pass: {single_wall:7.3f} s wall {single_cpu:7.3f} s cpu   "
            f"parallel scan {single_wall / max(parallel_wall, 1e-9):.2f}x faster ({os.cpu_count()} cores)"
        )
        print(f"  warm  (evaluate)       : {warm_wall:7.3f} s wall {warm_cpu:7.3f} s cpu")
        extrapolated = f" (first {stop} ticks x {scale:.1f})" if scale != 1.0 else ""
        print(
            f"  brute force per tick   : {brute_wall * scale:7.3f} s wall {brute_cpu * scale:7.3f} s cpu{extrapolated}"
        )
        print(
            f"  ratio brute/warm {brute_cpu * scale / max(warm_cpu, 1e-9):7.0f}x cpu, "
            f"brute/cold {brute_cpu * scale / max(cold_cpu, 1e-9):5.1f}x cpu; same answer: {same}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
