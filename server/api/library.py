"""The recordings a studio may open: its record folder and the files named on its command line.

:class:`RecordingLibrary` lists them (newest first: name, size, time, ticks, duration, example,
whether the run was deterministic, what a fork was forked from) and resolves a name a client sent
to a file, confined: a name is a plain file name (no folder part, no ``..``, ending in ``.mcap``)
of a regular file directly in the folder, or the name of a file given on the command line;
nothing else is opened, whatever the name says.

The routes (``router``): ``GET /api/recordings`` lists them and the studios open beside this one,
``POST /api/recordings/open`` opens one as a replay (``xabsl_studio.server.api.studios``; the same file twice is
the same replay), ``DELETE /api/recordings/open/{id}`` closes a replay or a fork, and
``POST /api/fork`` ("Run from here", in a replay of a deterministic recording) starts a live
session from a tick of it.
"""

from __future__ import annotations

import asyncio
import logging
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Annotated, Any

from fastapi import APIRouter, Depends, HTTPException, Request

from xabsl_studio.engine.record.recover import RecoveryFailed, in_use, recover
from xabsl_studio.server.api.openapi import error_responses
from xabsl_studio.server.api.studios import StudioFull, Studios
from xabsl_studio.server.protocol.rest import RECORDING_NAME_PATTERN, ForkBody, OpenBody

__all__ = ["RecordingLibrary", "router"]

#: What a recording's name may look like (a plain file name).
_NAME = re.compile(RECORDING_NAME_PATTERN)
log = logging.getLogger("xabsl.server")
#: The most recordings listed (newest first).
MAX_LISTED = 500


class RecordingLibrary:
    """The recordings a studio may open (see the module docstring).

    Args:
        folder: the record folder (None: none; a missing folder lists nothing).
        files: further recordings named on the command line (``xabsl serve --replay FILE``).
    """

    def __init__(self, folder: Path | None, files: Iterable[Path] = ()) -> None:
        self.folder = folder.expanduser().resolve() if folder is not None else None
        self.files = {p.name: p.expanduser().resolve() for p in files}
        self._info: dict[tuple[str, int, int], dict[str, Any]] = {}
        #: cut recordings (``.mcap.part``) that could not be recovered: why, and the file's version then
        self._unrecoverable: dict[str, tuple[str, tuple[int, int] | None]] = {}

    def resolve(self, name: str) -> Path:
        """The file of recording ``name``.

        Raises:
            LookupError: not a recording of this library (the message says why).
        """
        if not _NAME.match(name) or ".." in name:
            raise LookupError(f"not a recording name: {name!r} (a plain file name ending in .mcap)")
        given = self.files.get(name)
        if given is not None:
            return given
        if self.folder is None:
            raise LookupError(f"no recording {name!r} (this studio has no record folder)")
        path = self.folder / name
        # A link in the folder must not lead out of it: the resolved file is in the folder itself.
        real = path.resolve()
        if real.parent != self.folder or not real.is_file():
            raise LookupError(f"no recording {name!r} in {self.folder}")
        return real

    def list(self) -> list[dict[str, Any]]:
        """The recordings, newest first (header facts read once per file version).

        A file that cannot be read is an entry with its ``error``; a cut one nobody writes
        (``NAME.mcap.part``) is recovered first (``xabsl_studio.engine.record.recover``), and listed
        with its error if it cannot be; one being written is not listed (it is once it closes).
        """
        paths: dict[str, Path] = {}
        parts: dict[str, Path] = {}
        if self.folder is not None and self.folder.is_dir():
            for path in self.folder.glob("*.mcap.part"):
                if _NAME.match(path.name.removesuffix(".part")) and _inside(path, self.folder):
                    parts[path.name] = path
            for name, path in sorted(parts.items()):
                version = _version(path)
                if not in_use(path) and self._unrecoverable.get(name, ("", None))[1] != version:
                    try:
                        recover(path)
                    except RecoveryFailed as error:
                        self._unrecoverable[name] = (error.reason or str(error), version)
            for path in self.folder.glob("*.mcap"):
                if _NAME.match(path.name) and _inside(path, self.folder):
                    paths[path.name] = path
        paths.update({n: p for n, p in self.files.items() if p.is_file()})
        rows = []
        for name, path in [*paths.items(), *parts.items()]:
            try:
                stat = path.stat()
            except OSError:  # gone since the glob (recovered, pruned)
                continue
            rows.append((stat.st_mtime, name, path, stat.st_size))
        rows.sort(reverse=True)
        out = []
        info: dict[str, Any] | None
        for mtime, name, path, size in rows[:MAX_LISTED]:
            if name in parts:
                if in_use(path):  # being written: listed once it closes
                    continue
                reason = self._unrecoverable.get(name, ("cut", None))[0]
                info = {"error": f"cut by its writer and cannot be recovered: {reason}"}
                out.append({"name": name, "size": size, "modified": round(mtime, 3), **info})
                continue
            key = (str(path), int(mtime * 1e6), size)
            info = self._info.get(key)
            if info is None:
                info = self._info[key] = _facts(path)
            out.append({"name": name, "size": size, "modified": round(mtime, 3), **info})
        return out


def _version(path: Path) -> tuple[int, int] | None:
    """A file's size and modification time (None if it is gone)."""
    try:
        stat = path.stat()
    except OSError:
        return None
    return stat.st_size, stat.st_mtime_ns


def _inside(path: Path, folder: Path) -> bool:
    """A regular file directly in ``folder`` after resolving links (a link out of it is not listed)."""
    try:
        real = path.resolve()
        return real.parent == folder and real.is_file()
    except OSError:
        return False


def _facts(path: Path) -> dict[str, Any]:
    from xabsl_studio.engine.errors import XabslError
    from xabsl_studio.engine.record import Recording

    try:
        with Recording(path) as recording:
            header = recording.header
            hz = recording.behavior_hz
            return {
                "example": header.get("example"),
                "world": header.get("world"),
                "ticks": len(recording),
                "first": recording.first,
                "seconds": round(len(recording) / hz, 3),
                "agents": len(recording.agents),
                "deterministic": bool(header.get("deterministic")),
                "forked_from": header.get("forked_from"),
                "cut": recording.cut,
                "error": None,
            }
    except (XabslError, OSError) as error:
        return {"error": str(error).removeprefix(f"{path}: ")}
    except Exception as error:  # one unreadable file must never cost the listing of the others
        log.exception("reading the recording %s failed", path)
        return {"error": f"cannot be read ({type(error).__name__})"}


router = APIRouter()


def _studio(request: Request) -> Any:
    return request.app.state.studio


StudioDep = Annotated[Any, Depends(_studio)]


def _studios(studio: Any) -> Studios:
    studios: Studios = studio.studios
    return studios


@router.get("/api/recordings", tags=["recordings"], responses=error_responses())
async def list_recordings(studio: StudioDep) -> dict[str, Any]:
    """The recordings this studio may open (newest first) and the replays and forks open now."""
    library: RecordingLibrary = studio.library
    listed = await asyncio.to_thread(library.list)
    folder = str(library.folder) if library.folder is not None else None
    return {"folder": folder, "recordings": listed, "open": _studios(studio).describe()}


@router.post("/api/recordings/open", tags=["recordings"], responses=error_responses(400, 404, 409, 422))
async def open_recording(studio: StudioDep, body: OpenBody) -> dict[str, Any]:
    """Open a recording as a replay beside this studio; its address (``/replay/ID/``)."""
    from xabsl_studio.engine.host import ExampleError
    from xabsl_studio.server.session.replay import ReplaySession

    library: RecordingLibrary = studio.library
    try:
        path = library.resolve(body.name)
    except LookupError as error:
        raise HTTPException(404, str(error)) from None
    studios = _studios(studio)
    existing = studios.find("replay", file=body.name, path=str(path))
    if existing is not None:
        return existing.describe()
    try:
        session = await asyncio.to_thread(ReplaySession, path)
    except ExampleError as error:
        raise HTTPException(422, str(error)) from None
    try:
        opened = await studios.add("replay", session.example.name, session, {"file": body.name, "path": str(path)})
    except StudioFull as error:
        raise HTTPException(409, str(error)) from None
    return opened.describe()


@router.delete("/api/recordings/open/{ident}", tags=["recordings"], responses=error_responses(404))
async def close_studio(studio: StudioDep, ident: int) -> dict[str, Any]:
    """Close a replay or a fork opened beside this studio."""
    if not await _studios(studio).close(ident):
        raise HTTPException(404, f"no replay or fork {ident} is open")
    return {"closed": ident}


@router.post("/api/fork", tags=["recordings"], responses=error_responses(400, 409, 422))
async def fork_recording(studio: StudioDep, body: ForkBody) -> dict[str, Any]:
    """Run from here: a live session from tick ``seq`` of this replay, with the behaviors on disk.

    The new session's simulation re-simulates the recording to ``seq`` (its first ticks are the
    recording's) and goes on live with the behaviors on disk (those of the main studio's example
    folder when it serves the recorded example, else the installed example's); it is served
    beside this one (``/fork/ID/``). A recording that cannot be re-simulated but holds its
    behavior's sources (an attached session's, docs/attach.md) forks robot ``robot`` into the
    bench world instead, fed its recorded inputs from ``seq`` on. 409: this is not
    a replay, or too many forks run; 422: the recording cannot be forked (not deterministic, no
    such example on this machine, a tick outside it).
    """
    from xabsl_studio.server.session.fork import ForkError, fork_session

    recording = studio.session.played
    if recording is None:
        raise HTTPException(409, "run from here forks a replay; this studio runs live")
    try:
        forked = await asyncio.to_thread(fork_session, recording, body.seq, _studios(studio).home_example, body.robot)
    except ForkError as error:
        raise HTTPException(422, str(error)) from None
    name = Path(recording.path).name
    try:
        opened = await _studios(studio).add(
            "fork", f"{forked.example.name} (fork of {name} at {body.seq})", forked, {"file": name, "seq": body.seq}
        )
    except StudioFull as error:
        raise HTTPException(409, str(error)) from None
    except (RuntimeError, OSError) as error:  # the simulation ended while re-simulating: its reason
        reason = str(error).removeprefix("the simulation stopped: ").removesuffix("; reset starts it again")
        raise HTTPException(422, f"the fork did not start: {reason}") from None
    return opened.describe()
