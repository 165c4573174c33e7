"""The language server on websockets: the studio's ``/lsp`` and ``xabsl lsp --ws``.

pygls' own websocket transport runs one server for every connection; here each accepted
connection gets a fresh :class:`~xabsl_studio.lsp.server.XabslLanguageServer`, one JSON-RPC message per
text frame each way (:func:`serve_connection`). Messages are handled one at a time per
connection in a small worker pool shared by every connection of the process
(:data:`~xabsl_studio.server.protocol.limits.MAX_LSP_WORKERS` threads), so a recheck never stalls the
event loop (the studio's frames keep streaming) and a storm of connections cannot make
threads; answers go back through a queue in order.

Limits (docs/security.md): a message over
:data:`~xabsl_studio.server.protocol.limits.MAX_LSP_MESSAGE_BYTES` closes with 1009, a binary frame with
1003, a client that lets more than :data:`~xabsl_studio.server.protocol.limits.MAX_LSP_PENDING` answers
pile up with 1008; the caller refuses connections over
:data:`~xabsl_studio.server.protocol.limits.MAX_LSP_CLIENTS` with 1013 (:class:`ConnectionCap`).

An ``exit`` notification closes this connection only: pygls would end the process, and the
process may be the studio.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import threading
from collections.abc import Awaitable, Callable, Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor

from xabsl_studio.lsp.rpc import handle_text
from xabsl_studio.lsp.server import create_server
from xabsl_studio.server.protocol.limits import (
    MAX_LSP_CLIENTS,
    MAX_LSP_MESSAGE_BYTES,
    MAX_LSP_PENDING,
    MAX_LSP_WORKERS,
    CloseCode,
)

logger = logging.getLogger("xabsl.lsp")

_pool: ThreadPoolExecutor | None = None
_pool_lock = threading.Lock()


def workers() -> ThreadPoolExecutor:
    """The worker pool every websocket connection of this process handles its messages in."""
    global _pool
    with _pool_lock:
        if _pool is None:
            _pool = ThreadPoolExecutor(max_workers=MAX_LSP_WORKERS, thread_name_prefix="xabsl-lsp")
        return _pool


class ConnectionCap:
    """How many language-server connections are open, against a limit (used on one event loop)."""

    def __init__(self, limit: int = MAX_LSP_CLIENTS) -> None:
        self.limit = limit
        self.open = 0

    def enter(self) -> bool:
        """Count one more connection; False (and nothing counted) when the limit is reached."""
        if self.open >= self.limit:
            return False
        self.open += 1
        return True

    def leave(self) -> None:
        """One connection ended."""
        self.open -= 1


class _QueueWriter:
    """pygls' writer interface onto an asyncio queue (safe to call from the worker thread)."""

    def __init__(self, loop: asyncio.AbstractEventLoop, queue: asyncio.Queue[str | None]) -> None:
        self.loop = loop
        self.queue = queue

    def write(self, data: bytes) -> None:
        self.loop.call_soon_threadsafe(self.queue.put_nowait, data.decode("utf-8"))

    def close(self) -> None:
        self.loop.call_soon_threadsafe(self.queue.put_nowait, None)


def too_big(text: str) -> bool:
    """Whether a message is over :data:`MAX_LSP_MESSAGE_BYTES` in UTF-8 (as the transport counts)."""
    if len(text) * 4 <= MAX_LSP_MESSAGE_BYTES:
        return False  # no text of this length can be larger
    return len(text) > MAX_LSP_MESSAGE_BYTES or len(text.encode("utf-8", "surrogatepass")) > MAX_LSP_MESSAGE_BYTES


async def serve_connection(
    receive: Callable[[], Awaitable[str | bytes | None]],
    send_text: Callable[[str], Awaitable[None]],
    close: Callable[[int], Awaitable[None]],
    *,
    roots: Iterable[str] | None = None,
    root: str | None = None,
    agents: str | None = None,
) -> None:
    """Speak the protocol on one accepted connection until the client goes away.

    Args:
        receive: the next frame: its text, bytes for a binary frame, None when the peer closed.
        send_text: sends one text frame.
        close: closes the connection with a code.
        roots: the only folders served (the studio's behavior folders); None: the client's
            workspace folders (``xabsl lsp --ws``).
        root: the folder the custom request ``xabsl/root`` answers.
        agents: the agents file of every document (``--agents``).
    """
    loop = asyncio.get_running_loop()
    queue: asyncio.Queue[str | None] = asyncio.Queue()
    server = create_server(agents=agents, root=root, roots=roots)
    server.protocol.set_writer(_QueueWriter(loop, queue), include_headers=False)
    pool = workers()

    async def pump() -> None:
        while (data := await queue.get()) is not None:
            await send_text(data)

    def handle(text: str) -> None:
        try:
            handle_text(server.protocol, text)
        except Exception as error:  # rpc.py answers what it can; a bad message must not end the connection
            logger.warning("language server: a message failed: %s: %s", type(error).__name__, error)

    sender = asyncio.create_task(pump())
    code: int | None = CloseCode.NORMAL
    try:
        while True:
            try:
                text = await receive()
            except Exception:  # the transport failed under us
                code = None
                break
            if text is None:
                code = None  # the peer closed
                break
            if not isinstance(text, str):
                code = CloseCode.UNSUPPORTED_DATA
                break
            if too_big(text):
                code = CloseCode.MESSAGE_TOO_BIG
                break
            if '"exit"' in text and _is_exit(text):
                break
            if queue.qsize() > MAX_LSP_PENDING:
                code = CloseCode.POLICY_VIOLATION  # it sends without reading the answers
                break
            await loop.run_in_executor(pool, handle, text)
    finally:
        queue.put_nowait(None)
        try:
            await asyncio.wait_for(sender, timeout=2)
        except Exception:  # the client is gone or slow: drop what is left
            sender.cancel()
        if code is not None:
            with contextlib.suppress(Exception):  # the peer may be gone already
                await close(code)


def _is_exit(text: str) -> bool:
    try:
        message = json.loads(text)
    except (ValueError, RecursionError):
        return False
    return isinstance(message, dict) and message.get("method") == "exit"


def serve_websocket(host: str, port: int, agents: str | None = None, origins: Sequence[str] = ()) -> None:
    """``xabsl lsp --ws``: serve websocket clients on ``host:port`` until interrupted.

    Each connection has its own language server (its own workspace folders). A handshake with
    an ``Origin`` header (a web page) is refused unless the origin is in ``origins``: any page
    open in a browser could otherwise connect to a loopback port.
    """
    with contextlib.suppress(KeyboardInterrupt):
        asyncio.run(_serve_websocket(host, port, agents, origins))


async def _serve_websocket(host: str, port: int, agents: str | None, origins: Sequence[str]) -> None:
    # websockets is only needed for this transport (pygls[ws]); imported when it is asked for.
    from websockets.asyncio.server import ServerConnection, serve
    from websockets.exceptions import ConnectionClosed

    cap = ConnectionCap()

    async def connection(ws: ServerConnection) -> None:
        if not cap.enter():
            await ws.close(CloseCode.TRY_AGAIN_LATER, "too many language server connections")
            return

        async def receive() -> str | bytes | None:
            try:
                return await ws.recv()
            except ConnectionClosed:
                return None

        async def close(code: int) -> None:
            await ws.close(code)

        try:
            await serve_connection(receive, ws.send, close, agents=agents)
        finally:
            cap.leave()

    allowed = [None, *origins]
    async with serve(connection, host, port, max_size=MAX_LSP_MESSAGE_BYTES, origins=allowed) as server:  # type: ignore[arg-type]
        await server.serve_forever()
