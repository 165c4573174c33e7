"""The team case: five robot processes (``examples/attach/robot.py``), each its own program and port.

``python -m xabsl_studio.examples.attach.team --port 7411`` starts robot1..robot5 on ports
7411..7415 (printing ``robotN pid PID port PORT`` for each) and waits;
``xabsl attach 127.0.0.1:7411 127.0.0.1:7412 ...`` debugs them in one studio session. Ctrl+C
stops them all.
"""

from __future__ import annotations

import argparse
import subprocess
import sys


def main(argv: list[str] | None = None) -> int:
    """Start the robots, print where they listen, wait until interrupted (or one ends)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--robots", type=int, default=5, help="how many robot processes (default 5)")
    parser.add_argument("--port", type=int, default=7411, help="the first robot's port (default 7411)")
    parser.add_argument("--hz", type=float, default=50.0, help="ticks per second of every robot")
    parser.add_argument("--token", default=None, help="token studios must present")
    parser.add_argument("--pausable", action="store_true", help="let studios pause and step the robots")
    args, rest = parser.parse_known_args(argv)
    processes = []
    for number in range(1, args.robots + 1):
        command = [
            sys.executable, "-m", "xabsl_studio.examples.attach.robot", "--name", f"robot{number}",
            "--port", str(args.port + number - 1), "--hz", str(args.hz), "--seed", str(number), *rest,
        ]  # fmt: skip
        if args.token:
            command += ["--token", args.token]
        if args.pausable:
            command.append("--pausable")
        processes.append(subprocess.Popen(command))
        # One line per robot: a tester (or a user) may stop one robot and start it again.
        print(f"robot{number} pid {processes[-1].pid} port {args.port + number - 1}", flush=True)
    addresses = " ".join(f"127.0.0.1:{args.port + i}" for i in range(args.robots))
    print(f"attach with: xabsl attach {addresses}", flush=True)
    try:
        while all(p.poll() is None for p in processes):
            try:
                processes[0].wait(timeout=0.5)
            except subprocess.TimeoutExpired:
                continue
    except KeyboardInterrupt:
        pass
    finally:
        for process in processes:
            process.terminate()
        for process in processes:
            process.wait(timeout=10)
    return 0


if __name__ == "__main__":
    sys.exit(main())
