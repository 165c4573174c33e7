"""The attach host's cost on a robot program's tick: no studio, one studio attached (docs/attach.md).

A robot program (``examples/attach/robot.py``'s body and bindings, the demo ball chaser) ticks
its engine as fast as it can, three ways, interleaved in rounds so that machine noise hits all
alike:

* ``bare``: ``engine.execute`` and the body's step, no host library;
* ``none``: the same plus ``link.publish()`` with no studio attached;
* ``one``: the same with one studio attached (a peer in another process reading every tick).

Prints the mean microseconds per tick of each, the ratios ``none / bare`` and ``one / bare``,
and what the library adds per tick as a share of the tick period of a robot running at
``--hz`` (the issue's goal: one studio at most 10 % of a tick, none not measurable).

The demo's own tick is a few microseconds of compute (five inputs, three options), less than
sampling its symbols takes, so ``one / bare`` stays well above 1.1 for it; a robot's real tick
(perception, motion, a larger behavior) and its period are what the share is taken of.

    python benchmarks/attach_cost.py [--ticks 2000] [--rounds 30] [--hz 100]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

from xabsl_studio.attach import serve_engines
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.runtime import Engine
from xabsl_studio.examples.attach.robot import DEMO, Body, bind

PEER = """
import socket, sys, time
from xabsl_studio.server.protocol.attach import Attach, Heartbeat, encode_attach, encode_from_studio
sock = socket.create_connection(("127.0.0.1", int(sys.argv[1])))
sock.sendall(encode_attach(Attach(None, "bench", False)))
sock.settimeout(0.5)
beat = encode_from_studio(Heartbeat())
last = time.monotonic()
while True:
    try:
        if not sock.recv(1 << 20):
            break
    except TimeoutError:
        pass
    if time.monotonic() - last > 0.5:
        sock.sendall(beat)
        last = time.monotonic()
"""


def run(engine: Engine, body: Body, ticks: int, publish: object | None) -> float:
    started = time.perf_counter()
    for _ in range(ticks):
        engine.execute(body.now_ms)
        if publish is not None:
            publish()  # type: ignore[operator]
        body.step(10)
    return (time.perf_counter() - started) / ticks * 1e6


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--ticks", type=int, default=2_000)
    parser.add_argument("--rounds", type=int, default=30)
    parser.add_argument("--hz", type=float, default=100.0, help="the robot's tick rate, for the share of a period")
    args = parser.parse_args()
    program = compile_file(str(DEMO)).program
    assert program is not None
    bare_body, none_body, one_body = Body(1), Body(1), Body(1)
    bare = Engine(bind(bare_body), program)
    alone = Engine(bind(none_body), program)
    watched = Engine(bind(one_body), program)
    link_none = serve_engines({"robot1": alone}, port=0)
    link_one = serve_engines({"robot1": watched}, port=0)
    peer = subprocess.Popen(
        [sys.executable, "-c", PEER, str(link_one.port)], cwd=Path(__file__).resolve().parent.parent
    )
    try:
        while link_one.studios < 1:
            time.sleep(0.01)
        times: dict[str, list[float]] = {"bare": [], "none": [], "one": []}
        run(bare, bare_body, 2000, None)  # warm up
        for _ in range(args.rounds):
            times["bare"].append(run(bare, bare_body, args.ticks, None))
            times["none"].append(run(alone, none_body, args.ticks, link_none.publish))
            times["one"].append(run(watched, one_body, args.ticks, link_one.publish))
        best = {k: min(v) for k, v in times.items()}
        for name, value in best.items():
            print(f"{name:>5}: {value:8.2f} us/tick (best of {args.rounds} rounds of {args.ticks} ticks)")
        print(f"ratio none/bare: {best['none'] / best['bare']:.3f}")
        print(f"ratio one/bare:  {best['one'] / best['bare']:.3f}")
        period = 1e6 / args.hz
        added = best["one"] - best["bare"]
        print(f"one studio adds {added:.1f} us/tick: {100 * added / period:.2f} % of a {period / 1000:g} ms tick")
        stats = link_one.stats()["studios"][0]
        print(f"studio: {stats['sent']} messages sent, {stats['dropped']} ticks dropped")
    finally:
        peer.terminate()
        peer.wait()
        link_none.close()
        link_one.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
