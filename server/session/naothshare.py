"""A NaoTH robot's single debug slot shared: other clients reach the robot through this studio.

A NaoTH robot serves its debug port to one client at a time. ``xabsl attach naoth://ROBOT --share
PORT`` makes the attached studio serve the same wire on ``PORT`` (loopback): other studios
(``xabsl attach naoth://127.0.0.1:PORT``) and RobotControl connect there, and each command is
carried out over this studio's connection to the robot, the answer sent back under the client's
own id. The robot sees one client, whose heartbeat this studio keeps; the clients' heartbeats end
here.

* Commands of one client are carried out in the order they came, one at a time; several clients'
  commands interleave with this studio's own questions.
* A client's ``Cognition:behavior:reload`` holds this studio's frame loop until the new behavior's
  tables are read (no frame joined with the old ones).
* Bounds: :data:`MAX_CLIENTS` clients, :data:`MAX_COMMAND` bytes per command; a client silent for
  :data:`CLIENT_TIMEOUT` s is dropped, as the robot would drop it. The port binds loopback only:
  the NaoTH wire has no authentication, so clients elsewhere come through an SSH tunnel.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import struct
from collections.abc import Awaitable, Callable

from xabsl_studio.engine.naoth import messages as M

__all__ = ["CLIENT_TIMEOUT", "MAX_CLIENTS", "MAX_COMMAND", "SharedSlot"]

log = logging.getLogger("xabsl.server")

#: Clients served at once.
MAX_CLIENTS = 8
#: The largest command read (an uploaded behavior is a few hundred KB).
MAX_COMMAND = 16 * 1024 * 1024
#: Seconds of silence after which a client is dropped (a robot drops one after 5 s).
CLIENT_TIMEOUT = 5.0
_INT = struct.Struct("<i")
_REPLY = struct.Struct("<iI")

#: Carries out one command on the robot: (name, arguments) -> the robot's answer.
Ask = Callable[[str, dict[str, bytes]], Awaitable[bytes]]


class SharedSlot:
    """Serves NaoTH's debug wire on ``port`` through ``ask`` (see the module docstring)."""

    def __init__(self, ask: Ask, port: int, host: str = "127.0.0.1") -> None:
        if host not in ("127.0.0.1", "::1", "localhost"):
            raise ValueError("the shared NaoTH port binds loopback only (the wire has no authentication)")
        self.ask = ask
        self.host = host
        self.port = port
        self.clients = 0
        self.served = 0
        self._server: asyncio.Server | None = None

    async def start(self) -> None:
        """Listen (``port`` 0 picks one: :attr:`port` then says which)."""
        self._server = await asyncio.start_server(self._client, self.host, self.port)
        self.port = int(self._server.sockets[0].getsockname()[1])

    async def close(self) -> None:
        """Stop listening and drop every client."""
        if self._server is not None:
            self._server.close()
            with contextlib.suppress(Exception):
                await self._server.wait_closed()
            self._server = None

    async def _client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        if self.clients >= MAX_CLIENTS:
            writer.close()
            return
        self.clients += 1
        try:
            while True:
                async with asyncio.timeout(CLIENT_TIMEOUT):  # not wait_for: see naoth._command
                    (ident,) = _INT.unpack(await reader.readexactly(4))
                if ident == -1:
                    continue  # the client's heartbeat: the robot hears this studio's
                async with asyncio.timeout(CLIENT_TIMEOUT):
                    (size,) = _INT.unpack(await reader.readexactly(4))
                if not 0 <= size <= MAX_COMMAND:
                    log.warning("shared NaoTH port: a client sent a command of %d bytes; dropped", size)
                    return
                async with asyncio.timeout(CLIENT_TIMEOUT):
                    data = await reader.readexactly(size)
                command = M.parse("CMD", data)
                args = {a.name: a.bytes for a in command.args}
                answer = await self.ask(command.name, args)
                self.served += 1
                writer.write(_REPLY.pack(ident, len(answer)) + answer)
                await writer.drain()
        except (asyncio.IncompleteReadError, TimeoutError, ConnectionError, M.DecodeError) as error:
            # gone, silent or not NaoTH's wire: the client is dropped, the robot's slot kept
            log.debug("shared NaoTH port: a client dropped: %r", error)
        except Exception as error:  # the robot went away under the command: the client is dropped
            log.info("shared NaoTH port: %s", error)
        finally:
            self.clients -= 1
            writer.close()
            with contextlib.suppress(Exception):
                await writer.wait_closed()
