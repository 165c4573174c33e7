"""Streaming load: the soccer example (10 agents) served to 20 websocket clients at 30 Hz.

Question: does the studio keep frames fresh and small, and what do clients cost the simulation?

The server runs as a real ``xabsl serve`` subprocess (so the clients' work does not share its
GIL); the clients are asyncio websocket connections in this process. Phases:

1. baseline: no client, ``--baseline`` seconds;
2. load: ``--clients`` clients subscribed at ``--rate`` Hz for ``--duration`` seconds.

Printed per phase, from the server's own counters (``/api/status`` timing): the real-time factor
(simulated / wall seconds), the simulation thread's cost per tick (tick + frame recording) and the
capacity it implies (how many times real time the thread could run). For the load phase: frame
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


def window(before: dict[str, Any], after: dict[str, Any], wall: float) -> dict[str, float]:
    t0, t1 = before["timing"], after["timing"]
    ticks = t1["ticks"] - t0["ticks"]
    busy = t1["busy_seconds"] - t0["busy_seconds"]
    framing = t1["frame_seconds"] - t0["frame_seconds"]
    tick_ms = 1000 * busy / ticks if ticks else float("nan")
    period_ms = 1000 / after["behavior_hz"]
    return {
        "rtf": (t1["sim_seconds"] - t0["sim_seconds"]) / wall,
        "tick_ms": tick_ms,
        "frame_ms": 1000 * framing / ticks if ticks else float("nan"),
        "capacity": period_ms / tick_ms if ticks else float("nan"),
        "ticks": ticks,
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
    parser.add_argument("--clients", type=int, default=20)
    parser.add_argument("--rate", type=float, default=30.0, help="frames per second per client")
    parser.add_argument("--speed", type=float, default=1.0, help="simulation speed (20: flat out)")
    parser.add_argument("--players", type=int, default=5, help="players per team (5: 10 agents)")
    args = parser.parse_args()

    port = free_port()
    command = [sys.executable, "-m", "engine.cli", "serve", str(REPO / "examples" / "soccer"), "--port", str(port),
               "--speed", str(args.speed), "--players", str(args.players)]
    server = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, cwd=REPO,
                              env={**os.environ, "PYTHONUNBUFFERED": "1"})
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
        time.sleep(2.0)
        agents = len(status(port)["world"].get("teams", [])) and args.players * 2
        print(f"soccer, {agents} agents, speed {args.speed:g}x; {args.clients} clients at {args.rate:g} Hz")

        before = status(port)
        started = time.monotonic()
        time.sleep(args.baseline)
        baseline = window(before, status(port), time.monotonic() - started)

        before = status(port)
        started = time.monotonic()
        group, wall = asyncio.run(load(port, args.clients, args.rate, args.duration))
        loaded = window(before, status(port), time.monotonic() - started)
        final = status(port)
    finally:
        server.terminate()
        server.wait(timeout=20)

    latencies = [x for c in group for x in c.latencies]
    deltas = [x for c in group for x in c.delta_sizes]
    fulls = [x for c in group for x in c.full_sizes]
    print(f"{'':24}{'no clients':>14}{'with clients':>14}")
    print(f"{'real-time factor':24}{baseline['rtf']:>14.3f}{loaded['rtf']:>14.3f}")
    print(f"{'sim thread ms/tick':24}{baseline['tick_ms']:>14.3f}{loaded['tick_ms']:>14.3f}")
    print(f"{'  of which frames':24}{baseline['frame_ms']:>14.3f}{loaded['frame_ms']:>14.3f}")
    print(f"{'capacity (x real time)':24}{baseline['capacity']:>14.2f}{loaded['capacity']:>14.2f}")
    cost = loaded["tick_ms"] / baseline["tick_ms"] - 1.0
    print(f"clients cost the simulation {100 * cost:+.1f} % per tick (goal < 10 %)")
    print(f"frame latency tick -> client: median {statistics.median(latencies):.1f} ms, "
          f"p99 {percentile(latencies, 99):.1f} ms, max {max(latencies):.1f} ms (goal p99 < 50 ms)")
    print(f"bytes per frame: delta median {statistics.median(deltas):.0f}, mean {statistics.mean(deltas):.0f}, "
          f"p99 {percentile(deltas, 99):.0f}; full {statistics.median(fulls) if fulls else float('nan'):.0f} "
          f"(goal < 4096)")
    per_client = [c.frames / wall for c in group]
    print(f"frames per client per second: median {statistics.median(per_client):.1f} (asked {args.rate:g})")
    print(f"ring buffer: {final['ring']['frames']} frames, {final['ring']['bytes'] / 1e6:.1f} MB "
          f"({final['ring']['seconds']} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
