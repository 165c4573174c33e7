"""The websocket transport under the ASGI app: uvicorn's sans-I/O websocket, refusing bad UTF-8 quietly.

uvicorn's ``websockets-sansio`` protocol (what ``ws="auto"`` picks) decodes each text message
itself and, on invalid UTF-8, logs a ``UnicodeDecodeError`` traceback and then, when the
``websockets`` state machine has already started closing, raises ``InvalidState`` from its own
``send_close`` in an asyncio callback (a second traceback). A client's bad bytes are its problem,
not the server's: :class:`WebSocketProtocol` checks text messages first and closes with 1007
(invalid frame payload data), logging nothing. ``xabsl serve`` and the tests' live server use it.
"""

from __future__ import annotations

from uvicorn.protocols.websockets.websockets_sansio_impl import WebSocketsSansIOProtocol
from websockets.protocol import State

from xabsl_studio.server.protocol.limits import CloseCode


class WebSocketProtocol(WebSocketsSansIOProtocol):
    """uvicorn's sans-I/O websocket protocol; a text message that is not UTF-8 closes with 1007."""

    def send_receive_event_to_app(self) -> None:
        """Hand a complete message to the app, unless it is a text message that is not UTF-8."""
        if self.curr_msg_data_type == "text" and not self.close_sent:
            data = self.frames[0] if len(self.frames) == 1 else b"".join(self.frames)
            try:
                data.decode("utf-8")
            except UnicodeDecodeError:
                self.frames = []
                self.refuse_invalid_text()
                return
        super().send_receive_event_to_app()

    def refuse_invalid_text(self) -> None:
        """Close with 1007 (if the connection is not closing already) and tell the app it is gone."""
        if self.conn.state is State.OPEN:
            self.conn.send_close(CloseCode.INVALID_DATA, "invalid UTF-8")
        code = self.conn.close_sent.code if self.conn.close_sent is not None else CloseCode.INVALID_DATA
        self.queue.put_nowait({"type": "websocket.disconnect", "code": code, "reason": ""})
        self.transport.write(b"".join(self.conn.data_to_send()))
        self.close_sent = True
        self.transport.close()
