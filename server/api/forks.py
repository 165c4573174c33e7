"""The original run beside a live fork (docs/studio.md "Fork").

After a ``fork`` the ring still holds the original run's ticks at older seqs.

* ``GET /api/fork/original?seq=``: for a tick of the fork, the original's tick with the same
  world time (``xabsl_studio.server.session.forkdiff.original_tick``) and every robot's activation
  path by name (the two runs may have different program versions, so ids would not compare), for
  the studio to show next to the fork's own path;
* ``GET /api/fork/diverge``: per robot, the first fork tick whose path differs from the
  original's (``xabsl_studio.server.session.forkdiff``), both paths, the option where they part
  and what its decision did on each side, for the timeline's mark.
"""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, HTTPException, Query, Request

from xabsl_studio.server.api.openapi import error_responses
from xabsl_studio.server.protocol.commands import Explain
from xabsl_studio.server.protocol.rest import DecisionJson, ForkDivergenceJson, RobotDivergenceJson
from xabsl_studio.server.session.forkdiff import ForkDivergence, named_paths, original_tick
from xabsl_studio.server.session.live import CommandError, Session

router = APIRouter()


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


@router.get("/api/fork/diverge", tags=["session"], responses=error_responses(404))
async def diverge(request: Request) -> ForkDivergenceJson:
    """Where the running fork first acts differently from the run it was forked from, per robot.

    Compares the fork's ticks with the original's at the same world times as they arrive (each
    tick once per fork). 404: the running world is no fork.
    """
    session: Session = request.app.state.studio.session
    fork = session.fork
    if fork is None:
        raise HTTPException(404, "the running world is not a fork (fork: run from a tick of the timeline)")
    state = request.app.state
    scan: ForkDivergence | None = getattr(state, "fork_divergence", None)
    if scan is None or scan.fork != fork:
        scan = state.fork_divergence = ForkDivergence(fork)
    scan.update(session.ring)
    for robot, found in scan.found.items():
        if robot not in scan.explained:
            scan.explained[robot] = await _with_whys(session, found)
    robots = sorted(scan.explained.values(), key=lambda d: (d["seq"], d["robot"]))
    return {
        "fork_seq": fork.seq,
        "fork_t": fork.t,
        "start": fork.start,
        "scanned": scan.scanned,
        "ended": scan.beyond,
        "robots": robots,
        "earliest": robots[0] if robots else None,
    }


async def _with_whys(session: Session, found: RobotDivergenceJson) -> RobotDivergenceJson:
    """The divergence with what the parting option's decision did at the two ticks."""
    option = found["option"]

    async def why(seq: int) -> DecisionJson | None:
        if option is None:
            return None
        try:
            answer = await session.explain(Explain(op="explain", robot=found["robot"], option=option, seq=seq), None)
        except CommandError:  # the tick left the ring, or the option did not run in it
            return None
        return {
            "decided_in": str(answer["decided_in_name"]),
            "target": str(answer["target_name"]),
            "stay": bool(answer["stay"]),
            "leaf": int(answer["leaf"]),
        }

    return {**found, "why_fork": await why(found["seq"]), "why_original": await why(found["original_seq"])}
