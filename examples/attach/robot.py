"""A robot process that runs the demo ball chaser on its own symbols and publishes every tick.

Not the studio's worker: a program of its own, as a team's robot program would be. It compiles
``examples/demo`` (or ``--behavior AGENTS_FILE``), binds the behavior's symbols and basic
behaviors to a small body of its own (a robot on a plane with one ball, a camera that sees
±60°, a game controller that starts the game after a second), ticks the engine at ``--hz`` and
calls ``link.publish()`` after every tick, so that ``xabsl attach 127.0.0.1:PORT`` can debug it::

    python -m xabsl_studio.examples.attach.robot --name robot1 --port 7410
    xabsl attach 127.0.0.1:7410

It prints one line when it listens (``robot1 listens on 127.0.0.1:7410``) and, at the end of
``--ticks`` ticks, one JSON line with what it did (ticks, studios, forced ticks).
"""

from __future__ import annotations

import argparse
import math
import signal
import sys
import time
from pathlib import Path

import orjson

from xabsl_studio.attach import serve_engines
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.runtime import BasicBehavior, Bindings, Engine
from xabsl_studio.engine.types import Kind

DEMO = Path(__file__).resolve().parent.parent / "demo" / "agents.xabsl"
GAME_STATES = ("init", "ready", "set", "playing", "finished")


class Body:
    """The robot's world: its pose, one ball, the clock (all this program's own state)."""

    def __init__(self, seed: int) -> None:
        self.x, self.y, self.heading = 0.0, 0.0, math.radians(90.0 * (seed % 4))
        self.ball_x, self.ball_y = 1500.0, 400.0 * ((seed % 3) - 1)
        self.speed = 0.0
        self.rate = 0.0
        self.now_ms = 0
        self.last_seen_ms = -10_000

    def ball(self) -> tuple[float, float]:
        """Distance (mm) and angle (deg, left positive) of the ball from the robot."""
        dx, dy = self.ball_x - self.x, self.ball_y - self.y
        angle = math.degrees(math.atan2(dy, dx) - self.heading)
        return math.hypot(dx, dy), (angle + 180.0) % 360.0 - 180.0

    def seen(self) -> bool:
        """Whether the camera sees the ball now."""
        return abs(self.ball()[1]) < 60.0

    def step(self, dt_ms: int) -> None:
        """Move by the commanded speed and turn rate for ``dt_ms``."""
        dt = dt_ms / 1000.0
        self.heading += math.radians(self.rate) * dt
        self.x += math.cos(self.heading) * self.speed * dt
        self.y += math.sin(self.heading) * self.speed * dt
        self.now_ms += dt_ms
        if self.seen():
            self.last_seen_ms = self.now_ms


def bind(body: Body) -> Bindings:
    """The demo's input symbols, input function and basic behaviors on ``body``."""
    bindings = Bindings()
    bindings.input("ball.seen", Kind.BOOLEAN, body.seen)
    bindings.input("ball.distance", Kind.DECIMAL, lambda: body.ball()[0])
    bindings.input("ball.angle", Kind.DECIMAL, lambda: body.ball()[1])
    bindings.input("ball.time_since_seen", Kind.DECIMAL, lambda: float(body.now_ms - body.last_seen_ms))
    bindings.enum("game.state", GAME_STATES)
    bindings.input("game.state", Kind.ENUM, lambda: 3 if body.now_ms >= 1000 else 1, enum="game.state")

    def clamp(value: float, lo: float, hi: float) -> float:
        return max(lo, min(hi, value))

    bindings.input(
        "clamp", Kind.DECIMAL, clamp, params=[("value", Kind.DECIMAL), ("lo", Kind.DECIMAL), ("hi", Kind.DECIMAL)]
    )

    class Stand(BasicBehavior):
        name = "stand"

        def execute(self) -> None:
            body.speed = body.rate = 0.0

    class Walk(BasicBehavior):
        name = "walk"
        parameters = (("speed", Kind.DECIMAL), ("direction", Kind.DECIMAL))

        def execute(self) -> None:
            body.speed = float(self.param("speed"))
            body.rate = max(-90.0, min(90.0, float(self.param("direction"))))

    class Turn(BasicBehavior):
        name = "turn"
        parameters = (("rate", Kind.DECIMAL),)

        def execute(self) -> None:
            body.speed, body.rate = 0.0, float(self.param("rate"))

    class Kick(BasicBehavior):
        name = "kick"
        parameters = (("strength", Kind.DECIMAL),)

        def execute(self) -> None:
            body.speed = body.rate = 0.0
            if self.time_of_execution == 0:  # the ball flies off; the robot has to find it again
                distance, _ = body.ball()
                if distance < 400:
                    body.ball_x += math.cos(body.heading) * 1200 * float(self.param("strength"))
                    body.ball_y += math.sin(body.heading) * 1200 * float(self.param("strength"))

    for behavior in (Stand, Walk, Turn, Kick):
        bindings.behavior(behavior)
    return bindings


def main(argv: list[str] | None = None) -> int:
    """Run the robot until ``--ticks`` ticks ran (0: until interrupted)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--name", default="robot1", help="the robot's name (default robot1)")
    parser.add_argument("--host", default="127.0.0.1", help="address to listen on (default loopback)")
    parser.add_argument("--port", type=int, default=7410, help="port (default 7410; 0 picks a free one)")
    parser.add_argument("--token", default=None, help="token studios must present")
    parser.add_argument("--hz", type=float, default=50.0, help="ticks per second (default 50)")
    parser.add_argument("--ticks", type=int, default=0, help="stop after this many ticks (default: run on)")
    parser.add_argument("--seed", type=int, default=1, help="where the robot and the ball start")
    parser.add_argument("--pausable", action="store_true", help="let studios pause and step this robot")
    parser.add_argument("--behavior", default=str(DEMO), help="the agents file to run (default: examples/demo)")
    args = parser.parse_args(argv)

    compilation = compile_file(args.behavior)
    if compilation.program is None:
        for diagnostic in compilation.errors:
            print(diagnostic.format(), file=sys.stderr)
        return 1
    body = Body(args.seed)
    engine = Engine(bind(body), compilation.program, agent_name=args.name)
    link = serve_engines(
        {args.name: engine}, port=args.port, host=args.host, token=args.token, name=args.name, pausable=args.pausable
    )
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    print(f"{args.name} listens on {link.address[0]}:{link.port}", flush=True)
    period_ms = round(1000 / args.hz)
    forced = 0
    try:
        next_due = time.perf_counter()
        while args.ticks <= 0 or link.ticks < args.ticks:
            engine.execute(body.now_ms)
            forced += bool(engine.root_actions.forced)
            link.publish()
            body.step(period_ms)
            next_due += period_ms / 1000.0
            delay = next_due - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
            else:
                next_due = time.perf_counter()
    except KeyboardInterrupt:
        pass
    finally:
        report = {"robot": args.name, "ticks": link.ticks, "forced_ticks": forced, **link.stats()}
        print(orjson.dumps(report).decode(), flush=True)
        link.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
