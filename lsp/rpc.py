"""The JSON-RPC layer of the language server: every request answered, no traceback anywhere.

pygls answers most malformed messages with silence and a traceback in the log: a request whose
params do not fit its type is dropped, a handler's exception becomes an error reply carrying
the server's traceback. :class:`XabslProtocol` keeps pygls' dispatch and changes what goes
wrong:

* a message that is not JSON, not an object, not JSON-RPC 2.0, or whose params do not fit its
  method gets the JSON-RPC error of the spec (parse error, invalid request, invalid params),
  with the request's id when it has a usable one, else ``null``; a malformed *notification* is
  logged in one line and dropped (there is nobody to answer);
* a request before ``initialize`` gets "server not initialized", one after ``shutdown`` "invalid
  request", a notification method sent with an id "invalid request";
* a handler's exception is an error reply with its message only: a
  :class:`~pygls.exceptions.JsonRpcException` as raised (the handlers raise those for bad input),
  anything else "internal error" with the exception's type, logged in one line.

:func:`handle_text` is the one entry for a message's text, whatever the transport (stdio,
the studio's ``/lsp``, ``xabsl lsp --ws``).
"""

from __future__ import annotations

import json
import logging
from concurrent.futures import Future
from typing import Any

from lsprotocol import types as lsp
from pygls.exceptions import (
    JsonRpcException,
    JsonRpcInternalError,
    JsonRpcInvalidParams,
    JsonRpcInvalidRequest,
    JsonRpcParseError,
    JsonRpcRequestCancelled,
    JsonRpcServerNotInitialized,
)
from pygls.protocol import LanguageServerProtocol

logger = logging.getLogger("xabsl.lsp")


class Malformed:
    """A message that cannot be handled, and the error its sender gets (a request's sender only)."""

    def __init__(self, ident: int | str | None, request: bool, error: JsonRpcException) -> None:
        self.ident = ident
        self.request = request
        self.error = error


def _ident(data: dict[str, Any]) -> int | str | None:
    """The id to answer with: the message's own when JSON-RPC allows it (a string or an integer)."""
    ident = data.get("id")
    if isinstance(ident, str) or (isinstance(ident, int) and not isinstance(ident, bool)):
        return ident
    return None


def _why(error: BaseException) -> str:
    """One line about a structuring error (cattrs nests the real causes in groups)."""
    causes = getattr(error, "exceptions", None)
    if causes:
        return _why(causes[0])
    text = str(error).splitlines()[0] if str(error) else type(error).__name__
    return text[:200]


class XabslProtocol(LanguageServerProtocol):
    """pygls' language server protocol, answering every request (see the module docstring)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.closing = False

    # ------------------------------------------------------------------ reading

    def structure_message(self, data: Any) -> Any:
        """The typed message of a decoded JSON object, or :class:`Malformed` with the error to answer."""
        if not isinstance(data, dict):
            return Malformed(None, True, JsonRpcInvalidRequest("Invalid Request: not a JSON object"))
        method = data.get("method")
        request = "id" in data and "result" not in data and "error" not in data
        if data.get("jsonrpc") != "2.0":
            return Malformed(_ident(data), request, JsonRpcInvalidRequest("Invalid Request: not JSON-RPC 2.0"))
        if "method" not in data and ("id" not in data or ("result" not in data and "error" not in data)):
            what = "Invalid Request: neither a request, a notification nor an answer"
            return Malformed(_ident(data), "id" in data, JsonRpcInvalidRequest(what))
        if "method" in data:
            if not isinstance(method, str):
                return Malformed(_ident(data), request, JsonRpcInvalidRequest("Invalid Request: no method name"))
            if "id" in data and _ident(data) is None:
                return Malformed(None, True, JsonRpcInvalidRequest("Invalid Request: an id is a string or an integer"))
        try:
            message = self._structure(data, method)
        except Exception as error:  # cattrs' errors, a RecursionError of a deep structure...
            what = f"Invalid Params for {method}: {_why(error)}" if isinstance(method, str) else "Invalid message"
            return Malformed(_ident(data), request and isinstance(method, str), JsonRpcInvalidParams(what))
        if isinstance(method, str) and "id" in data and not hasattr(message, "id"):
            return Malformed(_ident(data), True, JsonRpcInvalidRequest(f"Invalid Request: {method} is a notification"))
        return message

    def _structure(self, data: dict[str, Any], method: Any) -> Any:
        """As pygls' own ``structure_message``, without its traceback in the log."""
        if "method" in data:
            kind = self.get_message_type(method)
            if kind is None:  # an unknown method: pygls answers "method not found"
                return super().structure_message(data)
            return self._converter.structure(data, kind)
        if "error" in data:
            return self._converter.structure(data, lsp.ResponseErrorMessage)
        return super().structure_message(data)  # an answer to a request of ours

    # ------------------------------------------------------------------ dispatching

    def handle_message(self, message: Any) -> None:
        """Dispatch one message; answer the errors pygls would leave unanswered."""
        if isinstance(message, Malformed):
            if message.request:
                self.reply_error(message.ident, message.error)
            else:
                logger.warning("language server: dropped a notification: %s", message.error.message)
            return
        method = getattr(message, "method", None)
        ident = getattr(message, "id", None)
        if method is not None and ident is not None:  # a request
            if method != lsp.INITIALIZE and not self.initialized:
                self.reply_error(ident, JsonRpcServerNotInitialized("the server is not initialized yet"))
                return
            if self.closing and method != lsp.EXIT:
                self.reply_error(ident, JsonRpcInvalidRequest("the server is shutting down"))
                return
            if method == lsp.SHUTDOWN:
                self.closing = True
        super().handle_message(message)

    @property
    def initialized(self) -> bool:
        """Whether ``initialize`` ran (pygls' workspace exists from then on)."""
        try:
            self.workspace  # noqa: B018 - the property raises before initialize
        except RuntimeError:
            return False
        return True

    def reply_error(self, ident: int | str | None, error: JsonRpcException) -> None:
        """Send the JSON-RPC error ``error`` as the answer to request ``ident`` (None: ``"id": null``)."""
        if ident is None:  # lsprotocol would leave the id out; JSON-RPC wants it null
            self._send_data({"jsonrpc": "2.0", "id": None, "error": {"code": error.code, "message": error.message}})
            return
        self._send_response(ident, error=lsp.ResponseError(code=error.code, message=error.message))

    def _send_handler_result(self, future: Future[Any], *, msg_id: Any) -> None:
        """Answer a request from its handler's future (overrides pygls: no traceback, logged in one line)."""
        self._request_futures.pop(msg_id, None)
        if future.cancelled():
            self.reply_error(msg_id, JsonRpcRequestCancelled(f"request {msg_id} was cancelled"))
            return
        error = future.exception()
        if error is None:
            self._send_response(msg_id, result=future.result())
        elif isinstance(error, JsonRpcException):
            self.reply_error(msg_id, error)
        else:
            logger.warning("language server: request %s failed: %s: %s", msg_id, type(error).__name__, error)
            self.reply_error(msg_id, JsonRpcInternalError(f"internal error: {type(error).__name__}"))


def handle_text(protocol: XabslProtocol, text: str | bytes) -> None:
    """Handle one message as received (the text of one frame or one Content-Length body)."""
    try:
        data = json.loads(text)
    except (ValueError, RecursionError):
        protocol.reply_error(None, JsonRpcParseError("Parse error: not JSON"))
        return
    protocol.handle_message(protocol.structure_message(data))


__all__ = ["Malformed", "XabslProtocol", "handle_text"]
