"""Fixtures for the studio server: example copies, a real uvicorn on a loopback port, ws clients.

Behavior folders are copied into ``tmp_path`` so that tests may edit, break and rename files.
:class:`LiveServer` runs uvicorn in a thread on a free port of 127.0.0.1; :class:`WsClient` is a
real websocket client (``websockets.sync``) that keeps the latest ``hello`` and merges frame
deltas, as the web UI does, so tests can assert on exact values.
"""

from __future__ import annotations

import contextlib
import gc
import shutil
import socket
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import orjson
import pytest
import uvicorn
from websockets.sync.client import ClientConnection, connect

from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.examples.soccer.studio import SoccerExample
from xabsl_studio.server.api.app import create_app
from xabsl_studio.server.api.listen import uvicorn_config
from xabsl_studio.server.api.security import SecurityPolicy
from xabsl_studio.server.protocol.packing import decode_hello
from xabsl_studio.server.session.live import Session

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def demo_dir(tmp_path: Path) -> Path:
    """A private copy of examples/demo."""
    target = tmp_path / "demo"
    shutil.copytree(REPO / "examples" / "demo", target)
    return target


@pytest.fixture
def soccer_dir(tmp_path: Path) -> Path:
    """A private copy of the soccer behavior folders (the world's code comes from the package)."""
    target = tmp_path / "soccer"
    target.mkdir()
    for name in ("behavior", "chase"):
        shutil.copytree(REPO / "examples" / "soccer" / name, target / name)
    return target


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class LiveServer:
    """A real uvicorn serving ``create_app(session, policy)`` on 127.0.0.1 in a thread."""

    def __init__(self, session: Session, policy: SecurityPolicy | None = None) -> None:
        self.session = session
        self.policy = policy or SecurityPolicy(token=None)
        self.app = create_app(session, self.policy, web_dist=None)
        self.port = free_port()
        config = uvicorn_config(self.app, "127.0.0.1", self.port)  # as `xabsl serve`
        self.server = uvicorn.Server(config)
        self.thread = threading.Thread(target=self.server.run, daemon=True)

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    @property
    def ws_url(self) -> str:
        return f"ws://127.0.0.1:{self.port}/ws"

    @property
    def studio(self) -> Any:
        return self.app.state.studio

    def __enter__(self) -> LiveServer:
        self.thread.start()
        deadline = time.monotonic() + 15
        while not self.server.started:
            if time.monotonic() > deadline or not self.thread.is_alive():
                raise RuntimeError("uvicorn did not start")
            time.sleep(0.02)
        return self

    def __exit__(self, *exc: object) -> None:
        self.server.should_exit = True
        self.thread.join(timeout=15)


class WsClient:
    """A websocket client that tracks hello, merged symbol values and replies."""

    def __init__(self, ws: ClientConnection) -> None:
        self.ws = ws
        self.hello: dict[str, Any] | None = None
        self.hellos: list[dict[str, Any]] = []
        self.frame: dict[str, Any] | None = None
        self.values: dict[int, dict[str, dict[str, Any]]] = {}
        self.replies: dict[Any, dict[str, Any]] = {}
        self.other: list[dict[str, Any]] = []
        self.frames = 0
        self.seqs: list[int] = []
        self.log: list[dict[str, Any]] = []
        self.sizes: list[int] = []
        self._ids = 0
        self._seen_hellos: set[int] = set()

    def receive(self, timeout: float = 10.0) -> dict[str, Any]:
        data = self.ws.recv(timeout=timeout)
        message = orjson.loads(data)
        kind = message["type"]
        if kind == "hello":
            message = decode_hello(message)  # a team-sized structure comes compressed
            self.hello = message
            self.hellos.append(message)
            self.values = {}
        elif kind == "frame":
            assert self.hello is not None, "a frame before any hello"
            assert message["gen"] == self.hello["generation"], "a frame of another generation than the hello"
            self.frame = message
            self.frames += 1
            self.seqs.append(message["seq"])
            self.log.append({k: message[k] for k in ("seq", "gen", "t", "full")})
            self.sizes.append(len(data))
            for robot in message["robots"]:
                values = self.values.setdefault(robot["id"], {"inputs": {}, "outputs": {}})
                for kind_ in ("inputs", "outputs"):
                    if message["full"] and kind_ in robot:
                        values[kind_] = {}
                    values[kind_].update(robot.get(kind_, {}))
        elif kind == "reply":
            self.replies[message["id"]] = message
        else:
            self.other.append(message)
        return message

    def until(self, predicate: Callable[[dict[str, Any]], bool], timeout: float = 10.0) -> dict[str, Any]:
        """Receive until ``predicate(message)``; returns that message."""
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("no matching message")
            message = self.receive(timeout=left)
            if predicate(message):
                return message

    def frame_after(
        self, predicate: Callable[[dict[str, Any]], bool] = lambda f: True, timeout: float = 10.0
    ) -> dict[str, Any]:
        return self.until(lambda m: m["type"] == "frame" and predicate(m), timeout)

    def wait_frame(self, predicate: Callable[[dict[str, Any]], bool], timeout: float = 10.0) -> dict[str, Any]:
        """The latest frame if it satisfies ``predicate`` (it may have come during a command), else the next."""
        if self.frame is not None and predicate(self.frame):
            return self.frame
        return self.frame_after(predicate, timeout)

    def wait_hello(self, reason: str, timeout: float = 10.0) -> dict[str, Any]:
        """The first hello with ``reason`` not returned yet (received already, or the next one)."""
        for i, hello in enumerate(self.hellos):
            if hello["reason"] == reason and i not in self._seen_hellos:
                self._seen_hellos.add(i)
                return hello
        hello = self.until(lambda m: m["type"] == "hello" and m["reason"] == reason, timeout)
        self._seen_hellos.add(len(self.hellos) - 1)
        return hello

    def send(self, message: dict[str, Any]) -> None:
        self.ws.send(orjson.dumps(message).decode())

    def command(self, op: str, timeout: float = 20.0, **args: Any) -> dict[str, Any]:
        """Send a command and wait for its reply (frames keep being merged meanwhile)."""
        self._ids += 1
        ident = self._ids
        self.send({"type": "command", "id": ident, "op": op, **args})
        return self.until(lambda m: m["type"] == "reply" and m["id"] == ident, timeout)

    def root(self, robot: int) -> list[Any]:
        """The root node of a robot's path in the latest frame."""
        assert self.frame is not None
        path = self.frame["robots"][robot]["path"]
        assert path, f"robot {robot} has an empty path"
        return path[0]

    def program(self, robot: int = 0) -> dict[str, Any]:
        assert self.hello is not None
        key = self.hello["structure"]["robots"][robot]["program"]
        return self.hello["structure"]["programs"][key]

    def option_id(self, name: str, robot: int = 0) -> int:
        return next(o["id"] for o in self.program(robot)["options"] if o["name"] == name)

    def state_id(self, option: str, state: str, robot: int = 0) -> int:
        o = next(o for o in self.program(robot)["options"] if o["name"] == option)
        return next(s["id"] for s in o["states"] if s["name"] == state)

    def symbol_id(self, kind: str, name: str, robot: int = 0) -> int:
        return next(s["id"] for s in self.program(robot)[kind] if s["name"] == name)


@pytest.fixture
def demo_session(demo_dir: Path) -> Iterator[Session]:
    session = Session(BenchExample(demo_dir), seed=3, speed=5.0)
    yield session
    session.stop()


@pytest.fixture
def live_demo(demo_session: Session) -> Iterator[LiveServer]:
    with LiveServer(demo_session) as server:
        yield server


@pytest.fixture
def soccer_session(soccer_dir: Path) -> Iterator[Session]:
    session = Session(SoccerExample(soccer_dir, players_per_team=2, half_duration_s=600), seed=5, speed=5.0)
    yield session
    session.stop()
    # pymunk spaces must be freed while the interpreter runs: collect the app's reference cycles now.
    del session
    gc.collect()


@pytest.fixture
def client_for() -> Iterator[Callable[..., WsClient]]:
    """``client_for(server, **connect_kwargs)`` opens a WsClient; all are closed at the end."""
    with contextlib.ExitStack() as stack:

        def open_client(server: LiveServer, path: str = "", **kwargs: Any) -> WsClient:
            ws = stack.enter_context(connect(server.ws_url + path, max_size=None, open_timeout=10, **kwargs))
            return WsClient(ws)

        yield open_client
