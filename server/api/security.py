"""Who may talk to the studio: the token, Origin and Host checks, request body limits.

Threats, and the check for each:

* another machine on the network (the server bound off loopback): a token, generated and printed
  like Jupyter's when none is given, required on every ``/api`` request (except the OpenAPI
  schema) and on the websocket handshake;
* a web page in the user's browser (CSRF / cross-site websocket hijacking): mutating requests and
  the websocket must come without ``Origin`` or from the server's own origin (or one given with
  ``--allow-origin``);
* DNS rebinding (a foreign name resolving to 127.0.0.1): a loopback server only answers requests
  whose ``Host`` is a loopback name;
* resource exhaustion: request bodies are capped (413) before the app reads them; websocket
  messages are capped by uvicorn (``ws_max_size``) and again by the client handler.

:class:`SecurityMiddleware` applies the HTTP and handshake checks to every request in one place
(pure ASGI, so it also sees websocket handshakes and streamed bodies).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import parse_qs, urlsplit

import orjson
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from xabsl_studio.server.protocol.limits import MAX_BODY_BYTES
from xabsl_studio.server.protocol.tokens import MIN_TOKEN_CHARS as MIN_TOKEN_CHARS
from xabsl_studio.server.protocol.tokens import TokenError as TokenError
from xabsl_studio.server.protocol.tokens import check_token, is_loopback, new_token, token_matches

TOKEN_HEADER = "x-xabsl-token"
MUTATING = frozenset({"POST", "PUT", "PATCH", "DELETE"})
#: Paths under /api that need no token (the schema is public documentation).
PUBLIC_API = frozenset({"/api/openapi.json", "/api/docs", "/api/docs/oauth2-redirect"})
_LOOPBACK_NAMES = frozenset({"localhost", "127.0.0.1", "::1", "[::1]"})


def _split_host(host_header: str) -> tuple[str, str] | None:
    """``example.org:8000`` -> ``("example.org", "8000")``; ``[::1]`` -> ``("::1", "")``.

    None for a header that is not ``name[:digits]`` (``127.0.0.1:evil``, spaces, stray brackets).
    """
    if host_header.startswith("["):
        end = host_header.find("]")
        if end < 0:
            return None
        name, rest = host_header[1:end], host_header[end + 1 :]
        if rest and not rest.startswith(":"):
            return None
        port = rest[1:]
        if rest and not port:
            return None
    else:
        name, sep, port = host_header.partition(":")
        if sep and not port:
            return None
    if port and not (port.isascii() and port.isdigit()):
        return None
    if not name or any(c.isspace() or c in "/?#@[]" for c in name):
        return None
    return name, port


@dataclass
class SecurityPolicy:
    """The checks in force.

    Args:
        token: the token clients must present, or None (allowed only on a loopback server).
        loopback: the server listens on loopback only (enables the Host check).
        allowed_origins: extra origins (``scheme://host:port``) allowed besides the server's own.
    """

    token: str | None
    loopback: bool = True
    allowed_origins: frozenset[str] = field(default_factory=frozenset)
    max_body: int = MAX_BODY_BYTES

    def __post_init__(self) -> None:
        check_token(self.token, self.loopback)

    @classmethod
    def for_host(cls, host: str, token: str | None, allowed_origins: Iterable[str] = ()) -> SecurityPolicy:
        """The policy for a server bound to ``host``: off loopback a token is always required.

        Raises:
            TokenError: an empty token, or a short one off loopback.
        """
        loopback = is_loopback(host)
        if token is None and not loopback:
            token = new_token()
        return cls(token, loopback, frozenset(o.rstrip("/").lower() for o in allowed_origins))

    def token_ok(self, headers: dict[str, str], query: str) -> bool:
        """True when no token is required or one of the presented ones is it (constant time)."""
        if self.token is None:
            return True
        given: list[str] = []
        auth = headers.get("authorization", "")
        if auth.lower().startswith("bearer "):
            given.append(auth[7:].strip())
        if TOKEN_HEADER in headers:
            given.append(headers[TOKEN_HEADER])
        given.extend(parse_qs(query).get("token", []))
        return token_matches(given, self.token)

    def host_ok(self, headers: dict[str, str]) -> bool:
        """On a loopback server: the ``Host`` is a loopback name with an optional numeric port."""
        if not self.loopback:
            return True
        host = headers.get("host")
        if host is None:
            return True
        split = _split_host(host)
        return split is not None and split[0].lower() in _LOOPBACK_NAMES

    def origin_ok(self, headers: dict[str, str], scheme: str = "http") -> bool:
        """True without ``Origin``, for an allowed one, or for the server's own origin.

        ``scheme`` is the request's (``http``/``https``, or ``ws``/``wss`` for a handshake): an
        ``https`` origin is not the same origin as an ``http`` server at the same host and port.
        """
        origin = headers.get("origin")
        if origin is None:
            return True
        origin = origin.rstrip("/").lower()
        if origin in self.allowed_origins:
            return True
        parts = urlsplit(origin)
        if parts.scheme not in ("http", "https") or not parts.netloc:
            return False  # includes "null" (sandboxed frames, file:// pages)
        own = {"ws": "http", "wss": "https"}.get(scheme, scheme)
        if parts.scheme != own:
            return False
        host = headers.get("host", "").lower()
        default = "80" if parts.scheme == "http" else "443"
        return _with_port(parts.netloc, default) == _with_port(host, default)


def _with_port(netloc: str, default: str) -> str:
    if netloc.startswith("["):
        return netloc if "]:" in netloc else netloc + ":" + default
    return netloc if ":" in netloc else netloc + ":" + default


class SecurityMiddleware:
    """Applies a :class:`SecurityPolicy` to every HTTP request and websocket handshake."""

    def __init__(self, app: ASGIApp, policy: SecurityPolicy) -> None:
        self.app = app
        self.policy = policy

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Check one request or handshake, then pass it on (or answer 401/403/413 here)."""
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope.get("headers", [])}
        query = scope.get("query_string", b"").decode("latin-1")
        policy = self.policy
        if scope["type"] == "websocket":
            scheme = scope.get("scheme", "ws")
            allowed = policy.host_ok(headers) and policy.origin_ok(headers, scheme) and policy.token_ok(headers, query)
            if not allowed:
                # Closing before accepting makes the server answer the handshake with HTTP 403.
                await send({"type": "websocket.close", "code": 1008})
                return
            await self.app(scope, receive, send)
            return

        method = scope["method"]
        path = scope["path"]
        if not policy.host_ok(headers):
            await _json(send, 403, "this server only answers requests for a loopback host name")
            return
        if path.startswith("/api") and path not in PUBLIC_API and not policy.token_ok(headers, query):
            await _json(send, 401, "a token is required (Authorization: Bearer TOKEN or ?token=TOKEN)")
            return
        if method in MUTATING:
            if not policy.origin_ok(headers, scope.get("scheme", "http")):
                await _json(send, 403, f"requests from origin {headers.get('origin')} are not allowed")
                return
            length = headers.get("content-length")
            if length is not None and (not length.isdigit() or int(length) > policy.max_body):
                await _json(send, 413, f"request body over {policy.max_body} bytes")
                return
            body = await _read_body(receive, policy.max_body)
            if body is None:
                await _json(send, 413, f"request body over {policy.max_body} bytes")
                return
            receive = _replay(body, receive)
        await self.app(scope, receive, send)


async def _read_body(receive: Receive, limit: int) -> bytes | None:
    chunks: list[bytes] = []
    size = 0
    while True:
        message = await receive()
        if message["type"] != "http.request":
            break
        chunk = message.get("body", b"")
        size += len(chunk)
        if size > limit:
            return None
        chunks.append(chunk)
        if not message.get("more_body", False):
            break
    return b"".join(chunks)


def _replay(body: bytes, receive: Receive) -> Receive:
    sent = False

    async def replay() -> Message:
        nonlocal sent
        if not sent:
            sent = True
            return {"type": "http.request", "body": body, "more_body": False}
        return await receive()

    return replay


async def _json(send: Send, status: int, detail: str) -> None:
    body = orjson.dumps({"detail": detail})
    headers: list[Any] = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]
    if status == 401:
        headers.append((b"www-authenticate", b"Bearer"))
    await send({"type": "http.response.start", "status": status, "headers": headers})
    await send({"type": "http.response.body", "body": body})
