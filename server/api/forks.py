"""``GET /api/fork/original``: the original run beside a fork, at the fork's ticks (docs/studio.md "Fork").

After a ``fork`` the ring still holds the original run's ticks at older seqs: for a tick of the
fork this finds the original's tick with the same world time (``xabsl_studio.server.session.live.original_tick``)
and answers every robot's activation path by name (the two runs may have different program
versions, so ids would not compare), for the studio to show next to the fork's own path.
"""

from __future__ import annotations

from typing import Any

import orjson
from fastapi import APIRouter, HTTPException, Query, Request

from xabsl_studio.engine.runtime.activation import BEHAVIOR_NODE, OPTION_NODE
from xabsl_studio.server.api.openapi import error_responses
from xabsl_studio.server.protocol.types import ID_INDEX
from xabsl_studio.server.session.frames import Entry
from xabsl_studio.server.session.live import Session, original_tick

router = APIRouter()


def named_paths(entry: Entry) -> list[dict[str, Any]]:
    """Every robot of ``entry``: id, name, path (``{"depth", "option", "state"}``, ``{"depth", "behavior"}``)."""
    structure = entry.gen.structure
    frame = orjson.loads(entry.delta)
    robots = []
    for robot in frame["robots"]:
        info = structure["robots"][robot["id"]]
        program = structure["programs"].get(info["program"]) if info["program"] is not None else None
        options = {o["id"]: o for o in program["options"]} if program else {}
        behaviors = {b["id"]: b["name"] for b in program["behaviors"]} if program else {}
        path: list[dict[str, Any]] = []
        for node in robot["path"]:
            if node[0] == OPTION_NODE and node[ID_INDEX] in options:
                option = options[node[ID_INDEX]]
                state = node[ID_INDEX + 1]
                states = option["states"]
                path.append(
                    {
                        "depth": node[1],
                        "option": option["name"],
                        "state": states[state]["name"] if 0 <= state < len(states) else None,
                    }
                )
            elif node[0] == BEHAVIOR_NODE and node[ID_INDEX] in behaviors:
                path.append({"depth": node[1], "behavior": behaviors[node[ID_INDEX]]})
        robots.append({"id": robot["id"], "name": info["name"], "path": path})
    return robots


@router.get("/api/fork/original", tags=["session"], responses=error_responses(404))
async def original(request: Request, seq: int = Query(ge=0, le=2**62, description="a tick of the fork")) -> Any:
    """The original run's tick at the world time of the fork's tick ``seq``: seq, t and named paths.

    404: the running world is no fork, ``seq`` is not one of its ticks in the ring, or the
    original's tick at that time left the ring (or the original never ran that far).
    """
    session: Session = request.app.state.studio.session
    fork = session.fork
    if fork is None:
        raise HTTPException(404, "the running world is not a fork (fork: run from a tick of the timeline)")
    entry = original_tick(session.ring, fork, seq)
    if entry is None:
        raise HTTPException(404, f"no tick of the original run at the time of tick {seq} is in the history")
    origin = {"seq": fork.seq, "t": fork.t, "start": fork.start}
    return {"seq": entry.seq, "t": entry.t, "fork": origin, "robots": named_paths(entry)}
