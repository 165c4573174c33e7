"""The language server on a websocket another server already accepted (the studio's ``/lsp``).

pygls' own websocket transport runs its own server; the studio has one (FastAPI), so this
module connects a fresh :class:`~xabsl_studio.lsp.server.XabslLanguageServer` to an accepted connection: one
JSON-RPC message per text frame each way. Messages are handled one at a time in a worker
thread, so a recheck never stalls the studio's event loop (its frames keep streaming); answers
go back through a queue in order.

An ``exit`` notification closes this connection only: pygls would end the process, and the
process is the studio.
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import Awaitable, Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from xabsl_studio.lsp.server import create_server

logger = logging.getLogger(__name__)

#: largest message accepted from a client (a whole file's text in didOpen)
MAX_MESSAGE = 8 * 1024 * 1024


class _QueueWriter:
    """pygls' writer interface onto an asyncio queue (safe to call from the worker thread)."""

    def __init__(self, loop: asyncio.AbstractEventLoop, queue: asyncio.Queue[str | None]) -> None:
        self.loop = loop
        self.queue = queue

    def write(self, data: bytes) -> None:
        self.loop.call_soon_threadsafe(self.queue.put_nowait, data.decode("utf-8"))

    def close(self) -> None:
        self.loop.call_soon_threadsafe(self.queue.put_nowait, None)


async def serve_connection(
    receive_text: Callable[[], Awaitable[str]],
    send_text: Callable[[str], Awaitable[None]],
    root: Path | None = None,
) -> None:
    """Speak the protocol on one accepted connection until the client goes away.

    Args:
        receive_text: the next text frame (raises when the connection closed).
        send_text: sends one text frame.
        root: the behavior folder (the custom request ``xabsl/root`` answers its URI).
    """
    loop = asyncio.get_running_loop()
    queue: asyncio.Queue[str | None] = asyncio.Queue()
    server = create_server(root=str(root) if root else None)
    server.protocol.set_writer(_QueueWriter(loop, queue), include_headers=False)
    worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="xabsl-lsp")

    async def pump() -> None:
        while (data := await queue.get()) is not None:
            await send_text(data)

    sender = asyncio.create_task(pump())

    def handle(text: str) -> None:
        try:
            message = json.loads(text, object_hook=server.protocol.structure_message)
            server.protocol.handle_message(message)
        except Exception:  # a bad message must not end the connection
            logger.exception("language server: unable to handle a message")

    try:
        while True:
            try:
                text = await receive_text()
            except Exception:
                break
            if len(text) > MAX_MESSAGE:
                break
            if '"exit"' in text and _is_exit(text):
                break
            await loop.run_in_executor(worker, handle, text)
    finally:
        queue.put_nowait(None)
        try:
            await asyncio.wait_for(sender, timeout=2)
        except Exception:  # the client is gone or slow: drop what is left
            sender.cancel()
        worker.shutdown(wait=False)


def _is_exit(text: str) -> bool:
    try:
        message = json.loads(text)
    except ValueError:
        return False
    return isinstance(message, dict) and message.get("method") == "exit"
