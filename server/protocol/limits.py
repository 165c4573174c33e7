"""The studio's websocket protocol, version 1: its version, limits and close codes (docs/protocol.md).

The messages themselves are typed in ``commands``, ``replies`` and ``host`` beside it; changing a message's shape means
bumping :data:`VERSION` (the web UI checks it in every ``hello``).
"""

from __future__ import annotations

import enum

#: The schema version sent in ``hello``; a client that does not know it must not go on.
VERSION = 1

#: Largest client message in bytes (uvicorn's ``ws_max_size`` and our own check, close 1009).
MAX_MESSAGE_BYTES = 64 * 1024
#: Largest message on the editor's language-server websocket (``/lsp``): an opened or changed file
#: travels whole, JSON-escaped, and files may be 16 MiB (``xabsl_studio.server.session.files.MAX_FILE_BYTES``). It is
#: uvicorn's ``ws_max_size``; ``/ws`` keeps its own lower limit.
MAX_LSP_MESSAGE_BYTES = 40 * 1024 * 1024
#: Most language-server connections at once, per studio and per ``xabsl lsp --ws`` (close 1013 above):
#: each holds its own parsed behavior set.
MAX_LSP_CLIENTS = 16
#: Threads that handle language-server messages, shared by every connection of the process: more
#: would only compete with the event loop for the interpreter (the studio's frames would stall).
MAX_LSP_WORKERS = 2
#: Answers waiting for one language-server client; a client that sends without reading them is
#: closed with 1008 when it has this many.
MAX_LSP_PENDING = 4096
#: Largest REST request body in bytes (413 above).
MAX_BODY_BYTES = 1024 * 1024
#: Longest request target (path and query, as sent) in bytes (414 above): room for the longest
#: ``collapse`` of a graph request, 4,000 characters percent-encoded at up to 12 bytes each.
MAX_TARGET_BYTES = 64 * 1024
#: Largest request head (request line and headers) in bytes (431 above).
MAX_HEAD_BYTES = 96 * 1024
#: uvicorn's HTTP parser buffer (``h11_max_incomplete_event_size``). h11 refuses a head over it
#: only while the head is incomplete, so by how TCP happened to cut the request: it lies well
#: above :data:`MAX_HEAD_BYTES` so that the studio's own check, which does not depend on that,
#: decides.
PARSER_HEAD_BYTES = 2 * MAX_HEAD_BYTES
#: Most websocket clients at once (close 1013 above).
MAX_CLIENTS = 64
#: Control messages (replies, events, history chunks) waiting for one client; a client that sends
#: commands without reading the replies is closed with 1008 when it reaches this.
MAX_PENDING_CONTROL = 256

#: Frames per second a client may ask for.
MIN_RATE, MAX_RATE, DEFAULT_RATE = 1.0, 60.0, 30.0
#: Simulation speed factors the session accepts.
MIN_SPEED, MAX_SPEED = 0.1, 20.0
#: At least one full frame per this many ticks in every client's stream (see ``frame.full``).
FULL_EVERY = 200
#: Frames per ``history`` message.
HISTORY_CHUNK = 200
#: Most ticks one ``step`` command runs.
MAX_STEP_TICKS = 400


class CloseCode(enum.IntEnum):
    """Websocket close codes the server uses (RFC 6455 section 7.4.1)."""

    NORMAL = 1000
    GOING_AWAY = 1001
    UNSUPPORTED_DATA = 1003
    INVALID_DATA = 1007
    POLICY_VIOLATION = 1008
    MESSAGE_TOO_BIG = 1009
    INTERNAL_ERROR = 1011
    TRY_AGAIN_LATER = 1013
