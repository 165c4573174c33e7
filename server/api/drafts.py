"""``POST /api/tests/draft``: "Save as test", a behavior test file of the tester's situation (docs/tests.md).

The text comes from ``xabsl_studio.engine.testing.save.draft_test``, which writes every name and
value of the request as TOML data (a name is never TOML syntax) and checks that the text is one
test of that name, reading no file while it checks. Drafting runs in a worker thread (it parses
what it wrote), and so does saving.

Saving (``save``) writes ``tests/NAME.xabsl-test.toml`` in the example folder, confined: the
``tests`` folder (created when missing) must resolve inside the example folder, and nothing may be
at the file's name yet, not even a dangling link (it would be written through) or a FIFO
(409). The file is written atomically (``xabsl_studio.engine.files.write_atomically``).
"""

from __future__ import annotations

import asyncio
import os
from pathlib import Path
from typing import Annotated, Any

import orjson
from fastapi import APIRouter, Depends, HTTPException, Request

from xabsl_studio.engine.files import write_atomically
from xabsl_studio.engine.testing.save import DraftError, draft_file_name, draft_test
from xabsl_studio.engine.worlds.loader import world_names
from xabsl_studio.server.api.openapi import error_responses
from xabsl_studio.server.protocol.rest import TestDraft, TestDraftBody
from xabsl_studio.server.session.files import FileError

__all__ = ["TestDraftBody", "router", "save_draft"]

router = APIRouter()


def _studio(request: Request) -> Any:
    return request.app.state.studio


StudioDep = Annotated[Any, Depends(_studio)]


def save_draft(root: Path, file: str, text: str) -> None:
    """Write ``text`` as ``tests/FILE`` below the example folder ``root`` (see the module docstring).

    Raises:
        FileError: 403 ``tests`` leads out of the example folder or cannot be written; 409 it is
            no folder, or something is at the file's name already.
    """
    tests = root / "tests"
    try:
        tests.mkdir(exist_ok=True)
    except FileExistsError:  # a file, or a dangling link
        raise FileError(409, "tests is not a folder in the example folder") from None
    except OSError as error:
        raise FileError(403, f"cannot make the tests folder: {error.strerror or error}") from None
    real = Path(os.path.realpath(tests))
    if not real.is_relative_to(Path(os.path.realpath(root))):
        raise FileError(403, f"tests leads out of the example folder (to {real}): not saved")
    if not real.is_dir():
        raise FileError(409, "tests is not a folder in the example folder")
    target = real / file
    if os.path.lexists(target):
        raise FileError(409, f"tests/{file} exists already")
    try:
        write_atomically(target, text.encode("utf-8"))
    except OSError as error:
        raise FileError(403, f"cannot save tests/{file}: {error.strerror or error}") from None


@router.post("/api/tests/draft", tags=["files"], responses=error_responses(400, 409, 422))
async def test_draft(studio: StudioDep, body: TestDraftBody) -> TestDraft:
    """A behavior test file reproducing the tester's situation (text; with ``save``, also written).

    The setup comes from the world's latest scene when the world plug-in can turn a scene into a
    setup (``setup_from_scene``); the file goes to the example folder's ``tests/`` (409 if it exists,
    403 if ``tests`` leads out of the example folder). With ``hit``, the scene is the hit's tick and
    the assertions are the breakpoint's (409 when the breakpoint was removed or the tick left the
    history).
    """
    session = studio.session
    plugin = session.example
    latest = session.ring.latest
    hit = None
    if body.hit is not None:
        point = session.breakpoints.get(body.hit.program, {}).get(body.hit.breakpoint)
        if point is None:
            raise HTTPException(409, f"no breakpoint {body.hit.breakpoint} in {body.hit.program!r} (removed?)")
        latest = session.ring.get(body.hit.seq)
        if latest is None or not latest.scene:  # the ring keeps scenes of its newest ticks only
            raise HTTPException(409, f"the world at tick {body.hit.seq} is no longer kept; save from a recent hit")
        hit = (point, body.robot, body.hit.seq, latest.t)
    scene = orjson.loads(latest.scene) if latest is not None else {}
    status = orjson.loads(latest.status) if latest is not None else {}
    gen = session.generation
    agents = orjson.loads(gen.scene_bytes).get("agents", []) if gen is not None else []
    names = [str(a.get("name")) for a in agents if isinstance(a, dict)]
    if body.robot not in names:
        raise HTTPException(409, f"no robot {body.robot!r} in this session")
    example = getattr(plugin, "example", plugin)
    describe = getattr(example, "setup_from_scene", None)
    setup = describe(scene, status, names) if callable(describe) and scene else None
    root = Path(plugin.root)
    where = Path(getattr(plugin, "path", plugin.root))

    def draft() -> tuple[str, str]:
        world = getattr(plugin, "world", None)
        if world is None and not (where / "studio.py").is_file() and plugin.name in world_names():
            world = plugin.name  # a folder without studio.py served in a named world: name it
        return draft_file_name(body.name), draft_test(
            name=body.name,
            robot=body.robot,
            tests_folder=root / "tests",
            example_path=where,
            world=world,
            options=getattr(plugin, "options", {}),
            seed=session.seed,
            setup=setup,
            force=(body.force.kind, body.force.name, body.force.params) if body.force is not None else None,
            overrides=body.overrides,
            active=body.active,
            behaviors=body.behaviors,
            duration=body.duration,
            hit=hit,
        )

    try:
        file, text = await asyncio.to_thread(draft)
    except (DraftError, ValueError) as error:
        raise HTTPException(422, str(error)) from None
    if body.save:
        async with studio.write_lock:
            await asyncio.to_thread(save_draft, root, file, text)
    return {"text": text, "path": f"tests/{file}", "saved": body.save}
