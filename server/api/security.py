"""Who may talk to the studio: the token, Origin and Host checks, request body limits.

Threats, and the check for each:

* another machine on the network (the server bound off loopback): a token, generated and printed
  like Jupyter's when none is given, required on every request and websocket handshake, under
  every prefix (``/api``, ``/docs``, ``/replay/ID/``, ``/fork/ID/``, what a route added later
  serves). Public are only what carries no behavior data, for ``GET``/``HEAD``: the web UI's
  static files (the page reads the token from its address) and the API schema
  (:data:`PUBLIC_API`). The behavior documentation at ``/docs`` is behind the token; its pages
  link to each other without it, so a docs request that presented the token gets a cookie
  (:data:`DOCS_COOKIE`, HttpOnly, SameSite=Strict) that opens the documentation, and only it;
* a web page in the user's browser (CSRF / cross-site websocket hijacking): mutating requests and
  the websocket must come without ``Origin`` or from the server's own origin (or one given with
  ``--allow-origin``);
* DNS rebinding (a foreign name resolving to 127.0.0.1): a loopback server only answers requests
  whose ``Host`` is a loopback name;
* resource exhaustion: request bodies are capped (413) before the app reads them, request
  targets (414) and heads (431) before anything looks at them; websocket messages are capped by
  uvicorn (``ws_max_size``) and again by the client handler.

:class:`SecurityMiddleware` applies the HTTP and handshake checks to every request in one place
(pure ASGI, so it also sees websocket handshakes and streamed bodies).
"""

from __future__ import annotations

import base64
import hashlib
import hmac
import secrets
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlsplit

import orjson
from starlette.requests import cookie_parser
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from xabsl_studio.server.api.studios import split_prefix
from xabsl_studio.server.protocol.limits import MAX_BODY_BYTES, MAX_HEAD_BYTES, MAX_TARGET_BYTES
from xabsl_studio.server.protocol.tokens import MIN_TOKEN_CHARS as MIN_TOKEN_CHARS
from xabsl_studio.server.protocol.tokens import TokenError as TokenError
from xabsl_studio.server.protocol.tokens import check_token, is_loopback, new_token, token_matches

TOKEN_HEADER = "x-xabsl-token"
MUTATING = frozenset({"POST", "PUT", "PATCH", "DELETE"})
#: Paths under /api that need no token (the schema is public documentation).
PUBLIC_API = frozenset({"/api/openapi.json", "/api/docs", "/api/docs/oauth2-redirect"})
#: Methods a public path answers without the token.
READING = frozenset({"GET", "HEAD"})
#: The cookie that carries the documentation's access from page to page: ``xabsl-docs-PORT``.
DOCS_COOKIE = "xabsl-docs"
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

    def docs_cookie(self) -> str | None:
        """The value of the documentation cookie: derived from the token, not the token itself.

        A server on another port of the same host receives the cookie too (cookies ignore ports):
        it learns a key that opens this server's documentation, never its API or websocket.
        """
        if self.token is None:
            return None
        digest = hmac.new(self.token.encode(), b"xabsl-studio /docs cookie", hashlib.sha256).digest()
        return base64.urlsafe_b64encode(digest).rstrip(b"=").decode()

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


def is_docs(path: str) -> bool:
    """A path of the behavior documentation (``/docs`` and below)."""
    return path == "/docs" or path.startswith("/docs/")


class PublicPaths:
    """Which requests need no token: reading the web UI's files or the API schema.

    Args:
        ui: the web UI's top-level entries (files by name, folders as ``name/``); ``/`` always is.
    """

    def __init__(self, ui: Iterable[str] = ()) -> None:
        self.ui = frozenset(ui)

    @classmethod
    def of_build(cls, web_dist: Path | None) -> PublicPaths:
        """The public paths of a built web UI (its top-level files and folders), or of none."""
        if web_dist is None or not web_dist.is_dir():
            return cls()
        return cls(p.name + "/" if p.is_dir() else p.name for p in web_dist.iterdir() if not p.name.startswith("."))

    def __call__(self, scope: Scope, path: str) -> bool:
        """True for a request of ``scope`` for ``path`` (inside a ``/replay/ID`` prefix, if any)."""
        if scope.get("method") not in READING:
            return False
        if path == "/" or path in PUBLIC_API:
            return True
        top, slash, _ = path[1:].partition("/")
        return (top + slash) in self.ui


class SecurityMiddleware:
    """Applies a :class:`SecurityPolicy` to every HTTP request and websocket handshake.

    Args:
        app: the app behind the checks.
        policy: the checks.
        public: the requests that need no token (default: ``/`` and the API schema).
    """

    def __init__(self, app: ASGIApp, policy: SecurityPolicy, public: PublicPaths | None = None) -> None:
        self.app = app
        self.policy = policy
        self.public = public or PublicPaths()

    def _docs_cookie_ok(self, headers: dict[str, str], scope: Scope, path: str) -> bool:
        expected = self.policy.docs_cookie()
        if expected is None or scope.get("method") not in READING or not is_docs(path):
            return False
        given = cookie_parser(headers.get("cookie", "")).get(_cookie_name(scope))
        return given is not None and secrets.compare_digest(given.encode("utf-8", "surrogateescape"), expected.encode())

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Check one request or handshake, then pass it on (or answer 401/403/413/414/431 here)."""
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        oversized = _oversized_head(scope)
        if oversized is not None:
            if scope["type"] == "websocket":
                await send({"type": "websocket.close", "code": 1008})
            else:
                await _json(send, *oversized)
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
        split = split_prefix(path)
        # the path inside /replay/ID/ or /fork/ID/ (their redirect to the slash is public)
        inner = path if split is None else (split[2] if split[2] is not None else "/")
        if not policy.host_ok(headers):
            await _json(send, 403, "this server only answers requests for a loopback host name")
            return
        if not self.public(scope, inner):
            if policy.token_ok(headers, query):
                if policy.token is not None and split is None and is_docs(path):
                    send = _with_cookie(send, _cookie_name(scope), policy.docs_cookie() or "")
            elif not self._docs_cookie_ok(headers, scope, inner):
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


def _oversized_head(scope: Scope) -> tuple[int, str] | None:
    """``(414 or 431, why)`` for a request target or head over the limits, else None.

    Measured on what the server parsed, so the answer is the same however the request arrived.
    """
    target = len(scope.get("raw_path") or scope["path"].encode("utf-8")) + len(scope.get("query_string", b"")) + 1
    if target > MAX_TARGET_BYTES:
        return 414, f"request target over {MAX_TARGET_BYTES} bytes"
    head = target + sum(len(name) + len(value) + 4 for name, value in scope.get("headers", []))
    if head > MAX_HEAD_BYTES:
        return 431, f"request head over {MAX_HEAD_BYTES} bytes"
    return None


def _cookie_name(scope: Scope) -> str:
    """``xabsl-docs-8000``: one cookie per port, since two studios on one host share cookies."""
    server = scope.get("server")
    port = server[1] if isinstance(server, tuple | list) and len(server) > 1 and server[1] else 0
    return f"{DOCS_COOKIE}-{port}"


def _with_cookie(send: Send, name: str, value: str) -> Send:
    """``send`` that adds the documentation cookie to the response's headers."""
    cookie = f"{name}={value}; Path=/; HttpOnly; SameSite=Strict".encode("latin-1")

    async def sending(message: Message) -> None:
        if message["type"] == "http.response.start":
            message = {**message, "headers": [*message.get("headers", []), (b"set-cookie", cookie)]}
        await send(message)

    return sending


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
