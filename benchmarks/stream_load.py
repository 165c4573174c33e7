"""Streaming load: the soccer example (10 agents) served to 20 websocket clients at 30 Hz.

Question: does the studio keep frames fresh and small, and what do clients cost the simulation?

The server runs as a real ``xabsl serve`` subprocess (so the clients' work does not share its
GIL), which runs the simulation in a process of its own (docs/server.md); the clients are
asyncio websocket connections in this process. Phases:

``--rounds`` load phases (``--clients`` clients subscribed at ``--rate`` Hz, ``--duration``
seconds in all), each between two phases without clients (``--baseline`` seconds in all), after
``--warmup`` seconds. The tick cost drifts with the match (kick-off, then play), so each load
phase is compared with the phases without clients around it, not with one baseline at the start.

Printed per phase, from the simulation process's own counters (``/api/status`` timing): the
real-time factor (simulated / wall seconds), its cost per tick (engines + physics + sampling the
tick for the server) in wall time and in CPU time of the simulation thread (wall time also counts
time the OS gave the core to another process; with fewer cores than busy processes -- server,
simulation, this benchmark's clients -- the two differ), and the capacity it implies (how many
times real time the simulation could run). The server process's cost of turning samples into
ring entries (masks, deltas, key frames) is printed too: it no longer counts against the
simulation. For the load phase: frame
latency from the tick (the frame's ``wall`` stamp, server clock) to its receipt by a client
(median, p99; same machine, same clock), bytes per frame (delta frames and full frames), frames
received per client per second. ``--speed 20`` runs the simulation flat out, which turns the
real-time factor itself into the capacity measure.

Goals (docs/protocol.md, the issue): p99 latency < 50 ms, frames < 4 KB for 10 agents, clients
cost the simulation < 10 %.

    .venv/bin/python benchmarks/stream_load.py --duration 60
"""

from __future__ import annotations

import argparse
import asyncio
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import httpx2 as httpx
import orjson
import websockets

REPO = Path(__file__).resolve().parents[1]


def free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def status(port: int) -> dict[str, Any]:
    return httpx.get(f"http://127.0.0.1:{port}/api/status", timeout=10).json()


def counters(before: dict[str, Any], after: dict[str, Any], wall: float) -> dict[str, float]:
    """The simulation's and the server's counters over one window (differences of two statuses)."""
    t0, t1 = before["timing"], after["timing"]
    pipe0, pipe1 = before.get("simulation", {}).get("pipe", {}), after.get("simulation", {}).get("pipe", {})
    nan = float("nan")  # a counter an older server (simulation in a thread) does not have
    return {
        "wall": wall,
        "ticks": t1["ticks"] - t0["ticks"],
        "busy": t1["busy_seconds"] - t0["busy_seconds"],
        "cpu": t1.get("cpu_seconds", nan) - t0.get("cpu_seconds", nan),
        "sampling": t1["frame_seconds"] - t0["frame_seconds"],
        "sim": t1["sim_seconds"] - t0["sim_seconds"],
        "recorded": after["ring"].get("recorded", nan) - before["ring"].get("recorded", nan),
        "recording": after["ring"].get("record_seconds", nan) - before["ring"].get("record_seconds", nan),
        "dropped": pipe1.get("dropped", 0) - pipe0.get("dropped", 0),
    }


def summary(windows: list[dict[str, float]], behavior_hz: int) -> dict[str, float]:
    """Per-tick figures of several windows taken together."""
    total = {key: sum(w[key] for w in windows) for key in windows[0]}
    ticks = total["ticks"] or float("nan")
    period_ms = 1000 / behavior_hz
    return {
        "rtf": total["sim"] / total["wall"],
        "tick_ms": 1000 * total["busy"] / ticks,
        "cpu_ms": 1000 * total["cpu"] / ticks,
        "frame_ms": 1000 * total["sampling"] / ticks,
        "frame_share": total["sampling"] / total["busy"] if total["busy"] else float("nan"),
        "capacity": period_ms / (1000 * total["busy"] / ticks),
        "cpu_capacity": period_ms / (1000 * total["cpu"] / ticks),
        "record_ms": 1000 * total["recording"] / total["recorded"] if total["recorded"] else float("nan"),
        # (nan when every window lacks a counter)
        "dropped": total["dropped"],
    }


class Client:
    def __init__(self) -> None:
        self.latencies: list[float] = []
        self.delta_sizes: list[int] = []
        self.full_sizes: list[int] = []
        self.frames = 0
        self.gaps = 0
        self.last_seq: int | None = None

    async def run(self, url: str, rate: float, stop: asyncio.Event) -> None:
        async with websockets.connect(url, max_size=None, compression=None) as ws:
            await ws.send(orjson.dumps({"type": "subscribe", "rate": rate}).decode())
            while not stop.is_set():
                try:
                    data = await asyncio.wait_for(ws.recv(), timeout=0.5)
                except TimeoutError:
                    continue
                received = time.time() * 1000.0
                raw = data.encode() if isinstance(data, str) else data
                if not raw.startswith(b'{"type":"frame"'):
                    continue
                # Only the stamps are needed: find them without decoding the whole frame.
                start = raw.index(b'"wall":') + 7
                wall = float(raw[start : raw.index(b",", start)])
                full = b'"full":true' in raw[:160]
                self.latencies.append(received - wall)
                (self.full_sizes if full else self.delta_sizes).append(len(raw))
                self.frames += 1


async def load(port: int, clients: int, rate: float, duration: float) -> tuple[list[Client], float]:
    stop = asyncio.Event()
    group = [Client() for _ in range(clients)]
    tasks = [asyncio.create_task(c.run(f"ws://127.0.0.1:{port}/ws", rate, stop)) for c in group]
    await asyncio.sleep(2.0)  # connected, first full frames received
    for c in group:
        c.latencies.clear()
        c.delta_sizes.clear()
        c.frames = 0
    started = time.monotonic()
    await asyncio.sleep(duration)
    stop.set()
    wall = time.monotonic() - started
    await asyncio.gather(*tasks, return_exceptions=True)
    return group, wall


def percentile(values: list[float], p: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(p / 100 * len(ordered)))] if ordered else float("nan")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=60.0, help="seconds with clients (default 60)")
    parser.add_argument("--baseline", type=float, default=15.0, help="seconds without clients (default 15)")
    parser.add_argument(
        "--rounds", type=int, default=3, help="load phases, each between two phases without clients (default 3)"
    )
    parser.add_argument("--warmup", type=float, default=5.0, help="seconds before measuring (default 5)")
    parser.add_argument("--clients", type=int, default=20)
    parser.add_argument("--rate", type=float, default=30.0, help="frames per second per client")
    parser.add_argument("--speed", type=float, default=1.0, help="simulation speed (20: flat out)")
    parser.add_argument("--players", type=int, default=5, help="players per team (5: 10 agents)")
    args = parser.parse_args()

    port = free_port()
    command = [
        sys.executable,
        "-m",
        "xabsl_studio.engine.cli",
        "serve",
        str(REPO / "examples" / "soccer"),
        "--port",
        str(port),
        "--speed",
        str(args.speed),
        "--robots",
        str(args.players),
    ]
    server = subprocess.Popen(
        command,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        cwd=REPO,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    idle: list[dict[str, float]] = []
    loaded: list[dict[str, float]] = []
    groups: list[tuple[list[Client], float]] = []
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                status(port)
                break
            except httpx.TransportError:
                if server.poll() is not None or time.monotonic() > deadline:
                    print(server.stderr.read().decode() if server.stderr else "", file=sys.stderr)
                    return 1
                time.sleep(0.3)
        time.sleep(args.warmup)
        first = status(port)
        behavior_hz = first["behavior_hz"]
        agents = len(first["world"].get("teams", [])) and args.players * 2
        print(
            f"soccer, {agents} agents, speed {args.speed:g}x; {args.clients} clients at {args.rate:g} Hz; "
            f"{args.rounds} load phases of {args.duration / args.rounds:g} s between phases without clients"
        )

        def idle_phase(seconds: float) -> None:
            before, started = status(port), time.monotonic()
            time.sleep(seconds)
            idle.append(counters(before, status(port), time.monotonic() - started))

        for _ in range(args.rounds):
            idle_phase(args.baseline / (args.rounds + 1))
            before, started = status(port), time.monotonic()
            group, wall = asyncio.run(load(port, args.clients, args.rate, args.duration / args.rounds))
            loaded.append(counters(before, status(port), time.monotonic() - started))
            groups.append((group, wall))
        idle_phase(args.baseline / (args.rounds + 1))
        final = status(port)
    finally:
        server.terminate()
        server.wait(timeout=20)

    # The tick cost drifts with the match (kick-off, play, ...): compare each load phase with the
    # phases without clients right before and after it, not with one baseline at the start.
    baseline, with_clients = summary(idle, behavior_hz), summary(loaded, behavior_hz)
    rows = [
        ("real-time factor", "rtf", 3),
        ("simulation ms/tick (wall)", "tick_ms", 3),
        ("simulation ms/tick (CPU)", "cpu_ms", 3),
        ("  of which sampling", "frame_ms", 3),
        ("  sampling / tick (ratio)", "frame_share", 2),
        ("capacity (x real time)", "capacity", 2),
        ("  from CPU time", "cpu_capacity", 2),
        ("server ms/sample (ring)", "record_ms", 3),
        ("samples dropped", "dropped", 0),
    ]
    print(f"{'':28}{'no clients':>14}{'with clients':>14}")
    for label, key, digits in rows:
        print(f"{label:28}{baseline[key]:>14.{digits}f}{with_clients[key]:>14.{digits}f}")
    costs = []
    for k, window in enumerate(loaded):
        around = summary([idle[k], idle[k + 1]], behavior_hz)["tick_ms"]
        costs.append(summary([window], behavior_hz)["tick_ms"] / around - 1.0)
    cost = sum(costs) / len(costs)
    print(
        f"clients cost the simulation {100 * cost:+.1f} % per tick (goal < 10 %; per load phase, against the "
        f"phases around it: {', '.join(f'{100 * c:+.1f} %' for c in costs)})"
    )
    clients = [c for group, _ in groups for c in group]
    latencies = [x for c in clients for x in c.latencies]
    deltas = [x for c in clients for x in c.delta_sizes]
    fulls = [x for c in clients for x in c.full_sizes]
    print(
        f"frame latency tick -> client: median {statistics.median(latencies):.1f} ms, "
        f"p99 {percentile(latencies, 99):.1f} ms, max {max(latencies):.1f} ms (goal p99 < 50 ms)"
    )
    print(
        f"bytes per frame: delta median {statistics.median(deltas):.0f}, mean {statistics.mean(deltas):.0f}, "
        f"p99 {percentile(deltas, 99):.0f}; full {statistics.median(fulls) if fulls else float('nan'):.0f} "
        f"(goal < 4096)"
    )
    per_client = [c.frames / wall for group, wall in groups for c in group]
    print(f"frames per client per second: median {statistics.median(per_client):.1f} (asked {args.rate:g})")
    print(
        f"ring buffer: {final['ring']['frames']} frames, {final['ring']['bytes'] / 1e6:.1f} MB "
        f"({final['ring']['seconds']} s)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
