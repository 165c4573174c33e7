"""The REST API's bodies and results (``/api/...``, docs/protocol.md "REST"), each defined once.

Bodies are pydantic models: FastAPI validates requests with them and documents them in
``/api/openapi.json``. Results are ``TypedDict``s: the routes and the session build them (mypy
checks every key against these definitions), ``tsgen`` generates them into
``web/src/messages.gen.ts`` beside the websocket messages, and tests validate real answers of a
running studio against them with no key the definition lacks. The diagnostic and span shapes are
the engine's own (``xabsl_studio.engine.lang.diagnostics.DiagnosticJson``,
``xabsl_studio.engine.types.SpanJson``).
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, JsonValue, with_config
from typing_extensions import TypedDict

from xabsl_studio.engine.lang.diagnostics import DiagnosticJson

#: What a new file name may not hold, as a regular-expression class body (for session/files.py's
#: check and the OpenAPI pattern of new names): C0 and C1 controls, DEL, every space but U+0020, the
#: line and paragraph separators, the invisible format characters (soft hyphen, zero-width
#: characters, bidi embeddings, overrides and isolates, word joiners, the BOM, annotation marks).
#: Lone surrogates are refused by ``check_syntax`` (no Unicode); in a class, they would not be an
#: ECMA pattern.
INVISIBLE = (
    r"\x00-\x1f\x7f-\xa0\xad\u061c\u1680\u180e\u2000-\u200f\u2028-\u202f\u205f-\u2064\u2066-\u206f"
    r"\u3000\ufeff\ufff9-\ufffb"
)
#: A behavior file's path in the API: relative, no hidden part, ends in ``.xabsl``.
FILE_PATH_PATTERN = r"^([^/\\\x00.][^/\\\x00]*/)*[^/\\\x00.][^/\\\x00]*\.xabsl$"
#: What the path of a file the studio creates looks like: its name is visible (:data:`INVISIBLE`),
#: neither blank nor starting or ending with a space.
NEW_FILE_PATH_PATTERN = (
    r"^([^/\\\x00.][^/\\\x00]*/)*" + f"[^/\\\\ .{INVISIBLE}]([^/\\\\{INVISIBLE}]*[^/\\\\ {INVISIBLE}])?" + r"\.xabsl$"
)

#: A recording's name as the recordings list gives it (no folder part).
RECORDING_NAME_PATTERN = r"^[A-Za-z0-9_][A-Za-z0-9_.+-]{0,200}\.mcap$"

#: Results are checked against these in tests: a key the server sends that is not declared fails.
_RESULT = ConfigDict(extra="forbid")

# -- bodies ----------------------------------------------------------------------------------------


class FileBody(BaseModel):
    """The body of writing or creating a file."""

    text: str = Field(description="the whole file content")
    version: str | None = Field(default=None, description="the version edited (instead of If-Match)")


class RenameBody(BaseModel):
    """The body of renaming a file."""

    path: str = Field(
        description="the new path, relative to the example folder",
        json_schema_extra={"pattern": NEW_FILE_PATH_PATTERN},
    )


class CompileBody(BaseModel):
    """The body of compiling unsaved text."""

    path: str = Field(
        description="the file the text belongs to, relative to the example folder", pattern=FILE_PATH_PATTERN
    )
    text: str = Field(description="its unsaved content")


class TestForce(BaseModel):
    """What the tester forced: an option or basic behavior and its parameters (enums by element name)."""

    kind: str = Field(pattern="^(option|behavior)$")
    name: str = Field(min_length=1, max_length=200)
    params: dict[str, JsonValue] = Field(default_factory=dict)


class TestHit(BaseModel):
    """A breakpoint hit to reproduce: breakpoint ``breakpoint`` of behavior ``program`` after tick ``seq``."""

    program: str = Field(min_length=1, max_length=500)
    breakpoint: int = Field(ge=1, le=2**31)
    seq: int = Field(ge=0)


class TestDraftBody(BaseModel):
    """Save as test: the tester's situation (docs/tests.md); ``save`` writes ``tests/NAME.xabsl-test.toml``."""

    name: str = Field(min_length=1, max_length=120)
    robot: str = Field(min_length=1, max_length=120)
    force: TestForce | None = None
    overrides: dict[str, JsonValue] = Field(default_factory=dict)
    active: list[tuple[str, str]] = Field(default_factory=list, max_length=500)
    behaviors: list[str] = Field(default_factory=list, max_length=500)
    duration: float = Field(5.0, gt=0, le=3600)
    hit: TestHit | None = None
    save: bool = False


class OpenBody(BaseModel):
    """Which recording to open."""

    name: str = Field(description="a recording's name as listed", pattern=RECORDING_NAME_PATTERN, max_length=210)


class ForkBody(BaseModel):
    """Run from here: the tick of the replay to start the live session from."""

    seq: int = Field(ge=1, le=2**40, description="the fork tick (the first tick the new session runs)")
    robot: int = Field(
        default=0,
        ge=0,
        le=1000,
        description="a recording that cannot run again (an attached session's): the robot forked into the bench world",
    )


# -- results ---------------------------------------------------------------------------------------


@with_config(_RESULT)
class FileStat(TypedDict):
    """A behavior file on disk: its path in the API, its version (content hash), its size in bytes."""

    path: str
    version: str
    size: int


@with_config(_RESULT)
class FileEntry(FileStat):
    """One behavior file of ``GET /api/files``: also the behavior sets it belongs to."""

    programs: list[str]


@with_config(_RESULT)
class FileList(TypedDict):
    """``GET /api/files``: every behavior file below the behavior folders."""

    files: list[FileEntry]


@with_config(_RESULT)
class FileText(TypedDict):
    """``GET /api/files/{path}``: a file's text and version (also its ETag)."""

    path: str
    version: str
    text: str


@with_config(_RESULT)
class ProgramDiagnostic(DiagnosticJson):
    """A diagnostic of one behavior set of a save or a compile (``program``: the set's key)."""

    program: str


@with_config(_RESULT)
class _SaveResult(TypedDict):
    path: str
    version: str | None
    saved: bool
    ok: bool
    diagnostics: list[ProgramDiagnostic]
    reloaded: list[str]


@with_config(_RESULT)
class SaveResult(_SaveResult, total=False):
    """A write, create, rename or delete: what was saved, and the recompile of its behavior sets.

    ``detail`` (with status 422): saved, but a behavior set did not compile.
    """

    detail: str


@with_config(_RESULT)
class Recompiled(TypedDict):
    """One behavior set compiled from disk after a change (``reload``'s ``programs``, a save).

    ``error``: why it was not swapped in (its diagnostics' errors, or the engine refused it).
    """

    ok: bool
    diagnostics: list[DiagnosticJson]
    error: str | None


@with_config(_RESULT)
class CompileResult(TypedDict):
    """``POST /api/compile``: diagnostics of unsaved text (nothing saved or swapped)."""

    ok: bool
    diagnostics: list[ProgramDiagnostic]
    programs: list[str]


@with_config(_RESULT)
class ProgramStatus(TypedDict):
    """One behavior set in ``GET /api/status``: its last compile and what runs."""

    folder: str
    agents_file: str
    ok: bool
    running: bool
    #: nothing compiled clean yet: the studio shows what parsed
    partial: bool
    error: str | None
    diagnostics: list[DiagnosticJson]
    files: list[str]


@with_config(_RESULT)
class ReplayInfo(TypedDict):
    """``replay`` of ``GET /api/status`` on a replay: the recording and the playback position."""

    file: str
    ticks: int
    first: int
    position: int
    #: behavior times (ms) of the first and the last tick
    t0: int
    t1: int
    seconds: float
    header: dict[str, Any]
    events: int
    seeks: int
    seek_ms: float


@with_config(_RESULT)
class TestDraft(TypedDict):
    """``POST /api/tests/draft``: the behavior test file reproducing the tester's situation."""

    text: str
    path: str
    saved: bool


@with_config(_RESULT)
class ChangedFile(TypedDict):
    """One behavior file a generation changed."""

    program: str
    path: str
    change: Literal["changed", "added", "removed"]
    #: a unified diff from the previous generation's text to this one's
    diff: str


@with_config(_RESULT)
class GenerationDiff(TypedDict):
    """``GET /api/generations/{n}/diff``: what generation ``n`` changed against ``n - 1``."""

    number: int
    reason: str
    previous: int
    files: list[ChangedFile]


@with_config(_RESULT)
class OptionGroupJson(TypedDict):
    """One group of an option graph (``xabsl_studio.engine.emit.groups.OptionGroup``).

    A source folder or name prefix with its options' ids, or the called basic behaviors' ids.
    """

    key: str
    options: list[int]
    behaviors: list[int]


@with_config(_RESULT)
class GraphGroups(TypedDict):
    """``GET /api/graph-groups/{program}``: the groups in the order the grouped SVG numbers them."""

    groups: list[OptionGroupJson]


@with_config(_RESULT)
class _NamedNode(TypedDict):
    depth: int


@with_config(_RESULT)
class NamedNode(_NamedNode, total=False):
    """A path node by name (``xabsl_studio.server.session.forkdiff``): an option and its state, or a basic behavior."""

    option: str
    state: str | None
    behavior: str


@with_config(_RESULT)
class DecisionJson(TypedDict):
    """What one decision did at a tick (from the recorded values of that tick: ``explain``)."""

    decided_in: str
    target: str
    stay: bool
    leaf: int


@with_config(_RESULT)
class RobotDivergenceJson(TypedDict):
    """One robot's first fork tick ``seq`` whose path differs from the original's tick ``original_seq``.

    ``option`` is the option whose decision makes them part (null: no option, e.g. a fault);
    ``why_fork`` and ``why_original`` what it did on each side (null: not explainable).
    ``uncompared_before``: fork ticks just before ``seq`` that could not be compared (a sample of
    either run was dropped: the paths may have parted in one of them; 0: the tick before was
    compared and equal).
    """

    robot: int
    name: str
    seq: int
    t: int
    original_seq: int
    uncompared_before: int
    fork_path: list[NamedNode]
    original_path: list[NamedNode]
    option: str | None
    why_fork: DecisionJson | None
    why_original: DecisionJson | None


@with_config(_RESULT)
class ForkDivergenceJson(TypedDict):
    """``GET /api/fork/diverge``: where the running fork first acts differently from its original, per robot.

    Every fork tick up to ``scanned`` was compared; ``ended``: the original run ends (or left the
    history) before the fork's next tick, so nothing later compares. ``earliest``: the first of
    ``robots`` (null: no robot acts differently so far).
    """

    fork_seq: int
    fork_t: int
    start: int
    scanned: int
    ended: bool
    robots: list[RobotDivergenceJson]
    earliest: RobotDivergenceJson | None


#: Every result, printed as a TypeScript interface by ``tsgen``.
RESULTS: tuple[type, ...] = (
    FileStat,
    FileEntry,
    FileList,
    FileText,
    SaveResult,
    Recompiled,
    CompileResult,
    ProgramStatus,
    ReplayInfo,
    TestDraft,
    ChangedFile,
    GenerationDiff,
    OptionGroupJson,
    GraphGroups,
    NamedNode,
    DecisionJson,
    RobotDivergenceJson,
    ForkDivergenceJson,
)
#: Every body, printed as a TypeScript interface by ``tsgen`` (what the web UI sends).
BODIES: tuple[type, ...] = (FileBody, RenameBody, CompileBody, TestDraftBody, OpenBody, ForkBody)
