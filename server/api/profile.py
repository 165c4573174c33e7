"""``GET /api/profile``: the profile (xabsl_studio.engine.profile) of the live session's ring buffer.

Counted here, in the server process, from the ticks the ring already keeps (every tick of the
last ``RING_SECONDS``, each entry's encoded delta holds every robot's path): the browser only
receives the ticks its frame rate lets through, so counts made there would miss activations and
short oscillations. One request decodes each entry once (about 5 µs of JSON per robot and tick);
the result is cached until the ring has a newer tick. The report is the document of
docs/profile.md with the robots' names as agents, ``seq`` of the session's ticks (what the
timeline seeks) and coverage against the programs of the newest generation in the ring.
"""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Iterator
from typing import Any

import orjson
from fastapi import APIRouter, HTTPException, Query, Request
from fastapi.responses import Response

from xabsl_studio.engine.profile import build_report
from xabsl_studio.engine.profile.analysis import count_paths
from xabsl_studio.server.api.openapi import error_responses
from xabsl_studio.server.session.frames import Entry
from xabsl_studio.server.session.live import Session

router = APIRouter()
_LOCK = threading.Lock()


def _rows(entries: list[Entry], robot: str | None) -> Iterator[tuple[int, int, str, int, list[list[Any]]]]:
    for entry in entries:
        gen = entry.gen
        robots = gen.structure["robots"]
        frame = orjson.loads(entry.delta)
        for r in frame["robots"]:
            index = r["id"]
            if not gen.engines[index] or not r.get("path"):
                continue
            name = robots[index]["name"]
            if robot is None or name == robot:
                yield entry.seq, entry.t, name, gen.number, r["path"]


def session_profile(session: Session, robot: str | None = None, oscillation_ms: float = 1000.0) -> dict[str, Any]:
    """The profile of the ticks in ``session``'s ring (of ``robot`` only, when given).

    Raises:
        KeyError: no robot with an XABSL engine is named ``robot``.
    """
    entries = session.ring.snapshot()
    programs: dict[int, dict[str, Any]] = {}
    names: list[str] = []
    for entry in entries:
        gen = entry.gen
        if gen.number not in programs:
            programs[gen.number] = gen.structure
            for index, r in enumerate(gen.structure["robots"]):
                if gen.engines[index] and r["name"] not in names:
                    names.append(r["name"])
    if robot is not None:
        if robot not in names:
            raise KeyError(robot)
        names = [robot]

    def program_of(agent: str, gen: int) -> tuple[str, dict[str, Any]]:
        structure = programs[gen]
        key = next(r["program"] for r in structure["robots"] if r["name"] == agent)
        return key, structure["programs"][key]

    tick_ms = 1000.0 / session.behavior_hz
    counts, times = count_paths(_rows(entries, robot), names, program_of, tick_ms, oscillation_ms)
    latest: dict[str, dict[str, Any]] = {}
    newest = programs[max(programs)] if programs else {"programs": {}}
    for c in counts:
        latest[c.key] = newest["programs"].get(c.key) or program_of(c.agent, c.gen)[1]
    meta = {"recording": None, "example": None, "seed": session.seed, "ticks": len(entries)}
    report = build_report(counts, times, names, latest, tick_ms, oscillation_ms, meta)
    report["robots"] = {
        r["name"]: r["id"] for structure in programs.values() for r in structure["robots"] if r["name"] in names
    }
    return report


@router.get("/api/profile", tags=["session"], responses=error_responses(404, 422))
async def profile(
    request: Request,
    robot: str | None = None,
    oscillation_ms: float = Query(1000.0, gt=0, le=3_600_000, description="left and re-entered within this many ms"),
) -> Response:
    """The profile of the session's ring buffer (docs/profile.md; ``robot``: one robot by name)."""
    session: Session = request.app.state.studio.session
    latest = session.ring.latest
    key = (latest.seq if latest is not None else None, robot, oscillation_ms)
    cached: tuple[Any, bytes] | None = getattr(request.app.state, "profile_cache", None)
    if cached is not None and cached[0] == key:
        return Response(cached[1], media_type="application/json")

    def run() -> bytes:
        with _LOCK:  # one count at a time: two tabs asking at once share the machine's core
            return orjson.dumps(session_profile(session, robot, oscillation_ms))

    try:
        body = await asyncio.to_thread(run)
    except KeyError:
        raise HTTPException(404, f"no robot {robot!r} with an XABSL agent in the session") from None
    request.app.state.profile_cache = (key, body)
    return Response(body, media_type="application/json")
