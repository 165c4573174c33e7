"""How the studio's HTTP port is opened: one uvicorn configuration for every server of the project.

``xabsl serve``, ``xabsl attach``, the tests and the benchmarks serve the same app the same way:
the websocket protocol with its limits, the HTTP parser's head buffer above the studio's own head
check (``server/api/security.py``), the studio's lifespan.
"""

from __future__ import annotations

import uvicorn
from starlette.types import ASGIApp

from xabsl_studio.server.api.transport import WebSocketProtocol
from xabsl_studio.server.protocol.limits import MAX_LSP_MESSAGE_BYTES, PARSER_HEAD_BYTES


def uvicorn_config(app: ASGIApp, host: str, port: int, *, compress: bool = False) -> uvicorn.Config:
    """The uvicorn configuration that serves ``app`` on ``host:port``.

    ``compress``: websocket permessage-deflate (frames shrink, the server spends CPU on them).
    """
    return uvicorn.Config(
        app,
        host=host,
        port=port,
        ws=WebSocketProtocol,
        # the editor's /lsp carries whole files; /ws keeps its own lower limit in the client handler
        ws_max_size=MAX_LSP_MESSAGE_BYTES,
        ws_per_message_deflate=compress,
        h11_max_incomplete_event_size=PARSER_HEAD_BYTES,
        log_level="warning",
        lifespan="on",
    )
