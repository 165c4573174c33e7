"""The behavior's source files in a recording: what a fork re-simulates the recorded ticks with.

A fork (:mod:`xabsl_studio.engine.record.fork`) runs ticks ``0 .. k - 1`` again before it goes on with the
behavior on disk, and those ticks must run the behavior that was recorded, not an edited one. The
program description of ``/xabsl/program`` is for display and cannot be run, so the recorder
keeps the texts of the include closure (``sources`` of the ``xabsl.Program`` message):
``{"agents": "agents.xabsl", "files": {"agents.xabsl": "...", "../behavior/x.xabsl": "..."}}``,
names relative to the agents file's folder. :func:`compile_sources` compiles them again in a
temporary folder laid out the same way.
"""

from __future__ import annotations

import os
import posixpath
import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.record.reader import RecordingError

__all__ = ["compile_sources", "program_sources", "same_sources", "write_sources"]


def program_sources(
    agents_file: str | os.PathLike[str], files: Iterable[str], base: Path | None = None
) -> dict[str, Any]:
    """The ``sources`` of a program compiled from ``agents_file``, read from disk now.

    Args:
        agents_file: the agents file the program was compiled from.
        files: the program's files (``Program.files``: display names, relative to ``base``).
        base: what relative display names are relative to (default: the working directory).

    Raises:
        OSError: a file cannot be read.
    """
    agents = Path(agents_file).resolve()
    folder = agents.parent
    where = base if base is not None else Path.cwd()
    texts: dict[str, str] = {}
    for name in [*files, str(agents)]:
        path = Path(name) if os.path.isabs(name) else where / name
        relative = Path(os.path.relpath(path.resolve(), folder)).as_posix()
        if relative not in texts:
            texts[relative] = path.read_text(encoding="utf-8")
    return {"agents": agents.name, "files": dict(sorted(texts.items()))}


def same_sources(a: Mapping[str, Any] | None, b: Mapping[str, Any] | None) -> bool:
    """True when two ``sources`` hold the same files with the same texts."""
    return a is not None and b is not None and a.get("agents") == b.get("agents") and a.get("files") == b.get("files")


#: The most folders a recorded source name may climb (``../``) above the agents file's folder.
_MAX_UPS = 16
#: The longest part of a recorded source name, in bytes (file systems take 255).
_MAX_PART = 200


def compile_sources(sources: Mapping[str, Any], what: str = "the recorded behavior") -> Program:
    """Compile recorded ``sources`` again (in a temporary folder with the recorded layout).

    Raises:
        RecordingError: a malformed ``sources`` (names leaving their folder) or compile errors.
    """
    from xabsl_studio.engine.lang import compile_file  # the compiler only when a fork needs it

    with tempfile.TemporaryDirectory(prefix="xabsl-fork-") as tmp:
        base, agents_file = write_sources(sources, Path(tmp), what)
        compilation = compile_file(str(agents_file), str(base))
    if compilation.program is None:
        errors = "; ".join(str(d) for d in compilation.errors[:3])
        raise RecordingError(f"{what} does not compile again: {errors}")
    return compilation.program


def write_sources(sources: Mapping[str, Any], folder: Path, what: str = "the recorded behavior") -> tuple[Path, Path]:
    """Write recorded ``sources`` under ``folder`` with the recorded layout: (their base folder, the agents file).

    Names may climb out of the agents file's folder (``../common/x.xabsl``), never out of ``folder``.

    Raises:
        RecordingError: malformed ``sources`` (names leaving their folder, texts that are not text).
    """
    files = sources.get("files")
    agents = sources.get("agents")
    if not isinstance(files, dict) or not isinstance(agents, str) or agents not in files:
        raise RecordingError(f"{what}: malformed sources")
    normal: dict[str, str] = {}
    depth = 0
    for name, text in files.items():
        clean = posixpath.normpath(str(name))
        parts = clean.split("/")
        ups = len(parts) - len([p for p in parts if p != ".."])
        if clean.startswith("/") or ".." in parts[ups:] or not isinstance(text, str):
            raise RecordingError(f"{what}: malformed source file name {name!r}")
        # A name the temporary folder can hold: no NUL or control characters, short parts, few levels up.
        if ups > _MAX_UPS or any(not p or len(p.encode()) > _MAX_PART or not p.isprintable() for p in parts):
            raise RecordingError(f"{what}: malformed source file name {str(name)[:80]!r}")
        depth = max(depth, ups)
        normal[clean] = text
    base = folder.joinpath(*(["up"] * depth), "_xabsl_fork_agents")
    try:
        for name, text in normal.items():
            path = Path(os.path.normpath(base / name))
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text, encoding="utf-8")
    except (OSError, UnicodeError) as error:
        raise RecordingError(f"{what}: its source files cannot be written again ({error})") from None
    return base, base / posixpath.normpath(agents)
