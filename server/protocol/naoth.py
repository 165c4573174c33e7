"""The wire of NaoTH's debug port (5401): commands out, answers back, a heartbeat (docs/naoth.md).

A NaoTH robot and every one of its simulators serve their debug commands on TCP port 5401, one
client at a time, without authentication (the studio connects out to it; nothing listens here):

* client -> robot: ``int32 id`` (little-endian, 1..999 999, wrapping), ``int32 length``, then a
  protobuf ``CMD{name, args}`` (``xabsl_studio.engine.naoth.messages``); a bare ``int32 -1``
  every second is the heartbeat (a robot drops a client after 5 s of silence);
* robot -> client: ``int32 id``, ``uint32 size``, the command's output (text, or a serialized
  protobuf).

:func:`encode_command` and :class:`ReplyReader` are the two halves; :data:`MAX_REPLY` bounds an
answer before it is read.
"""

from __future__ import annotations

import struct
from collections.abc import Mapping

from xabsl_studio.engine.naoth import messages as M
from xabsl_studio.server.protocol.attach import WireError

__all__ = [
    "DEFAULT_PORT",
    "HEARTBEAT",
    "HEARTBEAT_SECONDS",
    "MAX_ID",
    "MAX_REPLY",
    "ReplyReader",
    "encode_command",
    "next_id",
    "parse_naoth_address",
]

#: NaoTH's debug port.
DEFAULT_PORT = 5401
#: The largest command id; ids wrap to 1 after it.
MAX_ID = 999_999
#: The heartbeat: a bare id of -1.
HEARTBEAT = struct.pack("<i", -1)
#: Seconds between two heartbeats (the robot drops a client after 5 s of silence).
HEARTBEAT_SECONDS = 1.0
#: The largest answer read (a behavior's complete state is a few hundred KB).
MAX_REPLY = 64 * 1024 * 1024
#: Seconds an answer may take (a robot answers within its next frame; a reload reads a file).
REPLY_TIMEOUT = 10.0
_COMMAND_HEADER = struct.Struct("<ii")
_REPLY_HEADER = struct.Struct("<iI")


def next_id(ident: int) -> int:
    """The id after ``ident`` (1..999 999, wrapping)."""
    return 1 if ident >= MAX_ID else ident + 1


def encode_command(ident: int, name: str, args: Mapping[str, bytes | str] | None = None) -> bytes:
    """One command on the wire: id, length, ``CMD`` (an argument's value may be text: UTF-8)."""
    if not 1 <= ident <= MAX_ID:
        raise ValueError(f"command id {ident} is not in 1..{MAX_ID}")
    command = M.new("CMD", name=name)
    for key, value in (args or {}).items():
        command.args.add(name=key, bytes=value.encode() if isinstance(value, str) else value)
    payload: bytes = command.SerializeToString()
    return _COMMAND_HEADER.pack(ident, len(payload)) + payload


class ReplyReader:
    """Cuts the robot's byte stream into ``(id, payload)`` answers; bounded by :data:`MAX_REPLY`."""

    def __init__(self, limit: int = MAX_REPLY) -> None:
        self.limit = limit
        self._buffer = bytearray()

    def feed(self, data: bytes) -> list[tuple[int, bytes]]:
        """The answers complete with ``data``.

        Raises:
            WireError: an answer larger than the limit (the connection is not NaoTH's).
        """
        self._buffer += data
        out: list[tuple[int, bytes]] = []
        while len(self._buffer) >= _REPLY_HEADER.size:
            ident, size = _REPLY_HEADER.unpack_from(self._buffer)
            if size > self.limit:
                raise WireError(f"the robot announced an answer of {size} bytes (at most {self.limit})")
            end = _REPLY_HEADER.size + size
            if len(self._buffer) < end:
                break
            out.append((ident, bytes(self._buffer[_REPLY_HEADER.size : end])))
            del self._buffer[:end]
        return out


def parse_naoth_address(text: str) -> tuple[str, int]:
    """``naoth://HOST[:PORT]`` (``naoth://[::1]:5401`` for IPv6) -> (host, port); 5401 by default.

    Raises:
        ValueError: not such an address.
    """
    if not text.startswith("naoth://"):
        raise ValueError(f"{text!r} is not naoth://HOST[:PORT]")
    rest = text[len("naoth://") :].rstrip("/")
    if rest.startswith("["):
        host, _, tail = rest[1:].partition("]")
        port_text = tail[1:] if tail.startswith(":") else ""
        if tail and not tail.startswith(":"):
            raise ValueError(f"{text!r} is not naoth://HOST[:PORT]")
    else:
        host, sep, port_text = rest.partition(":")
        if sep and not port_text:
            raise ValueError(f"{text!r} is not naoth://HOST[:PORT]")
    if not host or "/" in host or (port_text and not port_text.isdigit()):
        raise ValueError(f"{text!r} is not naoth://HOST[:PORT]")
    port = int(port_text) if port_text else DEFAULT_PORT
    if not 0 < port < 65536:
        raise ValueError(f"{text!r}: port {port} is not in 1..65535")
    return host, port
