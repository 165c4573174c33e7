"""FastAPI wiring: the websocket, the REST API under /api, the web UI at /, the session's lifetime.

:func:`create_app` joins a :class:`~xabsl_studio.server.session.live.Session` (started and stopped with the app's
lifespan), a :class:`~xabsl_studio.server.api.clients.Hub` for the websocket clients, the behavior files, the
graph cache and the security middleware. Handlers here stay thin: they validate, hand the work
to the module that owns it, and turn that module's errors into 4xx answers
(``{"detail": message}``). Anything slow runs off the event loop: compiling in a worker thread,
engine work in the simulation process (``Session.request``), Graphviz in a worker thread.

Writing a behavior file compiles every behavior the file belongs to (here, in the server process)
and hot-swaps clean ones into the simulation (``Session.apply``); one asyncio lock serialises
write + compile + swap so two saves cannot interleave their reloads. A file of a behavior set
changed outside the studio is picked up the same way (``Studio.watch_files``, polling with
``xabsl_studio.server.session.watch``): under that lock, so a save of the studio's own is never
taken for an external change.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import subprocess
from collections.abc import AsyncIterator, Iterator
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Annotated, Any

import orjson
from fastapi import APIRouter, Depends, FastAPI, Header, HTTPException, Query, Request, Response, WebSocket
from fastapi import Path as FastApiPath
from fastapi.dependencies.models import Dependant
from fastapi.exception_handlers import http_exception_handler
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse, StreamingResponse
from fastapi.routing import APIRoute
from fastapi.staticfiles import StaticFiles
from pydantic import JsonValue
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.requests import HTTPConnection
from starlette.routing import Match
from starlette.types import Receive, Scope, Send

import xabsl_studio
from xabsl_studio.engine.emit.dot import GraphvizMissing
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.record.mcapread import RecordingError
from xabsl_studio.engine.runtime.activation import OPTION_NODE
from xabsl_studio.server.api.clients import Client, Hub
from xabsl_studio.server.api.compare import router as compare_router
from xabsl_studio.server.api.docs import router as docs_router
from xabsl_studio.server.api.drafts import router as drafts_router
from xabsl_studio.server.api.forks import router as fork_router
from xabsl_studio.server.api.foxglove import FoxgloveServer
from xabsl_studio.server.api.foxglove import router as foxglove_router
from xabsl_studio.server.api.graphs import (
    GraphCache,
    GraphError,
    grouped_graph_dot,
    option_graph_dot,
    state_machine_dot,
)
from xabsl_studio.server.api.library import RecordingLibrary
from xabsl_studio.server.api.library import router as library_router
from xabsl_studio.server.api.openapi import ErrorBody, error_responses
from xabsl_studio.server.api.pictures import router as pictures_router
from xabsl_studio.server.api.profile import router as profile_router
from xabsl_studio.server.api.security import PublicPaths, SecurityMiddleware, SecurityPolicy
from xabsl_studio.server.api.studios import Studios, StudiosMiddleware
from xabsl_studio.server.protocol.commands import Command, History, Reload, guess_id, openapi_schemas, parse_command
from xabsl_studio.server.protocol.limits import HISTORY_CHUNK, MAX_CLIENTS, MAX_LSP_CLIENTS, VERSION, CloseCode
from xabsl_studio.server.protocol.replies import CompileEvent, FileEvent, Reply, RestReply, encode, encode_history_chunk
from xabsl_studio.server.protocol.rest import (
    FILE_PATH_PATTERN,
    NEW_FILE_PATH_PATTERN,
    CompileBody,
    CompileResult,
    FileBody,
    FileList,
    GenerationDiff,
    GraphGroups,
    ProgramDiagnostic,
    Recompiled,
    RenameBody,
    SaveResult,
)
from xabsl_studio.server.protocol.types import (
    BEHAVIOR_PARAMS_INDEX,
    DEPTH_INDEX,
    ID_INDEX,
    OPTION_PARAMS_INDEX,
    ProtocolError,
)
from xabsl_studio.server.session import frames
from xabsl_studio.server.session.files import BehaviorFiles, FileError
from xabsl_studio.server.session.frames import Generation
from xabsl_studio.server.session.generations import GenerationGone
from xabsl_studio.server.session.live import CommandError, Session
from xabsl_studio.server.session.watch import POLL_SECONDS, FileWatcher

log = logging.getLogger("xabsl.server")

#: the built studio UI: web/dist in a checkout (xabsl_studio/web links to it), package data in a wheel
WEB_DIST = Path(xabsl_studio.__file__).parent / "web"

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


#: What a behavior file path looks like (documented, not enforced here: ``xabsl_studio.server.session.files`` checks
#: paths and answers 400/403/404 with the reason, which a pattern mismatch could not give).
_FILE_PATH: dict[str, JsonValue] = {"pattern": FILE_PATH_PATTERN}
_NEW_FILE_PATH: dict[str, JsonValue] = {"pattern": NEW_FILE_PATH_PATTERN}
FilePath = Annotated[str, FastApiPath(description="relative to the example folder", json_schema_extra=_FILE_PATH)]
NewFilePath = Annotated[
    str, FastApiPath(description="relative to the example folder", json_schema_extra=_NEW_FILE_PATH)
]


class NdjsonResponse(StreamingResponse):
    """JSON lines (``/api/log``)."""

    media_type = "application/x-ndjson"


class SvgResponse(Response):
    """An SVG document (``/api/graph``)."""

    media_type = "image/svg+xml"


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
        #: the Foxglove WebSocket endpoint's viewers and feed (``/foxglove``; set by the lifespan)
        self.foxglove: FoxgloveServer | None = None
        #: open ``/lsp`` connections (capped at ``MAX_LSP_CLIENTS``)
        self.lsp_connections = 0
        self.write_lock = asyncio.Lock()
        #: the include closures' files as last seen, to notice changes made outside the studio
        self.watcher = FileWatcher(self.files.root)
        #: the recordings it may open, and the replays and forks served beside it (``create_app``)
        self.library: RecordingLibrary
        self.studios: Studios

    # -- commands -------------------------------------------------------------------------------

    async def run_command(self, command: Command, client: Client | None) -> Reply:
        """Carry out a (validated) websocket or REST command; its reply.

        ``reload`` and ``history`` are the server process's (compiling, the ring buffer); every
        other op goes to the simulation (``Session.request``).
        """
        session = self.session
        try:
            if isinstance(command, Reload):
                key = command.program
                if key is not None and key not in session.programs:
                    raise CommandError(f"unknown program {key!r}")
                results = await self.recompile([key] if key else list(session.programs))
                ok = all(r["ok"] for r in results.values())
                error = None if ok else "a behavior has errors; the running one is kept"
                return Reply(id=command.id, ok=ok, result={"programs": results}, error=error)
            if isinstance(command, History):
                return Reply(id=command.id, ok=True, result=self.start_history(command, client))
            owner = client.id if client is not None else None
            result = await session.request(command, owner)
            if self.foxglove is not None:
                self.foxglove.command(command)  # an event for its viewers, or a playback change
            return Reply(id=command.id, ok=True, result=result)
        except CommandError as error:
            return Reply(id=command.id, ok=False, error=str(error))

    def start_history(self, command: History, client: Client | None) -> dict[str, Any]:
        """Queue the ``history`` chunks for ``client``; the reply's result (frames, chunks, generations).

        A live session serves every generation still in the ring (``t0``, ``t1``: timeline times,
        ``t`` plus the generation's offset), each with what the client needs to read its ticks.
        """
        t0, t1, every = command.t0, command.t1, command.every
        if t1 < t0:
            raise CommandError("history needs t0 <= t1")
        if client is None:
            raise CommandError("history streams over the websocket; use GET /api/log over REST")
        gens, count, encoded = self.session.history_span(t0, t1, every)
        generations = [_generation_info(self.session, gen) for gen in gens]
        chunks = max(1, -(-count // HISTORY_CHUNK)) if count else 0

        def messages() -> Iterator[bytes]:
            chunk: list[bytes] = []
            index = 0
            try:
                for frame in encoded:
                    chunk.append(frame)
                    if len(chunk) == HISTORY_CHUNK:
                        yield encode_history_chunk(command.id, index, False, chunk)
                        index += 1
                        chunk = []
            except RecordingError as error:  # a damaged tick further on in a replay's file: the history ends there
                log.warning("history of the replay ends early: %s", error)
            yield encode_history_chunk(command.id, index, True, chunk)

        if count:
            client.history.append(messages())
            client.wake.set()
        return {"frames": count, "chunks": chunks, "generations": generations}

    # -- compiling and hot reload -------------------------------------------------------------------------

    async def recompile(self, keys: list[str]) -> dict[str, Recompiled]:
        """Compile behaviors from disk and hot-swap the clean ones; per key ok + diagnostics."""
        session = self.session
        results: dict[str, Recompiled] = {}
        for key in keys:
            compilation = await asyncio.to_thread(session.compile, key)
            problem = await session.apply(key, compilation)
            diagnostics = [d.as_dict() for d in compilation.diagnostics]
            results[key] = {"ok": problem is None, "diagnostics": diagnostics, "error": problem}
            if self.hub is not None:
                self.hub.broadcast(CompileEvent(program=key, ok=problem is None, diagnostics=diagnostics))
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
        """Recompile the behavior sets ``paths`` belong to, tell the clients, answer the write."""
        for path in paths:
            self.watcher.note(path)  # the studio's own write: never reported back as external
        keys: list[str] = []
        for path in paths:
            keys.extend(k for k in self.programs_of(path) if k not in keys)
        results = await self.recompile(keys)
        ok = all(r["ok"] for r in results.values())
        diagnostics: list[ProgramDiagnostic] = [
            {**d, "program": k} for k, r in results.items() for d in r["diagnostics"]
        ]
        if self.hub is not None:
            for path in paths:
                gone = path == deleted
                self.hub.broadcast(FileEvent(path=path, version=None if gone else version, deleted=gone))
        body: SaveResult = {
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

    # -- files changed outside the studio --------------------------------------------------------------

    def watched_paths(self) -> list[str]:
        """The API paths of every behavior set's include closure: what its last compile read, its agents file."""
        paths: set[str] = set()
        for state in self.session.programs.values():
            if state.compilation is not None:
                paths.update(state.compilation.files)
            agents = state.source.agents_file
            if agents.resolve().is_relative_to(self.files.root):
                paths.add(self.files.api_path(agents.resolve()))
        return sorted(paths)

    async def check_files(self) -> None:
        """One look at the watched files: each external change is told and compiled like a save."""
        async with self.write_lock:
            self.watcher.watch(self.watched_paths())
            changes = await asyncio.to_thread(self.watcher.scan)
            if not changes:
                return
            if self.hub is not None:
                for change in changes:
                    gone = change.version is None
                    self.hub.broadcast(FileEvent(path=change.path, version=change.version, deleted=gone, by="disk"))
            keys: list[str] = []
            for change in changes:
                keys.extend(k for k in self.programs_of(change.path) if k not in keys)
            await self.recompile(keys)
            # a new include brings its file into the closure: watched from now on, as it is now
            self.watcher.watch(self.watched_paths())

    async def watch_files(self) -> None:
        """Look at the watched files every POLL_SECONDS until cancelled (the app's lifespan)."""
        while True:
            await asyncio.sleep(POLL_SECONDS)
            try:
                await self.check_files()
            except Exception:  # one bad pass (a file vanishing mid-read) must not end the watching
                log.exception("watching the behavior files")


def _generation_info(session: Session, gen: Generation) -> dict[str, Any]:
    """A :class:`~xabsl_studio.server.protocol.replies.GenerationInfo` (the description only for past generations)."""
    first = next((e for e in session.ring.snapshot() if e.gen is gen), None)
    info: dict[str, Any] = {
        "number": gen.number,
        "reason": gen.reason,
        "offset": gen.offset,
        "seq": first.seq if first is not None else 0,
        "t": first.t if first is not None else 0,
        "changed_files": sorted({path for paths in gen.changed.values() for path in paths}),
    }
    if session.generation is None or gen.number != session.generation.number:
        info["structure"] = gen.wire_structure()[0]
        info["scene"] = orjson.loads(gen.scene_bytes)
    return info


def single_query_values(connection: HTTPConnection) -> None:
    """Refuse a query parameter of the route given twice (``?t0=abc&t0=5``): which one counts would be a guess.

    Parameters the route does not have are ignored, as FastAPI ignores them once; ``token`` may
    repeat (``SecurityMiddleware`` compares every value given).

    Raises:
        RequestValidationError: a 422 in FastAPI's validation format, naming the parameter.
    """
    route = connection.scope.get("route")
    dependant = getattr(route, "dependant", None)
    if dependant is None:
        return
    declared = set(_query_names(dependant))
    seen: set[str] = set()
    for key, _ in connection.query_params.multi_items():
        if key in seen and key in declared:
            values = connection.query_params.getlist(key)
            raise RequestValidationError(
                [{"type": "repeated", "loc": ("query", key), "msg": "given more than once", "input": values}]
            )
        seen.add(key)


def _query_names(dependant: Dependant) -> Iterator[str]:
    for field in dependant.query_params:
        yield field.alias
    for sub in dependant.dependencies:
        yield from _query_names(sub)


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
    """The live session (docs/protocol.md): one :class:`~xabsl_studio.server.api.clients.Client` per connection."""
    studio: Studio = ws.app.state.studio
    assert studio.hub is not None, "the app's lifespan did not run"
    await studio.hub.serve(ws, studio.run_command, MAX_CLIENTS)


@router.websocket("/lsp")
async def language_server(ws: WebSocket) -> None:
    """The XABSL language server for the editor (docs/editors.md): LSP, one message per text frame.

    It serves the behavior folders only (docs/security.md); over ``MAX_LSP_CLIENTS`` connections
    a new one is closed with 1013, as ``/ws`` does.
    """
    from xabsl_studio.lsp.bridge import serve_connection  # pygls is imported only when an editor connects

    studio: Studio = ws.app.state.studio
    await ws.accept()
    if studio.lsp_connections >= MAX_LSP_CLIENTS:
        await ws.close(CloseCode.TRY_AGAIN_LATER)
        return
    studio.lsp_connections += 1

    async def receive() -> str | bytes | None:
        message = await ws.receive()
        if message["type"] == "websocket.disconnect":
            return None
        text: str | None = message.get("text")
        return text if text is not None else bytes(message.get("bytes") or b"")

    try:
        await serve_connection(
            receive,
            ws.send_text,
            lambda code: ws.close(code),
            roots=[str(f) for f in studio.files.folders],
            root=str(studio.session.example.root),
        )
    finally:
        studio.lsp_connections -= 1


# -- session --------------------------------------------------------------------------------------


@router.get("/api/status", tags=["session"], responses=error_responses())
async def status(studio: StudioDep) -> dict[str, Any]:
    """The session status: clock, speed, ring buffer, programs and their diagnostics, clients, Foxglove viewers."""
    result = await studio.session.status()
    result["clients"] = studio.hub.stats() if studio.hub is not None else {}
    result["foxglove"] = studio.foxglove.stats() if studio.foxglove is not None else {}
    result["token_required"] = studio.policy.token is not None
    result["version"] = VERSION
    return result


@router.get("/api/structure", tags=["session"], responses=error_responses())
async def structure(studio: StudioDep) -> Response:
    """The ``structure`` of the current hello (programs JSON and agents)."""
    gen = studio.session.generation
    return Response(gen.structure_bytes if gen is not None else b"{}", media_type="application/json")


_REPLY = {"$ref": "#/components/schemas/RestReply"}
_COMMAND_DOC: dict[str, Any] = {
    "requestBody": {
        "required": True,
        "content": {"application/json": {"schema": {"$ref": "#/components/schemas/Command"}}},
    },
    "responses": {
        "200": {"description": "the command's reply", "content": {"application/json": {"schema": _REPLY}}},
        "400": {
            "description": "a malformed command (the reply's error says what is wrong)",
            "content": {"application/json": {"schema": _REPLY}},
        },
        "409": {
            "description": "a command that does not fit the session now: no such robot, option or symbol, "
            "step while running, the simulation stopped",
            "content": {"application/json": {"schema": _REPLY}},
        },
        "422": {
            "description": "reload: a behavior set has errors (the running one is kept)",
            "content": {"application/json": {"schema": _REPLY}},
        },
    },
}


@router.post("/api/command", tags=["session"], responses=error_responses(401, 403, 413), openapi_extra=_COMMAND_DOC)
async def command(studio: StudioDep, request: Request) -> Response:
    """A websocket command over REST (``{"op": "pause"}``); answers the reply.

    The body is read and validated by the same parser as the websocket's messages
    (``xabsl_studio.server.protocol.commands.parse_command``): one rule for both edges. 400: the command is malformed;
    409: it is well formed but does not fit the session (an unknown robot or option...).
    """
    body = await request.body()
    try:
        parsed = parse_command(body)
    except ProtocolError as error:
        return _reply_response(Reply(id=guess_id(body), ok=False, error=str(error)), 400)
    answer = await studio.run_command(parsed, None)
    if answer.ok:
        return _reply_response(answer, 200)
    # A reload that compiled (a result) with errors is 422; anything else refused is a conflict.
    return _reply_response(answer, 422 if isinstance(parsed, Reload) and answer.result is not None else 409)


def _reply_response(answer: Reply, status: int) -> Response:
    # A failed reply also carries the error as ``detail``, as every other REST error does.
    rest = RestReply(id=answer.id, ok=answer.ok, result=answer.result, error=answer.error, detail=answer.error)
    return Response(encode(rest), status_code=status, media_type="application/json")


@router.get(
    "/api/log",
    tags=["session"],
    response_class=NdjsonResponse,
    responses={
        **error_responses(422),
        200: {
            "description": "one JSON object per line and tick",
            "content": {"application/x-ndjson": {"schema": {"type": "string"}}},
        },
    },
)
async def activation_log(studio: StudioDep, t0: int = Query(0), t1: int = Query(2**62)) -> StreamingResponse:
    """The ring buffer between behavior times t0 and t1 as JSON lines, with names (none when t1 < t0)."""
    session = studio.session
    latest = session.ring.latest
    if latest is None or t1 < t0:
        return NdjsonResponse(iter(()))
    encoded = frames.history(session.ring, t0, t1)
    return NdjsonResponse(_log_lines(encoded, latest.gen))


@router.get("/api/generations/{number}/diff", tags=["session"], responses=error_responses(404))
async def generation_diff(studio: StudioDep, number: int = FastApiPath(ge=0, le=2**62)) -> GenerationDiff:
    """What a hot reload (or reset, fork) changed: per behavior file, its unified diff.

    Against generation ``number - 1``, from the sources the session keeps of recent generations.
    """
    session = studio.session
    if not session.keeps_sources:
        raise HTTPException(404, "a replay keeps no behavior sources per generation")
    try:
        return session.generations.diff(number)
    except GenerationGone as error:
        raise HTTPException(404, str(error)) from None


# -- files ------------------------------------------------------------------------------------------


@router.get("/api/files", tags=["files"], responses=error_responses())
async def list_files(studio: StudioDep) -> FileList:
    """Every behavior file: path, version, size, the behaviors it belongs to."""
    listed = await asyncio.to_thread(studio.files.list)
    return {"files": [{**item, "programs": studio.programs_of(item["path"])} for item in listed]}


@router.get("/api/files/{path:path}", tags=["files"], responses=error_responses(400, 404, 415))
async def read_file(studio: StudioDep, path: FilePath) -> JSONResponse:
    """A file's text and version (also as ETag)."""
    text, version = await asyncio.to_thread(studio.files.read, path)
    return JSONResponse({"path": path, "version": version, "text": text}, headers={"ETag": f'"{version}"'})


@router.put("/api/files/{path:path}", tags=["files"], responses=error_responses(400, 404, 409, 413, 422, 428))
async def write_file(
    studio: StudioDep, path: FilePath, body: FileBody, if_match: str | None = Header(default=None)
) -> Response:
    """Replace a file (If-Match: its version); compile; hot-swap when clean, else 422."""
    expected = _etag(if_match) or body.version
    async with studio.write_lock:
        version = await asyncio.to_thread(studio.files.write, path, body.text, expected)
        return await studio.after_write([path], version, 200)


@router.post(
    "/api/files/{path:path}", tags=["files"], status_code=201, responses=error_responses(400, 404, 409, 413, 422)
)
async def create_file(studio: StudioDep, path: NewFilePath, body: FileBody) -> Response:
    """Create a file (409 if it exists); compile the behaviors it belongs to."""
    async with studio.write_lock:
        version = await asyncio.to_thread(studio.files.create, path, body.text)
        return await studio.after_write([path], version, 201)


@router.patch("/api/files/{path:path}", tags=["files"], responses=error_responses(400, 404, 409, 413, 422))
async def rename_file(
    studio: StudioDep, path: FilePath, body: RenameBody, if_match: str | None = Header(default=None)
) -> Response:
    """Rename a file to ``body.path`` (409 if that exists)."""
    async with studio.write_lock:
        version = await asyncio.to_thread(studio.files.rename, path, body.path, _etag(if_match))
        return await studio.after_write([path, body.path], version, 200, deleted=path)


@router.delete("/api/files/{path:path}", tags=["files"], responses=error_responses(400, 404, 409, 422))
async def delete_file(studio: StudioDep, path: FilePath, if_match: str | None = Header(default=None)) -> Response:
    """Delete a file; compile the behaviors it belonged to."""
    async with studio.write_lock:
        await asyncio.to_thread(studio.files.delete, path, _etag(if_match))
        return await studio.after_write([path], None, 200, deleted=path)


@router.post("/api/compile", tags=["files"], responses=error_responses(400, 404, 413, 422))
async def compile_text(studio: StudioDep, body: CompileBody) -> CompileResult:
    """Diagnostics for unsaved text of a file (nothing is saved or swapped): as-you-type linting."""
    real = studio.files.resolve(body.path, must_exist=False)
    keys = studio.programs_of(body.path)
    diagnostics: list[ProgramDiagnostic] = []
    ok = True
    for key in keys:
        compilation = await asyncio.to_thread(studio.session.compile, key, {str(real): body.text})
        ok = ok and compilation.ok
        diagnostics.extend({**d.as_dict(), "program": key} for d in compilation.diagnostics)
    return {"ok": ok, "diagnostics": diagnostics, "programs": keys}


# -- graphs ------------------------------------------------------------------------------------------


def _running(studio: Studio, key: str) -> Program:
    shown = studio.session.shown_program(key)
    if shown is None:
        raise HTTPException(404, f"no running behavior {key!r}")
    return shown


async def _svg(studio: Studio, request: Request, dot: str) -> Response:
    try:
        svg, etag = await asyncio.to_thread(studio.graphs.svg, dot)
    except GraphvizMissing as error:
        raise HTTPException(503, str(error)) from None
    except subprocess.TimeoutExpired as error:
        raise HTTPException(503, f"Graphviz took longer than {error.timeout:g} s to lay out this graph") from None
    if _etag(request.headers.get("if-none-match")) == etag:
        return Response(status_code=304, headers={"ETag": f'"{etag}"'})
    return Response(svg, media_type="image/svg+xml", headers={"ETag": f'"{etag}"', "Cache-Control": "no-cache"})


_SVG_RESPONSES: dict[int | str, dict[str, Any]] = {
    **error_responses(404, 422, 503),
    200: {"description": "the graph", "content": {"image/svg+xml": {"schema": {"type": "string"}}}},
    304: {"description": "the SVG of the If-None-Match ETag is still current"},
}


#: The longest ``collapse`` list of one graph request (group keys are folder paths).
MAX_COLLAPSE_CHARS = 4000
#: Between two group keys in ``collapse`` (no folder name of a behavior set has one).
COLLAPSE_SEPARATOR = "|"


@router.get("/api/graph/{program}", tags=["graphs"], response_class=SvgResponse, responses=_SVG_RESPONSES)
async def graph(
    studio: StudioDep,
    request: Request,
    program: str,
    agent: str | None = None,
    root: str | None = None,
    collapse: Annotated[str | None, Query(max_length=MAX_COLLAPSE_CHARS)] = None,
) -> Response:
    """The option graph below an XABSL agent's root option, or below option ``root`` (a forced root) (SVG).

    With ``collapse`` (group keys separated by ``|``; ``*`` for all, empty for none) the graph is
    grouped by source folder: the groups named are one node each, the others clusters (the groups:
    ``/api/graph-groups``). Keys that name no group are ignored (a reload may remove a folder).
    """
    collapsed = None if collapse is None else [k for k in collapse.split(COLLAPSE_SEPARATOR) if k]
    try:
        running = _running(studio, program)
        if collapsed is None:
            dot = option_graph_dot(running, agent, root)
        else:
            dot, _ = grouped_graph_dot(running, agent, root, collapsed)
    except GraphError as error:
        raise HTTPException(404, str(error)) from None
    return await _svg(studio, request, dot)


@router.get("/api/graph-groups/{program}", tags=["graphs"], responses=error_responses(404))
async def graph_groups(
    studio: StudioDep, program: str, agent: str | None = None, root: str | None = None
) -> GraphGroups:
    """The option groups of a graph (source folders, or name prefixes), with their ids.

    In the order the grouped SVG numbers them (``group_<n>``).
    """
    try:
        _, groups = grouped_graph_dot(_running(studio, program), agent, root, [])
    except GraphError as error:
        raise HTTPException(404, str(error)) from None
    return {"groups": [{"key": g.key, "options": list(g.options), "behaviors": list(g.behaviors)} for g in groups]}


@router.get("/api/graph/{program}/{option}", tags=["graphs"], response_class=SvgResponse, responses=_SVG_RESPONSES)
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


async def _recording_error(request: Request, error: Exception) -> JSONResponse:
    """A replay's file turned out damaged where a request read it: 422 with what is wrong."""
    return JSONResponse({"detail": str(error)}, status_code=422)


async def _command_error(request: Request, error: Exception) -> JSONResponse:
    return JSONResponse({"detail": str(error)}, status_code=409)


def _routers() -> tuple[APIRouter, ...]:
    """The routers every studio app includes (``create_app``)."""
    return (
        router,
        drafts_router,
        docs_router,
        profile_router,
        compare_router,
        fork_router,
        library_router,
        pictures_router,
    )


def _allowed_methods(scope: Scope) -> set[str]:
    """The methods the API's routes answer for the path of ``scope`` (empty: no route has it)."""
    allowed: set[str] = set()
    for route in (r for api in _routers() for r in api.routes):
        if isinstance(route, APIRoute) and route.matches({**scope, "method": "GET"})[0] is not Match.NONE:
            allowed.update(route.methods or ())
    if "GET" in allowed:
        allowed.add("HEAD")
    return allowed


async def _method_not_allowed(request: Request, error: Exception) -> Response:
    """405 with the methods *every* route of the path allows (one route per method in FastAPI)."""
    assert isinstance(error, StarletteHTTPException)
    if error.status_code != 405:
        return await http_exception_handler(request, error)
    allowed = _allowed_methods(request.scope)
    return JSONResponse(
        {"detail": "Method Not Allowed"}, status_code=405, headers={"Allow": ", ".join(sorted(allowed))}
    )


class WebUi(StaticFiles):
    """The built web UI at ``/``, below every route.

    A path a route has (``GET /api/command``) is that route's 405, not a missing file: the mount
    matches every path, so the router would never get to its partial matches.
    """

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Serve a file of the build, or refuse a method a route of the path does not have."""
        if scope["type"] == "http" and _allowed_methods(scope):
            raise StarletteHTTPException(405)
        await super().__call__(scope, receive, send)


async def _no_ui(request: Request) -> HTMLResponse:
    return HTMLResponse(_NO_UI)


@asynccontextmanager
async def _lifespan(app: FastAPI) -> AsyncIterator[None]:
    studio: Studio = app.state.studio
    session = studio.session
    hub = Hub(session, asyncio.get_running_loop())
    hub.token_required = studio.policy.token is not None
    studio.hub = hub
    viewers = FoxgloveServer(session, lambda command: studio.run_command(command, None), asyncio.get_running_loop())
    studio.foxglove = viewers

    def notify(entry: frames.Entry) -> None:
        hub.on_entry(entry)
        viewers.on_entry(entry)

    session.notify = notify
    session.on_crash = hub.on_crash
    session.on_breakpoint = hub.on_breakpoint
    await session.start()
    watching = None
    # The main studio watches (a recording has no files; a fork beside it runs what it was
    # started with, and its own saves reload it)
    if getattr(app.state, "serves_studios", False) and session.played is None:
        studio.watcher.watch(studio.watched_paths())
        watching = asyncio.create_task(studio.watch_files())
    try:
        yield
    finally:
        if watching is not None:
            watching.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await watching
        if getattr(app.state, "serves_studios", False):
            await studio.studios.close_all()
        await hub.close_all()
        await viewers.close_all()
        studio.foxglove = None
        session.notify = _ignore
        await session.aclose()
        studio.hub = None


def _ignore(entry: frames.Entry) -> None:
    return None


def create_app(
    session: Session,
    policy: SecurityPolicy | None = None,
    web_dist: Path | None = WEB_DIST,
    library: RecordingLibrary | None = None,
    studios: Studios | None = None,
) -> FastAPI:
    """The studio app for a session (not started yet: the app's lifespan starts and stops it).

    Args:
        session: the simulation session to serve.
        policy: security checks (default: loopback, no token).
        web_dist: the built web UI, served at ``/`` (a help page when missing).
        library: the recordings it may open beside itself (default: none but a replay's own file).
        studios: the replays and forks served beside it: given, this app is one of them (served
            under a prefix by the main app's); None: this is the main app, which serves them.
    """
    policy = policy or SecurityPolicy(token=None)
    ui = web_dist if web_dist is not None and (web_dist / "index.html").is_file() else None
    public = PublicPaths.of_build(ui)
    app = FastAPI(
        title="xabsl studio",
        version=str(VERSION),
        description="Live XABSL behavior session: see docs/protocol.md.",
        openapi_url="/api/openapi.json",
        docs_url="/api/docs",
        # beside the viewer, public with it (FastAPI's default, /docs/..., is the behavior's documentation)
        swagger_ui_oauth2_redirect_url="/api/docs/oauth2-redirect",
        redoc_url=None,
        lifespan=_lifespan,
    )
    app.state.studio = studio = Studio(session, policy)
    if library is None:
        own = [Path(session.played.path)] if session.played is not None else []
        library = RecordingLibrary(None, own)
    studio.library = library
    if studios is not None:
        studio.studios = studios
    else:  # the main app: serves the others under their prefixes, behind its checks
        main = studio

        def make_app(served: Session, beside: Studios) -> FastAPI:
            # the main studio's recordings: its Recordings dialog lists them in every tab
            return create_app(served, policy, web_dist, library=main.library, studios=beside)

        studio.studios = Studios(make_app)
        app.add_middleware(StudiosMiddleware, studios=studio.studios, public=public)
        app.state.serves_studios = True
        if session.played is None:  # a replay runs no example of its own
            plugin = session.example
            studio.studios.home_example = (Path(getattr(plugin, "path", plugin.root)), getattr(plugin, "world", None))
    app.add_middleware(SecurityMiddleware, policy=policy, public=public)
    app.add_exception_handler(FileError, _file_error)
    app.add_exception_handler(CommandError, _command_error)
    app.add_exception_handler(RecordingError, _recording_error)
    app.add_exception_handler(StarletteHTTPException, _method_not_allowed)
    for included in _routers():
        app.include_router(included, dependencies=[Depends(single_query_values)])
    app.include_router(foxglove_router)  # one websocket route (/foxglove): no query parameters of its own
    _document_messages(app)
    if ui is not None:
        app.mount("/", WebUi(directory=ui, html=True), name="web")
    else:
        app.add_api_route("/", _no_ui, methods=["GET"], include_in_schema=False)
    return app


def _document_messages(app: FastAPI) -> None:
    """Add the command and reply schemas of ``server/protocol/`` to the app's OpenAPI components."""
    base = app.openapi

    def openapi() -> dict[str, Any]:
        schema = base()
        components = schema.setdefault("components", {}).setdefault("schemas", {})
        if "Command" not in components:
            components.update(openapi_schemas())
            components["ErrorBody"] = ErrorBody.model_json_schema()
        return schema

    app.openapi = openapi  # type: ignore[method-assign]


def _log_lines(encoded: Iterator[bytes], gen: frames.Generation) -> Iterator[bytes]:
    """Decoded frames (full first, then deltas) -> one JSON line per tick with names."""
    state: dict[int, dict[str, dict[str, Any]]] = {}
    names = _names(gen)
    robots_info = gen.structure["robots"]
    for data in encoded:
        frame = orjson.loads(data)
        robots = []
        for robot in frame["robots"]:
            index = robot["id"]
            values = state.setdefault(index, {"inputs": {}, "outputs": {}})
            for kind in ("inputs", "outputs"):
                values[kind].update(robot.get(kind, {}))
            table = names.get(index)
            if table is None:
                robots.append({"id": index, "name": robots_info[index]["name"], "path": []})
                continue
            robots.append(
                {
                    "id": index,
                    "name": robots_info[index]["name"],
                    "path": [table.node(node) for node in robot["path"]],
                    "outputs": {table.outputs.get(int(k), k): v for k, v in values["outputs"].items()},
                    "inputs": {table.inputs.get(int(k), k): v for k, v in values["inputs"].items()},
                    **{k: robot[k] for k in ("fault", "forced", "overrides") if k in robot},
                }
            )
        yield orjson.dumps({"seq": frame["seq"], "t": frame["t"], "robots": robots}) + b"\n"


class _Names:
    """Id -> name tables of one program, from its program JSON (the hello's structure)."""

    def __init__(self, program: dict[str, Any]) -> None:
        self.options = {o["id"]: o for o in program["options"]}
        self.behaviors = {b["id"]: b["name"] for b in program["behaviors"]}
        self.inputs = {s["id"]: s["name"] for s in program["inputs"]}
        self.outputs = {s["id"]: s["name"] for s in program["outputs"]}

    def node(self, node: list[Any]) -> dict[str, Any]:
        """A path node (``xabsl_studio.server.protocol.types.OptionNode`` or ``BehaviorNode``) with names."""
        depth = node[DEPTH_INDEX]
        if node[0] == OPTION_NODE:
            option = self.options[node[ID_INDEX]]
            states = option["states"]
            state, option_time, state_time, decided_in, leaf = node[ID_INDEX + 1 : OPTION_PARAMS_INDEX]
            params = node[OPTION_PARAMS_INDEX]
            return {
                "depth": depth,
                "option": option["name"],
                "state": states[state]["name"],
                "option_time": option_time,
                "state_time": state_time,
                "decided_in": states[decided_in]["name"] if decided_in >= 0 else None,
                "leaf": leaf,
                "params": dict(zip((p["name"] for p in option["params"]), params, strict=False)),
            }
        time, params = node[ID_INDEX + 1], node[BEHAVIOR_PARAMS_INDEX]
        return {"depth": depth, "behavior": self.behaviors[node[ID_INDEX]], "time": time, "params": params}


def _names(gen: frames.Generation) -> dict[int, _Names]:
    tables: dict[str, _Names] = {}
    result: dict[int, _Names] = {}
    programs = gen.structure["programs"]
    for robot in gen.structure["robots"]:
        key = robot["program"]
        if key is None:
            continue
        if key not in tables:
            tables[key] = _Names(programs[key])
        result[robot["id"]] = tables[key]
    return result
