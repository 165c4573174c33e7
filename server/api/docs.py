"""The running behaviors' HTML documentation at ``/docs`` (``xabsl_studio.engine.docs``, generated on demand).

``GET /docs`` lists the session's behaviors (or redirects to the only one);
``GET /docs/{program}/{path}`` serves a file of the documentation of the program running under
that key. Like every route, these need the token (``xabsl_studio.server.api.security``: a docs
request that presents it gets the cookie that carries it to the pages' relative links). A page
is a regular file of the program's documentation folder, links resolved, looked up in a worker
thread and streamed. Each program is documented once into a cache folder named by its digest
(:func:`xabsl_studio.engine.docs.program_digest`), so a hot reload that changes the behavior makes the next
request document the new one, while an unchanged program is served from disk. A folder is
generated beside its final place and renamed into it, so a request never sees half a folder.
"""

from __future__ import annotations

import asyncio
import os
import shutil
import stat
import tempfile
import threading
from html import escape
from pathlib import Path

from fastapi import APIRouter, HTTPException, Request
from fastapi.responses import FileResponse, HTMLResponse, RedirectResponse, Response

from xabsl_studio.engine.docs import GraphLayoutError, generate, program_digest
from xabsl_studio.engine.emit.dot import GraphvizMissing
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.server.session.live import Session

#: Documentation folders kept per cache; older ones are removed after a new one is generated.
KEEP = 8


def default_root() -> Path:
    """``$XDG_CACHE_HOME/xabsl-studio/docs`` (``~/.cache/...`` by default)."""
    cache = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(cache) / "xabsl-studio" / "docs"


class DocsCache:
    """Documentation folders by program digest below ``root`` (thread safe).

    Args:
        root: the cache folder (created on first use).
    """

    def __init__(self, root: Path | None = None) -> None:
        self.root = root or default_root()
        self._lock = threading.Lock()
        self._digests: dict[int, tuple[Program, str]] = {}
        self.generated = 0

    def digest(self, program: Program) -> str:
        """The program's digest, computed once per program object (tens of ms for a large set)."""
        cached = self._digests.get(id(program))
        if cached is not None and cached[0] is program:
            return cached[1]
        digest = program_digest(program)
        if len(self._digests) >= 2 * KEEP:
            self._digests.clear()
        self._digests[id(program)] = (program, digest)
        return digest

    def folder(self, program: Program) -> Path:
        """The documentation folder of ``program``, generated if there is none yet."""
        folder = self.root / self.digest(program)
        if (folder / "index.html").is_file():
            return folder
        with self._lock:
            if (folder / "index.html").is_file():
                return folder
            self.root.mkdir(parents=True, exist_ok=True)
            staging = Path(tempfile.mkdtemp(prefix=".new-", dir=self.root))
            try:
                generate(program, staging)
                if folder.exists() and not (folder / "index.html").is_file():
                    shutil.rmtree(folder)  # a broken leftover
                try:
                    os.replace(staging, folder)
                except OSError:
                    # another studio sharing the cache renamed its (identical) folder in first
                    if not (folder / "index.html").is_file():
                        raise
            finally:
                if staging.exists():
                    shutil.rmtree(staging, ignore_errors=True)
            self.generated += 1
            self._prune(keep=folder)
        return folder

    def _prune(self, keep: Path) -> None:
        folders = sorted(
            (p for p in self.root.iterdir() if p.is_dir() and not p.name.startswith(".")),
            key=lambda p: p.stat().st_mtime,
            reverse=True,
        )
        for old in [p for p in folders if p != keep][KEEP - 1 :]:
            shutil.rmtree(old, ignore_errors=True)


router = APIRouter()


def _session(request: Request) -> Session:
    session: Session = request.app.state.studio.session
    return session


def _cache(request: Request) -> DocsCache:
    cache: DocsCache | None = getattr(request.app.state, "docs_cache", None)
    if cache is None:
        cache = request.app.state.docs_cache = DocsCache()
    return cache


@router.get("/docs", include_in_schema=False)
async def docs_index(request: Request) -> Response:
    """The behaviors with documentation; the only one's index directly."""
    running = [key for key, state in _session(request).programs.items() if state.running is not None]
    if len(running) == 1:
        return RedirectResponse(f"/docs/{running[0]}/index.html")
    items = "".join(f'<li><a href="/docs/{escape(k)}/index.html">{escape(k)}</a></li>' for k in running)
    return HTMLResponse(
        '<!doctype html><html><head><meta charset="utf-8"><title>behavior documentation</title></head>'
        '<body style="font-family: sans-serif; max-width: 40em; margin: 3em auto"><h1>Behavior documentation</h1>'
        + (f"<ul>{items}</ul>" if items else "<p>No behavior is running.</p>")
        + "</body></html>"
    )


@router.get("/docs/{program}", include_in_schema=False)
async def docs_program(program: str) -> Response:
    """A behavior's documentation starts at its index."""
    return RedirectResponse(f"/docs/{program}/index.html")


@router.get("/docs/{program}/{path:path}", include_in_schema=False)
async def docs_file(request: Request, program: str, path: str) -> Response:
    """A file of the documentation of the behavior running under key ``program``."""
    state = _session(request).programs.get(program)
    if state is None or state.running is None:
        raise HTTPException(404, f"no running behavior {program!r}")
    try:
        folder = await asyncio.to_thread(_cache(request).folder, state.running)
    except GraphvizMissing as error:
        raise HTTPException(503, str(error)) from None
    except GraphLayoutError as error:
        raise HTTPException(503, str(error)) from None
    target = await asyncio.to_thread(page, folder, path or "index.html")
    if target is None:
        raise HTTPException(404, f"no documentation page {path!r}")
    return FileResponse(target, headers={"Cache-Control": "no-cache"})


def page(folder: Path, path: str) -> Path | None:
    """The regular file ``path`` names inside the documentation folder (links resolved), or None."""
    try:
        target = Path(os.path.realpath(folder / path))
        inside = target.is_relative_to(os.path.realpath(folder))
        return target if inside and stat.S_ISREG(target.stat().st_mode) else None
    except (OSError, ValueError):  # a name too long, a NUL: no such page
        return None
