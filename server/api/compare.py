"""``/api/compare``: the studio's Compare view, the structural diff of two versions of a behavior set.

Two routes, behind the same token, Origin and Host checks as every ``/api`` route
(``xabsl_studio.server.api.security``):

* ``GET /api/compare?program=KEY&old=SPEC[&new=SPEC][&recording=NAME&against=NAME]``: version
  ``old`` against ``new`` (default ``running``) of behavior set ``KEY``, as the document of
  ``xabsl diff --json`` (docs/compare.md) with the marked option graph and state machines (SVG).
  Given two recordings of the studio's library (``recording`` of the new version, ``against`` of
  the old one), the option graph is also coloured by each option's change of time share
  (``xabsl profile --against``);
* ``GET /api/compare/diverge?recording=NAME&against=NAME``: where two library recordings of one
  seed (two versions, or a fork and its original) first act differently, per robot, with both
  paths and both whys: the document of ``xabsl diverge --json``, for the timeline's mark;
* ``GET /api/compare/generations/{number}``: what generation ``number`` (a hot reload) changed
  against ``number - 1``, for every behavior set it changed: the structural view of the
  timeline's reload mark, beside its text diff (``GET /api/generations/{number}/diff``).

A ``SPEC`` is ``running`` (what the session runs), ``git:REV`` (the set's agents file at revision
``REV`` of the git repository holding it), ``git:REV:PATH``, ``recording:NAME`` (the behavior a
library recording ran: how a fork's original compares with it) or a folder or agents file.
Paths are relative to the example folder and confined to it and the behavior set's folders
(403 otherwise); nothing else of the disk is read. Every side is compiled with its display names
relative to its agents file's folder, so both sides name their files alike.
"""

from __future__ import annotations

import asyncio
import tempfile
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

from fastapi import APIRouter, HTTPException, Query, Request
from fastapi import Path as FastApiPath

from xabsl_studio.engine.cli import UsageError
from xabsl_studio.engine.cli.sides import resolve_side
from xabsl_studio.engine.cli.versions import GIT_PREFIX
from xabsl_studio.engine.compare import StructuralDiff, diff_programs
from xabsl_studio.engine.compare.diverge import diverge
from xabsl_studio.engine.compare.graphs import draw
from xabsl_studio.engine.compare.report import document
from xabsl_studio.engine.docs.graphs import GraphLayoutError
from xabsl_studio.engine.emit.dot import GraphvizMissing
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.profile import ProfileError, profile
from xabsl_studio.engine.profile.against import compare_reports
from xabsl_studio.engine.record import Recording, RecordingError
from xabsl_studio.engine.record.sources import compile_sources
from xabsl_studio.server.api.openapi import error_responses
from xabsl_studio.server.protocol.errors import ServerError
from xabsl_studio.server.session.live import ProgramState, Session

router = APIRouter()

RUNNING = "running"
RECORDING_PREFIX = "recording:"
#: One comparison at a time: compiling and Graphviz share the machine's cores with the simulation.
_LOCK = threading.Lock()


class VersionError(ServerError):
    """A version that cannot be compared; ``status`` is the HTTP answer."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


def _state(session: Session, key: str) -> ProgramState:
    if not session.keeps_sources or key not in session.programs:
        known = ", ".join(session.programs) if session.keeps_sources else ""
        raise VersionError(
            404, f"no behavior set {key!r} in this studio" + (f" (behavior sets: {known})" if known else "")
        )
    return session.programs[key]


def _compiled(agents: Path, overrides: dict[str, str] | None, what: str) -> Program:
    compilation = compile_file(str(agents), base=str(agents.parent), overrides=overrides)
    if compilation.program is None:
        first = "; ".join(d.format() for d in compilation.errors[:3])
        raise VersionError(422, f"{what} does not compile: {first}")
    return compilation.program


def _from_texts(state: ProgramState, root: Path, texts: dict[str, str] | None, what: str) -> Program:
    """The behavior set compiled from ``texts`` (display name relative to ``root`` -> text)."""
    if texts is None:
        raise VersionError(404, f"{what}: no source texts are kept")
    overrides = {str(root / name): text for name, text in texts.items()}
    return _compiled(state.source.agents_file, overrides, what)


def _inside(path: Path, folders: list[Path]) -> bool:
    real = path.resolve()
    return any(real == f or real.is_relative_to(f) for f in folders)


def version(session: Session, studio: Any, key: str, spec: str, scratch: Path) -> tuple[Program, dict[str, Any]]:
    """The program ``spec`` names for behavior set ``key``, and how the document describes it.

    Raises:
        VersionError: an unknown set, a spec outside the confinement (403), a missing folder,
            revision or recording (404), a malformed spec (400), a version with errors (422).
    """
    state = _state(session, key)
    root = Path(session.example.root).resolve()
    agents = state.source.agents_file.resolve()
    folders = [root, *(Path(f).resolve() for f in state.source.file_folders)]
    if spec == RUNNING:
        return _from_texts(state, root, state.running_sources, "the running behavior"), {"spec": spec}
    if spec.startswith(RECORDING_PREFIX):
        return _recorded(studio, key, spec[len(RECORDING_PREFIX) :]), {"spec": spec}
    if spec.startswith(GIT_PREFIX):
        rev, colon, path = spec[len(GIT_PREFIX) :].partition(":")
        if rev.startswith("-"):
            raise VersionError(400, f"{spec}: not a revision")
        if not colon or not path:  # the set's own agents file at REV
            if not agents.is_relative_to(root):
                raise VersionError(403, f"{spec}: the agents file is outside the example folder")
            spec_path = agents.relative_to(root).as_posix()
        else:
            spec_path = path
        if not _inside(root / spec_path, folders):
            raise VersionError(403, f"{spec}: {spec_path} is outside the behavior set's folders")
        full = f"{GIT_PREFIX}{rev}:{spec_path}"
    else:
        if not _inside(root / spec, folders):
            raise VersionError(403, f"{spec} is outside the behavior set's folders")
        full = spec
    try:
        side = resolve_side(full, scratch, cwd=root)
    except UsageError as error:
        raise VersionError(404, str(error)) from None
    return _compiled(side.agents_file, None, spec), side.describe()


def _recorded(studio: Any, key: str, name: str) -> Program:
    try:
        path = studio.library.resolve(name)
    except LookupError as error:
        raise VersionError(404, str(error)) from None
    try:
        with Recording(path) as recording:
            views = [v for (k, _gen), v in sorted(recording.programs.items()) if k == key]
            if not views:
                raise VersionError(404, f"{name} has no behavior set {key!r}")
            sources = views[0].sources
            if sources is None:
                raise VersionError(404, f"{name} keeps no source files of {key!r}")
            return compile_sources(sources, f"{key} of {name}")
    except RecordingError as error:
        raise VersionError(422, str(error)) from None


def _shares(studio: Any, key: str, new: str, old: str) -> dict[str, dict[str, Any]]:
    """Per option the behavioral diff of recording ``new`` against ``old`` (team ``key`` where both have it)."""
    reports = []
    for name in (new, old):
        try:
            path = studio.library.resolve(name)
        except LookupError as error:
            raise VersionError(404, str(error)) from None
        try:
            with Recording(path) as recording:
                reports.append(profile(recording))
        except RecordingError as error:
            raise VersionError(422, f"{name}: {error}") from None
    team = key if all(key in r["teams"] for r in reports) else None
    try:
        compared = compare_reports(reports[0], reports[1], team)
    except ProfileError as error:
        raise VersionError(422, str(error)) from None
    rows = compared["comparisons"][0]["options"]
    return {
        row["option"]: {
            "a": row["a"]["share"],
            "b": row["b"]["share"],
            "change": row["change"]["share"],
            "significant": row["change"]["significant"],
            "only_in": row["only_in"],
        }
        for row in rows
    }


def _drawn(diff: StructuralDiff, shares: dict[str, dict[str, Any]] | None) -> tuple[dict[str, Any] | None, str | None]:
    tooltips = None
    if shares:
        tooltips = {
            name: (
                s["change"],
                f"{name}: {100 * s['a']:.1f} % of robot time vs {100 * s['b']:.1f} % ({100 * s['change']:+.1f} points"
                + (", significant)" if s["significant"] else ")"),
            )
            for name, s in shares.items()
        }
    try:
        drawings = draw(diff, tooltips, jobs=1)
    except (GraphvizMissing, GraphLayoutError) as error:
        return None, str(error)
    return {"option_graph": drawings.option_graph, "state_machines": drawings.state_machines}, None


def _answer(studio: Any, key: str, old: str, new: str, recording: str | None, against: str | None) -> dict[str, Any]:
    session: Session = studio.session
    with tempfile.TemporaryDirectory(prefix="xabsl-compare-") as scratch:
        old_program, old_side = version(session, studio, key, old, Path(scratch) / "old")
        new_program, new_side = version(session, studio, key, new, Path(scratch) / "new")
    diff = diff_programs(old_program, new_program)
    shares = _shares(studio, key, recording, against) if recording and against else None
    svg, note = _drawn(diff, shares)
    return {"program": key, "diff": document(diff, old_side, new_side), "svg": svg, "note": note, "shares": shares}


def _locked(work: Callable[..., dict[str, Any]], *args: Any) -> dict[str, Any]:
    with _LOCK:
        return work(*args)


@router.get("/api/compare", tags=["compare"], responses=error_responses(400, 404, 422))
async def compare(
    request: Request,
    program: str = Query(min_length=1, max_length=200, description="the behavior set (its key)"),
    old: str = Query(min_length=1, max_length=1000, description="running, git:REV[:PATH], recording:NAME or a path"),
    new: str = Query(RUNNING, min_length=1, max_length=1000, description="the other version (default: running)"),
    recording: str | None = Query(None, max_length=300, description="a library recording of the new version"),
    against: str | None = Query(None, max_length=300, description="a library recording of the old version"),
) -> dict[str, Any]:
    """The structural diff of two versions of a behavior set, with the marked drawings (docs/compare.md).

    With ``recording`` and ``against`` (both or neither: one alone is 404), ``shares`` has each option's time share
    in both and the option graph is coloured by its change.
    """
    if bool(recording) != bool(against):  # a recording without the one to compare it with is not there
        raise HTTPException(404, "no recording to compare with: give both recording and against, or neither")
    studio = request.app.state.studio
    try:
        return await asyncio.to_thread(_locked, _answer, studio, program, old, new, recording, against)
    except VersionError as error:
        raise HTTPException(error.status, str(error)) from None


def _diverge(studio: Any, recording: str, against: str) -> dict[str, Any]:
    paths = []
    for name in (recording, against):
        try:
            paths.append(studio.library.resolve(name))
        except LookupError as error:
            raise VersionError(404, str(error)) from None
    try:
        with Recording(paths[0]) as a, Recording(paths[1]) as b:
            answer: dict[str, Any] = diverge(a, b).to_json()
    except RecordingError as error:
        raise VersionError(422, str(error)) from None
    # the studio names recordings by their library names, never by where they lie on disk
    answer.update(a=recording, b=against)
    return answer


@router.get("/api/compare/diverge", tags=["compare"], responses=error_responses(404, 422))
async def compare_diverge(
    request: Request,
    recording: str = Query(min_length=1, max_length=300, description="a library recording"),
    against: str = Query(min_length=1, max_length=300, description="the library recording to compare it with"),
) -> dict[str, Any]:
    """The first tick each robot acts differently in two recordings, both paths and both whys (``xabsl diverge``)."""
    studio = request.app.state.studio
    try:
        return await asyncio.to_thread(_locked, _diverge, studio, recording, against)
    except VersionError as error:
        raise HTTPException(error.status, str(error)) from None


def _generations(studio: Any, number: int, program: str | None) -> dict[str, Any]:
    session: Session = studio.session
    if not session.keeps_sources:
        raise VersionError(404, "a replay keeps no behavior sources per generation")
    gen, previous = session.generations.get(number), session.generations.get(number - 1)
    if gen is None or previous is None:
        raise VersionError(404, f"generation {number} or the one before it is not kept (any more)")
    root = Path(session.example.root).resolve()
    keys = [program] if program is not None else sorted(gen.changed)
    programs = []
    for key in keys:
        state = _state(session, key)
        before = _from_texts(state, root, dict(previous.sources.get(key, {})) or None, f"generation {number - 1}")
        after = _from_texts(state, root, dict(gen.sources.get(key, {})) or None, f"generation {number}")
        diff = diff_programs(before, after)
        svg, note = _drawn(diff, None)
        sides = ({"spec": f"generation {number - 1}"}, {"spec": f"generation {number}"})
        programs.append({"program": key, "diff": document(diff, *sides), "svg": svg, "note": note})
    return {"number": number, "previous": number - 1, "reason": gen.reason, "programs": programs}


@router.get("/api/compare/generations/{number}", tags=["compare"], responses=error_responses(404, 422))
async def compare_generations(
    request: Request,
    number: int = FastApiPath(ge=1, le=2**62),
    program: str | None = Query(
        None, min_length=1, max_length=200, description="one behavior set (default: all changed)"
    ),
) -> dict[str, Any]:
    """What generation ``number`` changed against ``number - 1``, structurally, per behavior set it changed."""
    studio = request.app.state.studio
    try:
        return await asyncio.to_thread(_locked, _generations, studio, number, program)
    except VersionError as error:
        raise HTTPException(error.status, str(error)) from None
