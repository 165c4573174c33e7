"""Further studios served beside the main one: recordings opened as replays, forks run from a replay.

The studio that ``xabsl serve`` starts can open more sessions in the same server: a recording of
its record folder as a read-only :class:`~xabsl_studio.server.session.replay.ReplaySession`, or a live
:class:`~xabsl_studio.server.session.live.Session` forked from a replay's tick ("Run from here"). Each is a whole
studio app of its own (``xabsl_studio.server.api.app.create_app``: the same routes, websocket, security policy and
web build) mounted under a path prefix, ``/replay/ID/`` or ``/fork/ID/``: the page uses relative
addresses, so the same web UI works there in a new browser tab, beside the original.

:class:`Studios` owns them: it starts each app's lifespan (the session and its websocket hub),
bounds how many are open (the oldest without clients makes room; when every one has clients, a
new one is refused) and closes them all when the main app stops. :class:`StudiosMiddleware`
passes a request for ``/replay/ID/...`` to that studio's app with the prefix taken off the path,
so the studio's own :class:`~xabsl_studio.server.api.security.SecurityMiddleware` checks it as it checks ``/api``
(token, Origin, Host) behind the main app's.

Without the token nothing tells an open id from a closed one: the main app's check runs first
(on the path inside the prefix), ``/replay/ID`` redirects to ``/replay/ID/`` for any id, and the
public paths (the web UI's files, the API schema) answer the same under every prefix: a closed
id's are served by the main app, whose files are the same.
"""

from __future__ import annotations

import contextlib
import itertools
import re
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import orjson
from starlette.types import ASGIApp, Receive, Scope, Send

from xabsl_studio.server.protocol.errors import ServerError

if TYPE_CHECKING:
    from fastapi import FastAPI

    from xabsl_studio.server.session.live import Session

__all__ = ["MAX_FORKS", "MAX_REPLAYS", "StudioFull", "Studios", "StudiosMiddleware", "SubStudio", "split_prefix"]

#: Replays open at once (each holds a recording file open and a ring of frames).
MAX_REPLAYS = 4
#: Forks running at once (each is a simulation process).
MAX_FORKS = 2

Kind = Literal["replay", "fork"]
_PREFIX = re.compile(r"^/(replay|fork)/([0-9]+)(/.*)?$")


def split_prefix(path: str) -> tuple[str, int, str | None] | None:
    """``/replay/3/api/status`` -> ``("replay", 3, "/api/status")``; None for a path of the main studio.

    The rest is None for ``/replay/3`` (no slash: redirected to ``/replay/3/``).
    """
    match = _PREFIX.match(path)
    if match is None:
        return None
    return match.group(1), int(match.group(2)), match.group(3)


class StudioFull(ServerError):
    """No room for another studio of a kind: every open one has clients."""


@dataclass(slots=True)
class SubStudio:
    """One studio served under ``/KIND/ID/``."""

    id: int
    kind: Kind
    label: str
    app: FastAPI
    session: Session
    stack: contextlib.AsyncExitStack
    #: what it was opened from: the recording file (and the fork tick)
    source: dict[str, Any] = field(default_factory=dict)
    opened: float = field(default_factory=time.time)

    @property
    def url(self) -> str:
        """Its address on the server (the page adds the token)."""
        return f"/{self.kind}/{self.id}/"

    def clients(self) -> int:
        """Websocket clients connected now."""
        hub = self.app.state.studio.hub
        return len(hub.clients) if hub is not None else 0

    def describe(self) -> dict[str, Any]:
        """What ``GET /api/recordings`` lists of it."""
        return {
            "id": self.id,
            "kind": self.kind,
            "label": self.label,
            "url": self.url,
            "clients": self.clients(),
            "opened": round(self.opened, 3),
            **self.source,
        }


class Studios:
    """The studios served beside the main one (see the module docstring).

    Args:
        make_app: the app of a studio served here, for its session (the main app's security
            policy, web build and recordings).
        limits: the most open at once, per kind.
    """

    def __init__(
        self,
        make_app: Callable[[Session, Studios], FastAPI],
        limits: dict[Kind, int] | None = None,
    ) -> None:
        #: builds the app of a studio served here (the main app's ``create_app`` with its policy,
        #: web build and recordings): given, not imported, so the edge's modules form no circle
        self.make_app = make_app
        self.limits: dict[Kind, int] = limits or {"replay": MAX_REPLAYS, "fork": MAX_FORKS}
        self.open: dict[int, SubStudio] = {}
        self._ids = itertools.count(1)
        #: the main studio's example (a live one) as ``(path, world)`` for ``load_example``: forks
        #: of a recording of that example run its behaviors
        self.home_example: tuple[Path, str | None] | None = None

    def get(self, kind: str, ident: int) -> SubStudio | None:
        """The open studio ``/KIND/ID/``, or None."""
        studio = self.open.get(ident)
        return studio if studio is not None and studio.kind == kind else None

    def find(self, kind: Kind, **source: Any) -> SubStudio | None:
        """An open studio of ``kind`` opened from ``source`` (the same file: the same replay)."""
        for studio in self.open.values():
            if studio.kind == kind and all(studio.source.get(k) == v for k, v in source.items()):
                return studio
        return None

    async def add(self, kind: Kind, label: str, session: Session, source: dict[str, Any]) -> SubStudio:
        """Serve ``session`` as a studio of ``kind`` (started here); closes it on failure.

        Raises:
            StudioFull: as many of ``kind`` are open as allowed, and each has clients.
        """
        try:
            await self._make_room(kind)
            app = self.make_app(session, self)
            stack = contextlib.AsyncExitStack()
            await stack.enter_async_context(app.router.lifespan_context(app))
        except BaseException:
            if not session.running:  # a replay or a session that never started: close its file
                with contextlib.suppress(Exception):
                    await session.aclose()
            raise
        studio = SubStudio(next(self._ids), kind, label, app, session, stack, source)
        self.open[studio.id] = studio
        return studio

    async def _make_room(self, kind: Kind) -> None:
        same = sorted((s for s in self.open.values() if s.kind == kind), key=lambda s: s.opened)
        if len(same) < self.limits[kind]:
            return
        idle = [s for s in same if s.clients() == 0]
        if not idle:
            raise StudioFull(
                f"{len(same)} {kind}s are open, each with a page on it (at most {self.limits[kind]}); close one first"
            )
        await self.close(idle[0].id)

    async def close(self, ident: int) -> bool:
        """Stop and forget studio ``ident``; False if it is not open."""
        studio = self.open.pop(ident, None)
        if studio is None:
            return False
        await studio.stack.aclose()  # the app's lifespan: clients closed, session stopped
        return True

    async def close_all(self) -> None:
        """Stop every studio (the main app stops)."""
        for ident in list(self.open):
            with contextlib.suppress(Exception):
                await self.close(ident)

    def describe(self) -> list[dict[str, Any]]:
        """Every open studio, oldest first."""
        return [s.describe() for s in sorted(self.open.values(), key=lambda s: s.opened)]


class StudiosMiddleware:
    """Passes ``/replay/ID/...`` and ``/fork/ID/...`` to that studio's app, the prefix taken off."""

    def __init__(self, app: ASGIApp, studios: Studios, public: Callable[[Scope, str], bool]) -> None:
        self.app = app
        self.studios = studios
        #: whether a request for a path inside the prefix needs no token (the main app's policy)
        self.public = public

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Dispatch one request or websocket by its path prefix."""
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        split = split_prefix(scope["path"])
        if split is None:
            await self.app(scope, receive, send)
            return
        kind, ident, rest = split
        if rest is None:  # "/replay/3": the page's relative addresses need the slash (for any id)
            await _redirect(scope, send, f"/{kind}/{ident}/")
            return
        prefix = f"/{kind}/{ident}".encode()
        raw = scope.get("raw_path")
        inner = dict(scope, path=rest, root_path="")
        if isinstance(raw, bytes) and raw.startswith(prefix):
            inner["raw_path"] = raw[len(prefix) :]
        studio = self.studios.get(kind, ident)
        if studio is not None:
            await studio.app(inner, receive, send)
        elif self.public(scope, rest):  # the same answer as an open studio's (its files are these)
            await self.app(inner, receive, send)
        else:
            await _not_found(scope, send, f"no {kind} {ident} is open (closed, or the server restarted)")


async def _not_found(scope: Scope, send: Send, detail: str) -> None:
    if scope["type"] == "websocket":
        await send({"type": "websocket.close", "code": 4404})
        return
    body = orjson.dumps({"detail": detail})
    headers = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]
    await send({"type": "http.response.start", "status": 404, "headers": headers})
    await send({"type": "http.response.body", "body": body})


async def _redirect(scope: Scope, send: Send, location: str) -> None:
    if scope["type"] == "websocket":
        await send({"type": "websocket.close", "code": 4404})
        return
    query = scope.get("query_string", b"")
    target = location.encode() + (b"?" + query if query else b"")
    await send({"type": "http.response.start", "status": 307, "headers": [(b"location", target)]})
    await send({"type": "http.response.body", "body": b""})
