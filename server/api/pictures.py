"""``GET /api/picture/...``: the studio's graphs as files to take away (SVG, PNG, PDF).

The same pictures as ``xabsl picture`` (:mod:`xabsl_studio.engine.docs.pictures`), of the
behavior the studio draws (``Session.shown_program``):

* ``/api/picture/{program}?format=F[&agent=A][&root=X]``: the option graph below agent ``A``'s
  root (default: the first agent) or below option ``X`` (a subtree);
  ``&robot=N[&seq=S]`` adds what robot ``N`` ran at tick ``S`` of the session (default: the
  newest tick), from the ticks the server keeps (its ring);
* ``/api/picture/{program}/{option}?format=F[&robot=N][&seq=S]``: the option's state machine, with
  that tick's active state and the transition that fired.

Like every route, these need the token. The answer is an attachment named after what it shows.
Bad input is a 4xx with a message: an unknown behavior, agent, option or robot, or a tick no
longer kept (404), a tick of an older version of the behavior (409), a malformed parameter (422);
a missing Graphviz is a 503.
"""

from __future__ import annotations

import asyncio
import re
from typing import Any, Literal

import orjson
from fastapi import APIRouter, HTTPException, Query, Request
from fastapi.responses import Response

from xabsl_studio.engine.docs.pictures import (
    FORMATS,
    PictureError,
    Ran,
    activation_graph,
    activation_machine,
    for_paper,
    render,
)
from xabsl_studio.engine.emit.dot import GraphvizMissing, option_graph
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.server.api.openapi import error_responses
from xabsl_studio.server.session.live import Session

router = APIRouter()

Format = Literal["svg", "png", "pdf"]

_RESPONSES: dict[int | str, dict[str, Any]] = {
    **error_responses(404, 409, 422, 503),
    200: {
        "description": "the picture, as an attachment",
        "content": {media: {"schema": {"type": "string", "format": "binary"}} for media in FORMATS.values()},
    },
}


class PictureResponse(Response):
    """A picture: SVG, PNG or PDF."""

    media_type = "application/octet-stream"


def _session(request: Request) -> Session:
    session: Session = request.app.state.studio.session
    return session


def _program(request: Request, key: str) -> Program:
    program = _session(request).shown_program(key)
    if program is None:
        raise HTTPException(404, f"no behavior {key!r} in this studio")
    return program


def _ran(request: Request, key: str, program: Program, robot: int, seq: int | None) -> tuple[Ran, list[Any], str]:
    """What ``robot`` ran at tick ``seq`` (default: the newest), its path, and a title."""
    session = _session(request)
    entry = session.ring.latest if seq is None else session.ring.get(seq)
    if entry is None:
        raise HTTPException(404, "no tick yet" if seq is None else f"tick {seq} is no longer kept")
    current = session.generation
    if current is not None and entry.gen.number != current.number:
        raise HTTPException(409, f"tick {entry.seq} ran an older version of the behavior")
    robots = entry.gen.structure.get("robots", [])
    if not 0 <= robot < len(robots):
        raise HTTPException(404, f"no robot {robot} (robots 0..{len(robots) - 1})")
    if robots[robot].get("program") != key:
        raise HTTPException(404, f"robot {robot} does not run behavior {key!r}")
    frame = orjson.loads(entry.delta)
    path = next((r.get("path") for r in frame.get("robots", []) if r.get("id") == robot), None)
    if not path:
        raise HTTPException(404, f"robot {robot} ran no behavior at tick {entry.seq}")
    try:
        ran = Ran.from_path(program, path)
    except ValueError as error:
        raise HTTPException(409, f"tick {entry.seq}: {error}") from None
    name = robots[robot].get("name", f"robot {robot}")
    return ran, path, f"{name} at tick {entry.seq} ({entry.t / 1000:.2f} s)"


async def _picture(dot: str, format: str, name: str) -> Response:
    try:
        data = await asyncio.to_thread(render, dot, format)
    except GraphvizMissing as error:
        raise HTTPException(503, str(error)) from None
    except PictureError as error:
        raise HTTPException(503, str(error)) from None
    filename = re.sub(r"[^A-Za-z0-9_.-]+", "_", name)[:120] + f".{format}"
    return Response(
        data,
        media_type=FORMATS[format],
        headers={"Content-Disposition": f'attachment; filename="{filename}"', "Cache-Control": "no-store"},
    )


@router.get("/api/picture/{program}", tags=["graphs"], response_class=PictureResponse, responses=_RESPONSES)
async def graph_picture(
    request: Request,
    program: str,
    format: Format = "svg",
    agent: str | None = Query(None, max_length=200),
    root: str | None = Query(None, max_length=200),
    robot: int | None = Query(None, ge=0, le=1000),
    seq: int | None = Query(None, ge=0, le=2**62),
) -> Response:
    """The option graph (whole for an agent, or below ``root``), with a robot's tick if asked, as a file."""
    ir = _program(request, program)
    if root is not None and root not in ir.options:
        raise HTTPException(404, f"no option {root!r} in this behavior")
    if seq is not None and robot is None:
        raise HTTPException(422, "seq needs robot: whose tick to draw")
    chosen = None
    if root is None and ir.agents:
        chosen = next((a for a in ir.agents if a.name == agent), None) if agent else ir.agents[0]
        if chosen is None:
            raise HTTPException(404, f"no agent {agent!r} in this behavior")
    if robot is not None:
        ran, path, title = _ran(request, program, ir, robot, seq)
        if root is None and agent is None:  # the graph below what the robot runs (an agent's root or a forced one)
            by_index = {o.index: o.name for o in ir.options.values()}
            root = next((by_index.get(n[2]) for n in path if n[0] == 0 and n[1] == 0), None)
        top = root or (chosen.root if chosen else None)
        return await _picture(activation_graph(ir, ran, top, title), format, f"{program}-{top or 'graph'}-tick")
    top = root or (chosen.root if chosen else None)
    heading = f"below {root}" if root else f"agent {chosen.name}" if chosen else None
    return await _picture(for_paper(option_graph(ir, top), heading), format, f"{program}-{top or 'graph'}")


@router.get("/api/picture/{program}/{option}", tags=["graphs"], response_class=PictureResponse, responses=_RESPONSES)
async def machine_picture(
    request: Request,
    program: str,
    option: str,
    format: Format = "svg",
    robot: int | None = Query(None, ge=0, le=1000),
    seq: int | None = Query(None, ge=0, le=2**62),
) -> Response:
    """One option's state machine (a name or an id), with a robot's tick if asked, as a file."""
    ir = _program(request, program)
    found = ir.options.get(option)
    if found is None and option.isdigit():
        found = next((o for o in ir.options.values() if o.index == int(option)), None)
    if found is None:
        raise HTTPException(404, f"no option {option!r} in this behavior")
    if seq is not None and robot is None:
        raise HTTPException(422, "seq needs robot: whose tick to draw")
    if robot is None:
        return await _picture(activation_machine(found, None, f"option {found.name}"), format, found.name)
    ran, _, title = _ran(request, program, ir, robot, seq)
    state = ran.states.get(found.name)
    shown = f"{found.name}: {state}" if state else f"{found.name} (not running)"
    return await _picture(activation_machine(found, ran, f"{title}, {shown}"), format, f"{found.name}-tick")
