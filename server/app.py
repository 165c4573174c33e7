"""FastAPI wiring: the websocket, the REST API under /api, the web UI at /, the session's lifetime.

:func:`create_app` joins a :class:`~server.session.Session` (started and stopped with the app's
lifespan), a :class:`~server.clients.Hub` for the websocket clients, the behavior files, the
graph cache and the security middleware. Handlers here stay thin: they validate, hand the work
to the module that owns it, and turn that module's errors into 4xx answers
(``{"detail": message}``). Anything slow runs off the event loop: compiling in a worker thread,
engine work in the simulation process (``Session.request``), Graphviz in a worker thread.

Writing a behavior file compiles every behavior the file belongs to (here, in the server process)
and hot-swaps clean ones into the simulation (``Session.apply``); one asyncio lock serialises
write + compile + swap so two saves cannot interleave their reloads.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import AsyncIterator, Iterator
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Annotated, Any

import orjson
from fastapi import APIRouter, Depends, FastAPI, Header, HTTPException, Query, Request, Response, WebSocket
from fastapi.responses import HTMLResponse, JSONResponse, StreamingResponse
from fastapi.staticfiles import StaticFiles
from pydantic import BaseModel, Field

from engine.emit.dot import GraphvizMissing
from engine.ir.model import Program
from server import frames
from server.clients import Client, Hub
from server.files import BehaviorFiles, FileError
from server.graphs import GraphCache, GraphError, option_graph_dot, state_machine_dot
from server.protocol import HISTORY_CHUNK, MAX_CLIENTS, VERSION, Command, Op, ProtocolError, parse_command
from server.security import SecurityMiddleware, SecurityPolicy
from server.session import CommandError, Session

log = logging.getLogger("xabsl.server")

WEB_DIST = Path(__file__).resolve().parent.parent / "web" / "dist"

_NO_UI = """<!doctype html>
<html><head><meta charset="utf-8"><title>xabsl studio</title></head>
<body style="font-family: sans-serif; max-width: 40em; margin: 3em auto">
<h1>xabsl studio</h1>
<p>The server runs, but the web UI is not built: <code>web/dist</code> is missing.</p>
<p>Build it with <code>make</code> (or <code>cd web &amp;&amp; npm install &amp;&amp; npm run build</code>),
then reload this page.</p>
<p>The API is live: <a href="/api/status">/api/status</a>, schema at
<a href="/api/openapi.json">/api/openapi.json</a>, websocket at <code>/ws</code>
(see docs/protocol.md).</p>
</body></html>
"""


class FileBody(BaseModel):
    text: str = Field(description="the whole file content")
    version: str | None = Field(default=None, description="the version edited (instead of If-Match)")


class RenameBody(BaseModel):
    path: str = Field(description="the new path, relative to the example folder")


class CompileBody(BaseModel):
    path: str = Field(description="the file the text belongs to, relative to the example folder")
    text: str = Field(description="its unsaved content")


def _etag(value: str | None) -> str | None:
    if value is None:
        return None
    value = value.strip()
    if value.startswith("W/"):
        value = value[2:]
    return value.strip('"')


class Studio:
    """The objects one app serves (reachable from handlers as ``request.app.state.studio``)."""

    def __init__(self, session: Session, policy: SecurityPolicy) -> None:
        self.session = session
        self.policy = policy
        self.files = BehaviorFiles(session.example.root, [f for s in session.example.sources for f in s.file_folders])
        self.graphs = GraphCache()
        self.hub: Hub | None = None
        self.write_lock = asyncio.Lock()

    # -- commands -------------------------------------------------------------------------------

    async def run_command(self, command: Command, client: Client | None) -> tuple[bool, Any, str | None]:
        """Carry out a websocket or REST command: ``(ok, result, error)``."""
        session = self.session
        args = command.args
        try:
            if command.op is Op.RELOAD:
                key = args.get("program")
                if key is not None and key not in session.programs:
                    raise CommandError(f"unknown program {key!r}")
                results = await self.recompile([key] if key else list(session.programs))
                ok = all(r["ok"] for r in results.values())
                return ok, {"programs": results}, None if ok else "a behavior has errors; the running one is kept"
            if command.op is Op.HISTORY:
                return self.start_history(command, client)
            owner = client.id if client is not None else None
            return True, await session.request(command.op, args, owner), None
        except CommandError as error:
            return False, None, str(error)

    def start_history(self, command: Command, client: Client | None) -> tuple[bool, Any, str | None]:
        t0, t1, every = _history_args(command.args)
        if client is None:
            raise CommandError("history streams over the websocket; use GET /api/log over REST")
        encoded = frames.history(self.session.ring, t0, t1, every)
        count = _count_history(self.session, t0, t1, every)
        chunks = max(1, -(-count // HISTORY_CHUNK)) if count else 0

        def messages() -> Iterator[bytes]:
            chunk: list[bytes] = []
            index = 0
            for frame in encoded:
                chunk.append(frame)
                if len(chunk) == HISTORY_CHUNK:
                    yield _history_message(command.id, index, False, chunk)
                    index += 1
                    chunk = []
            yield _history_message(command.id, index, True, chunk)

        if count:
            client.history.append(messages())
            client.wake.set()
        return True, {"frames": count, "chunks": chunks}, None

    # -- compiling and hot reload -------------------------------------------------------------------------

    async def recompile(self, keys: list[str]) -> dict[str, dict[str, Any]]:
        """Compile behaviors from disk and hot-swap the clean ones; per key ok + diagnostics."""
        session = self.session
        results: dict[str, dict[str, Any]] = {}
        for key in keys:
            compilation = await asyncio.to_thread(session.compile, key)
            problem = await session.apply(key, compilation)
            diagnostics = [d.as_dict() for d in compilation.diagnostics]
            results[key] = {"ok": problem is None, "diagnostics": diagnostics, "error": problem}
            if self.hub is not None:
                self.hub.broadcast(
                    orjson.dumps(
                        {
                            "type": "event",
                            "event": "compile",
                            "program": key,
                            "ok": problem is None,
                            "diagnostics": diagnostics,
                        }
                    )
                )
        return results

    def programs_of(self, path: str) -> list[str]:
        """The behaviors a file belongs to: its folder's, plus any whose last compile read it."""
        keys = []
        real = self.files.root / path
        for key, state in self.session.programs.items():
            inside = real.resolve().is_relative_to(state.source.folder)
            read = state.compilation is not None and path in state.compilation.files
            if inside or read:
                keys.append(key)
        return keys

    async def after_write(
        self, paths: list[str], version: str | None, status: int, deleted: str | None = None
    ) -> Response:
        keys: list[str] = []
        for path in paths:
            keys.extend(k for k in self.programs_of(path) if k not in keys)
        results = await self.recompile(keys)
        ok = all(r["ok"] for r in results.values())
        diagnostics = [dict(d, program=k) for k, r in results.items() for d in r["diagnostics"]]
        if self.hub is not None:
            for path in paths:
                self.hub.broadcast(
                    orjson.dumps(
                        {
                            "type": "event",
                            "event": "file",
                            "path": path,
                            "version": None if path == deleted else version,
                            "deleted": path == deleted,
                        }
                    )
                )
        body: dict[str, Any] = {
            "path": paths[-1],
            "version": version,
            "saved": True,
            "ok": ok,
            "diagnostics": diagnostics,
            "reloaded": [k for k, r in results.items() if r["ok"]],
        }
        if not ok:
            errors = [r["error"] for r in results.values() if r["error"]]
            body["detail"] = "saved, but " + "; ".join(errors)
            return JSONResponse(body, status_code=422)
        return JSONResponse(body, status_code=status)


def _history_args(args: dict[str, Any]) -> tuple[int, int, int]:
    t0, t1, every = args.get("t0", 0), args.get("t1", 2**62), args.get("every", 1)
    for name, value in (("t0", t0), ("t1", t1), ("every", every)):
        if isinstance(value, bool) or not isinstance(value, int):
            raise CommandError(f"{name} must be an integer")
    if every < 1 or t1 < t0:
        raise CommandError("history needs t0 <= t1 and every >= 1")
    return t0, t1, every


def _count_history(session: Session, t0: int, t1: int, every: int) -> int:
    entries = session.ring.snapshot()
    if not entries:
        return 0
    gen = entries[-1].gen
    n = sum(1 for e in entries if e.gen is gen and t0 <= e.t <= t1)
    return 0 if n == 0 else 1 + (n - 1) // every


def _history_message(command_id: Any, index: int, last: bool, chunk: list[bytes]) -> bytes:
    return b'{"type":"history","id":%s,"chunk":%d,"last":%s,"frames":[%s]}' % (
        orjson.dumps(command_id),
        index,
        b"true" if last else b"false",
        b",".join(chunk),
    )


def _studio(request: Request) -> Studio:
    studio: Studio = request.app.state.studio
    return studio


# Handlers are module-level functions that find their Studio through the request: FastAPI caches
# endpoint callables globally, so closures over a session would keep every session (and its
# world) alive for the life of the process.
StudioDep = Annotated[Studio, Depends(_studio)]
router = APIRouter()


@router.websocket("/ws")
async def websocket(ws: WebSocket) -> None:
    studio: Studio = ws.app.state.studio
    assert studio.hub is not None, "the app's lifespan did not run"
    await studio.hub.serve(ws, studio.run_command, MAX_CLIENTS)


@router.websocket("/lsp")
async def language_server(ws: WebSocket) -> None:
    """The XABSL language server for the editor (docs/editors.md): LSP, one message per text frame."""
    from lsp.bridge import serve_connection  # pygls is imported only when an editor connects

    studio: Studio = ws.app.state.studio
    await ws.accept()
    await serve_connection(ws.receive_text, ws.send_text, studio.session.example.root)


# -- session --------------------------------------------------------------------------------------


@router.get("/api/status", tags=["session"])
async def status(studio: StudioDep) -> dict[str, Any]:
    """The session status: clock, speed, ring buffer, programs and their diagnostics, clients."""
    result = await studio.session.status()
    result["clients"] = studio.hub.stats() if studio.hub is not None else {}
    result["token_required"] = studio.policy.token is not None
    result["version"] = VERSION
    return result


@router.get("/api/structure", tags=["session"])
async def structure(studio: StudioDep) -> Response:
    """The ``structure`` of the current hello (programs JSON and agents)."""
    gen = studio.session.generation
    return Response(gen.structure_bytes if gen is not None else b"{}", media_type="application/json")


@router.post("/api/command", tags=["session"])
async def command(studio: StudioDep, body: dict[str, Any]) -> JSONResponse:
    """A websocket command over REST (``{"op": "pause"}``); answers the reply."""
    try:
        parsed = parse_command(body)
    except ProtocolError as error:
        return JSONResponse(
            {"type": "reply", "id": body.get("id"), "ok": False, "error": str(error), "detail": str(error)},
            status_code=400,
        )
    ok, result, error = await studio.run_command(parsed, None)
    payload: dict[str, Any] = {"type": "reply", "id": parsed.id, "ok": ok}
    if result is not None:
        payload["result"] = result
    if error is not None:
        payload["error"] = error
        payload["detail"] = error
    return JSONResponse(payload, status_code=200 if ok else (422 if parsed.op is Op.RELOAD else 400))


@router.get("/api/log", tags=["session"])
async def activation_log(studio: StudioDep, t0: int = Query(0), t1: int = Query(2**62)) -> StreamingResponse:
    """The ring buffer between behavior times t0 and t1 as JSON lines, with names."""
    if t1 < t0:
        raise HTTPException(400, "t1 must not be before t0")
    session = studio.session
    latest = session.ring.latest
    if latest is None:
        return StreamingResponse(iter(()), media_type="application/x-ndjson")
    encoded = frames.history(session.ring, t0, t1)
    return StreamingResponse(_log_lines(encoded, latest.gen), media_type="application/x-ndjson")


# -- files ------------------------------------------------------------------------------------------


@router.get("/api/files", tags=["files"])
async def list_files(studio: StudioDep) -> dict[str, Any]:
    """Every behavior file: path, version, size, the behaviors it belongs to."""
    listed = await asyncio.to_thread(studio.files.list)
    for item in listed:
        item["programs"] = studio.programs_of(item["path"])
    return {"files": listed}


@router.get("/api/files/{path:path}", tags=["files"])
async def read_file(studio: StudioDep, path: str) -> JSONResponse:
    """A file's text and version (also as ETag)."""
    text, version = await asyncio.to_thread(studio.files.read, path)
    return JSONResponse({"path": path, "version": version, "text": text}, headers={"ETag": f'"{version}"'})


@router.put("/api/files/{path:path}", tags=["files"])
async def write_file(
    studio: StudioDep, path: str, body: FileBody, if_match: str | None = Header(default=None)
) -> Response:
    """Replace a file (If-Match: its version); compile; hot-swap when clean, else 422."""
    expected = _etag(if_match) or body.version
    async with studio.write_lock:
        version = await asyncio.to_thread(studio.files.write, path, body.text, expected)
        return await studio.after_write([path], version, 200)


@router.post("/api/files/{path:path}", tags=["files"])
async def create_file(studio: StudioDep, path: str, body: FileBody) -> Response:
    """Create a file (409 if it exists); compile the behaviors it belongs to."""
    async with studio.write_lock:
        version = await asyncio.to_thread(studio.files.create, path, body.text)
        return await studio.after_write([path], version, 201)


@router.patch("/api/files/{path:path}", tags=["files"])
async def rename_file(
    studio: StudioDep, path: str, body: RenameBody, if_match: str | None = Header(default=None)
) -> Response:
    """Rename a file to ``body.path`` (409 if that exists)."""
    async with studio.write_lock:
        version = await asyncio.to_thread(studio.files.rename, path, body.path, _etag(if_match))
        return await studio.after_write([path, body.path], version, 200, deleted=path)


@router.delete("/api/files/{path:path}", tags=["files"])
async def delete_file(studio: StudioDep, path: str, if_match: str | None = Header(default=None)) -> Response:
    """Delete a file; compile the behaviors it belonged to."""
    async with studio.write_lock:
        await asyncio.to_thread(studio.files.delete, path, _etag(if_match))
        return await studio.after_write([path], None, 200, deleted=path)


@router.post("/api/compile", tags=["files"])
async def compile_text(studio: StudioDep, body: CompileBody) -> dict[str, Any]:
    """Diagnostics for unsaved text of a file (nothing is saved or swapped): as-you-type linting."""
    real = studio.files.resolve(body.path, must_exist=False)
    keys = studio.programs_of(body.path)
    diagnostics: list[dict[str, Any]] = []
    ok = True
    for key in keys:
        compilation = await asyncio.to_thread(studio.session.compile, key, {str(real): body.text})
        ok = ok and compilation.ok
        diagnostics.extend(dict(d.as_dict(), program=key) for d in compilation.diagnostics)
    return {"ok": ok, "diagnostics": diagnostics, "programs": keys}


# -- graphs ------------------------------------------------------------------------------------------


def _running(studio: Studio, key: str) -> Program:
    state = studio.session.programs.get(key)
    if state is None or state.running is None:
        raise HTTPException(404, f"no running behavior {key!r}")
    return state.running


async def _svg(studio: Studio, request: Request, dot: str) -> Response:
    try:
        svg, etag = await asyncio.to_thread(studio.graphs.svg, dot)
    except GraphvizMissing as error:
        raise HTTPException(503, str(error)) from None
    if _etag(request.headers.get("if-none-match")) == etag:
        return Response(status_code=304, headers={"ETag": f'"{etag}"'})
    return Response(svg, media_type="image/svg+xml", headers={"ETag": f'"{etag}"', "Cache-Control": "no-cache"})


@router.get("/api/graph/{program}", tags=["graphs"])
async def graph(studio: StudioDep, request: Request, program: str, agent: str | None = None) -> Response:
    """The option graph below an XABSL agent's root option (SVG)."""
    try:
        dot = option_graph_dot(_running(studio, program), agent)
    except GraphError as error:
        raise HTTPException(404, str(error)) from None
    return await _svg(studio, request, dot)


@router.get("/api/graph/{program}/{option}", tags=["graphs"])
async def option_graph(studio: StudioDep, request: Request, program: str, option: str) -> Response:
    """The state machine of one option (SVG)."""
    try:
        dot = state_machine_dot(_running(studio, program), option)
    except GraphError as error:
        raise HTTPException(404, str(error)) from None
    return await _svg(studio, request, dot)


async def _file_error(request: Request, error: Exception) -> JSONResponse:
    assert isinstance(error, FileError)
    return JSONResponse({"detail": error.message, **error.extra}, status_code=error.status)


async def _command_error(request: Request, error: Exception) -> JSONResponse:
    return JSONResponse({"detail": str(error)}, status_code=400)


async def _no_ui(request: Request) -> HTMLResponse:
    return HTMLResponse(_NO_UI)


@asynccontextmanager
async def _lifespan(app: FastAPI) -> AsyncIterator[None]:
    studio: Studio = app.state.studio
    session = studio.session
    hub = Hub(session, asyncio.get_running_loop())
    hub.token_required = studio.policy.token is not None
    studio.hub = hub
    session.notify = hub.on_entry
    session.on_crash = hub.on_crash
    await session.start()
    try:
        yield
    finally:
        await hub.close_all()
        session.notify = _ignore
        await session.aclose()
        studio.hub = None


def _ignore(entry: frames.Entry) -> None:
    return None


def create_app(session: Session, policy: SecurityPolicy | None = None, web_dist: Path | None = WEB_DIST) -> FastAPI:
    """The studio app for a session (not started yet: the app's lifespan starts and stops it).

    Args:
        session: the simulation session to serve.
        policy: security checks (default: loopback, no token).
        web_dist: the built web UI, served at ``/`` (a help page when missing).
    """
    policy = policy or SecurityPolicy(token=None)
    app = FastAPI(
        title="xabsl studio",
        version=str(VERSION),
        description="Live XABSL behavior session: see docs/protocol.md.",
        openapi_url="/api/openapi.json",
        docs_url="/api/docs",
        redoc_url=None,
        lifespan=_lifespan,
    )
    app.state.studio = Studio(session, policy)
    app.add_middleware(SecurityMiddleware, policy=policy)
    app.add_exception_handler(FileError, _file_error)
    app.add_exception_handler(CommandError, _command_error)
    app.include_router(router)
    if web_dist is not None and (web_dist / "index.html").is_file():
        app.mount("/", StaticFiles(directory=web_dist, html=True), name="web")
    else:
        app.add_api_route("/", _no_ui, methods=["GET"], include_in_schema=False)
    return app


def _log_lines(encoded: Iterator[bytes], gen: frames.Generation) -> Iterator[bytes]:
    """Decoded frames (full first, then deltas) -> one JSON line per tick with names."""
    state: dict[int, dict[str, dict[str, Any]]] = {}
    names = _names(gen)
    for data in encoded:
        frame = orjson.loads(data)
        agents = []
        for agent in frame["agents"]:
            index = agent["id"]
            values = state.setdefault(index, {"inputs": {}, "outputs": {}})
            for kind in ("inputs", "outputs"):
                values[kind].update(agent.get(kind, {}))
            table = names.get(index)
            if table is None:
                agents.append({"id": index, "name": gen.structure["agents"][index]["name"], "path": []})
                continue
            agents.append(
                {
                    "id": index,
                    "name": gen.structure["agents"][index]["name"],
                    "path": [table.node(node) for node in agent["path"]],
                    "outputs": {table.outputs.get(int(k), k): v for k, v in values["outputs"].items()},
                    "inputs": {table.inputs.get(int(k), k): v for k, v in values["inputs"].items()},
                    **{k: agent[k] for k in ("fault", "forced", "overrides") if k in agent},
                }
            )
        yield orjson.dumps({"seq": frame["seq"], "t": frame["t"], "agents": agents}) + b"\n"


class _Names:
    """Id -> name tables of one program, from its program JSON (the hello's structure)."""

    def __init__(self, program: dict[str, Any]) -> None:
        self.options = {o["id"]: o for o in program["options"]}
        self.behaviors = {b["id"]: b["name"] for b in program["behaviors"]}
        self.inputs = {s["id"]: s["name"] for s in program["inputs"]}
        self.outputs = {s["id"]: s["name"] for s in program["outputs"]}

    def node(self, node: list[Any]) -> dict[str, Any]:
        if node[0] == 0:
            _, depth, option_id, state_id, option_time, state_time, decided_in, leaf, params = node
            option = self.options[option_id]
            states = option["states"]
            return {
                "depth": depth,
                "option": option["name"],
                "state": states[state_id]["name"],
                "option_time": option_time,
                "state_time": state_time,
                "decided_in": states[decided_in]["name"] if decided_in >= 0 else None,
                "leaf": leaf,
                "params": dict(zip((p["name"] for p in option["params"]), params, strict=False)),
            }
        _, depth, behavior_id, time, params = node
        return {"depth": depth, "behavior": self.behaviors[behavior_id], "time": time, "params": params}


def _names(gen: frames.Generation) -> dict[int, _Names]:
    tables: dict[str, _Names] = {}
    result: dict[int, _Names] = {}
    programs = gen.structure["programs"]
    for agent in gen.structure["agents"]:
        key = agent["program"]
        if key is None:
            continue
        if key not in tables:
            tables[key] = _Names(programs[key])
        result[agent["id"]] = tables[key]
    return result
