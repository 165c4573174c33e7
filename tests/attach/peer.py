"""A studio's end of the attach protocol for tests: a plain blocking socket speaking the wire format.

What ``xabsl attach`` does too, without the session: the tests of the host library check what
arrives on the wire (every seq, the sample after a command) and can misbehave on purpose (stop
answering heartbeats, never read).
"""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from xabsl_studio.server.protocol.attach import (
    MAX_HOST_MESSAGE,
    Attach,
    Control,
    FrameReader,
    Heartbeat,
    HostGeneration,
    Refused,
    Welcome,
    decode_from_host,
    encode_attach,
    encode_from_studio,
)
from xabsl_studio.server.protocol.host import Sample, WorkerCommand, WorkerReply, WorkerRequest

REPO = Path(__file__).resolve().parents[2]


class Peer:
    """One connection to a host; ``received`` keeps every decoded message in order."""

    def __init__(self, port: int, token: str | None = None, studio: str = "test", control: bool = True) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=10)
        self.reader = FrameReader(MAX_HOST_MESSAGE)
        self.received: list[Any] = []
        self._ids = 0
        self.sock.sendall(encode_attach(Attach(token, studio, control)))

    def read(self, timeout: float = 5.0) -> list[Any]:
        """Whatever arrives within ``timeout`` (at least one message unless the host closed)."""
        self.sock.settimeout(timeout)
        while True:
            try:
                data = self.sock.recv(1 << 16)
            except TimeoutError:
                return []
            if not data:
                raise ConnectionError("the host closed the connection")
            messages = [decode_from_host(m) for m in self.reader.feed(data)]
            if messages:
                self.received.extend(messages)
                return messages

    def until(self, predicate: Any, timeout: float = 10.0) -> Any:
        """Read until a message satisfies ``predicate``; that message."""
        deadline = time.monotonic() + timeout
        for message in self.received:
            if predicate(message):
                return message
        while time.monotonic() < deadline:
            for message in self.read(max(0.05, deadline - time.monotonic())):
                if predicate(message):
                    return message
        raise AssertionError(f"nothing matched within {timeout} s; last: {self.received[-3:]}")

    def welcome(self) -> Welcome | Refused:
        return self.until(lambda m: isinstance(m, Welcome | Refused))  # type: ignore[no-any-return]

    def request(self, command: WorkerCommand, owner: str | None = "client1") -> int:
        self._ids += 1
        self.sock.sendall(encode_from_studio(WorkerRequest(self._ids, command, owner)))
        return self._ids

    def reply(self, ident: int, timeout: float = 10.0) -> WorkerReply:
        found: WorkerReply = self.until(lambda m: isinstance(m, WorkerReply) and m.ident == ident, timeout)
        return found

    def call(self, command: WorkerCommand, owner: str | None = "client1") -> WorkerReply:
        return self.reply(self.request(command, owner))

    def heartbeat(self) -> None:
        self.sock.sendall(encode_from_studio(Heartbeat()))

    def control(self, take: bool) -> None:
        self.sock.sendall(encode_from_studio(Control(take=take)))

    def samples(self) -> list[Sample]:
        return [m for m in self.received if isinstance(m, Sample)]

    def generations(self) -> list[HostGeneration]:
        return [m for m in self.received if isinstance(m, HostGeneration)]

    def close(self) -> None:
        self.sock.close()


def start_robot(*args: str) -> tuple[subprocess.Popen[str], int]:
    """``examples/attach/robot.py`` as its own process; it and the port it listens on."""
    process = subprocess.Popen(
        [sys.executable, "-m", "xabsl_studio.examples.attach.robot", "--port", "0", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=REPO,
    )
    assert process.stdout is not None
    line = process.stdout.readline()
    if " listens on " not in line:
        process.kill()
        raise RuntimeError(f"the robot did not start: {line}{process.stderr.read() if process.stderr else ''}")
    return process, int(line.rsplit(":", 1)[1])


def stop_robot(process: subprocess.Popen[str], wait: float = 0.0) -> str:
    """End the robot (after ``wait`` s for it to end by itself); what it printed after its first line."""
    try:
        process.wait(timeout=wait)
    except subprocess.TimeoutExpired:
        process.terminate()
    out, _ = process.communicate(timeout=10)
    return out
