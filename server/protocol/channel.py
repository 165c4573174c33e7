"""The pipe between the studio server and its simulation process: framed messages, never blocking.

One ``AF_UNIX`` stream socket pair carries pickled messages (``<length><pickle>``) both ways: the
dataclasses of ``xabsl_studio.server.protocol.host``
(:data:`~xabsl_studio.server.protocol.host.ToWorker` one way,
:data:`~xabsl_studio.server.protocol.host.FromWorker` the other). Both
ends keep their socket non-blocking:

* writes go straight to the kernel; what the kernel does not take waits in a user-space buffer
  that the next :meth:`Channel.flush` pushes on. A message marked ``droppable`` (a tick's
  sample) is *not* queued behind such a backlog: it is dropped and counted, so a server that
  falls behind costs the simulation nothing but a few samples (clients then get a full frame);
* reads take whatever bytes are there and return the complete messages among them, keeping a
  partial one for later.

The simulation process waits for its socket with ``select`` between ticks; the server process
watches it with ``loop.add_reader`` (no extra thread).
"""

from __future__ import annotations

import pickle
import socket
import struct
from typing import Generic, TypeVar

from xabsl_studio.server.protocol.errors import ServerError

_HEADER = struct.Struct("<I")
_READ_SIZE = 1 << 20


class ChannelClosed(ServerError, ConnectionError):
    """The other end closed the socket (its process ended)."""


SendT = TypeVar("SendT")
ReceiveT = TypeVar("ReceiveT")


class Channel(Generic[SendT, ReceiveT]):
    """Length-prefixed pickled messages over a non-blocking stream socket (see the module docstring).

    ``Channel[SendT, ReceiveT]``: this end sends ``SendT`` and receives ``ReceiveT``.
    """

    def __init__(self, sock: socket.socket) -> None:
        sock.setblocking(False)
        self.sock = sock
        self._out = bytearray()
        self._in = bytearray()
        self.sent = 0
        self.dropped = 0
        self.bytes_sent = 0

    def fileno(self) -> int:
        """The socket's file descriptor (for ``select`` and ``loop.add_reader``)."""
        return self.sock.fileno()

    @property
    def backlog(self) -> int:
        """Bytes written but not yet taken by the kernel."""
        return len(self._out)

    def send(self, message: SendT, droppable: bool = False) -> bool:
        """Send ``message``; a droppable one is dropped (False) while older bytes still wait.

        Raises:
            ChannelClosed: the other end is gone.
        """
        if self._out and not self.flush() and droppable:
            self.dropped += 1
            return False
        data = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
        framed = _HEADER.pack(len(data)) + data
        self.sent += 1
        self.bytes_sent += len(framed)
        if self._out:
            self._out += framed
            return True
        try:
            written = self.sock.send(framed)
        except BlockingIOError:
            written = 0
        except OSError as error:
            raise ChannelClosed(str(error)) from None
        if written < len(framed):
            self._out += framed[written:]
        return True

    def flush(self) -> bool:
        """Push buffered bytes on; True when nothing is left waiting.

        Raises:
            ChannelClosed: the other end is gone.
        """
        while self._out:
            try:
                written = self.sock.send(self._out)
            except BlockingIOError:
                return False
            except OSError as error:
                raise ChannelClosed(str(error)) from None
            del self._out[:written]
        return True

    def receive(self) -> list[ReceiveT]:
        """The complete messages that arrived (possibly none).

        Raises:
            ChannelClosed: the other end closed the socket (after its last complete message).
        """
        closed = False
        while True:
            try:
                data = self.sock.recv(_READ_SIZE)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:
                closed = True
                break
            if not data:
                closed = True
                break
            self._in += data
            if len(data) < _READ_SIZE:
                break
        messages: list[ReceiveT] = []
        buffer = self._in
        start = 0
        while len(buffer) - start >= _HEADER.size:
            (size,) = _HEADER.unpack_from(buffer, start)
            end = start + _HEADER.size + size
            if end > len(buffer):
                break
            messages.append(pickle.loads(buffer[start + _HEADER.size : end]))
            start = end
        if start:
            del buffer[:start]
        if closed and not messages:
            raise ChannelClosed("the other end closed the channel")
        return messages

    def close(self) -> None:
        """Close this end."""
        self.sock.close()
