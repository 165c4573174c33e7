"""Which behavior a tournament side plays: a folder, or a folder at a git revision.

``git:REV:PATH`` names the folder ``PATH`` (relative to the current directory, inside a git
work tree) as it was at revision ``REV`` (``HEAD~1``, a branch, a tag, a commit); it is extracted
with ``git archive`` into a temporary folder, so ``git:HEAD~1:examples/soccer/behavior`` against
``examples/soccer/behavior`` compares the last commit with the working tree. The extracted folder
must hold the agents file's whole include closure (the example team's does).
"""

from __future__ import annotations

import io
import subprocess
import tarfile
from dataclasses import dataclass
from pathlib import Path

from xabsl_studio.engine.cli import UsageError

GIT_PREFIX = "git:"


@dataclass(frozen=True, slots=True)
class Version:
    """One side of a tournament: what the user wrote (``spec``) and the folder it names on disk."""

    spec: str
    folder: Path
    #: the commit a ``git:`` version was extracted from (None for a plain folder)
    commit: str | None = None


def _git(args: list[str], cwd: Path) -> bytes:
    try:
        done = subprocess.run(["git", *args], cwd=cwd, capture_output=True, check=False)
    except FileNotFoundError as error:
        raise UsageError("git:REV:PATH needs the git command, which is not installed") from error
    if done.returncode != 0:
        message = done.stderr.decode("utf-8", "replace").strip().splitlines()
        raise UsageError(f"git {' '.join(args)}: {message[-1] if message else 'failed'}")
    return done.stdout


def resolve(spec: str, scratch: Path, cwd: Path | None = None) -> Version:
    """The :class:`Version` that ``spec`` names; ``git:`` versions are extracted below ``scratch``.

    Raises:
        UsageError: a malformed ``git:`` spec, not a git work tree, an unknown revision, a path
            that does not exist at that revision, or a folder that does not exist.
    """
    cwd = (cwd or Path.cwd()).resolve()
    if not spec.startswith(GIT_PREFIX):
        folder = (cwd / spec).resolve()
        if not folder.is_dir():
            raise UsageError(f"no such behavior folder: {spec}")
        return Version(spec, folder)
    rev, colon, path = spec[len(GIT_PREFIX) :].partition(":")
    if not colon or not rev or not path:
        raise UsageError(f"{spec}: expected git:REV:PATH, e.g. git:HEAD~1:examples/soccer/behavior")
    top = Path(_git(["rev-parse", "--show-toplevel"], cwd).decode().strip()).resolve()
    try:
        resolved = _git(["rev-parse", "--verify", "--quiet", "--end-of-options", f"{rev}^{{commit}}"], cwd)
    except UsageError as error:
        raise UsageError(f"{spec}: unknown revision {rev!r} in {top}") from error
    commit_id = resolved.decode().strip()
    target = (cwd / path).resolve()
    if not target.is_relative_to(top):
        raise UsageError(f"{spec}: {path} is outside the git work tree {top}")
    relative = target.relative_to(top).as_posix() or "."
    archive = _git(["archive", "--format=tar", commit_id, "--", relative], top)
    out = scratch / commit_id[:12]
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        tar.extractall(out, filter="data")
    folder = out / relative
    if not folder.is_dir():
        raise UsageError(f"{spec}: {relative} is not a folder at {rev}")
    return Version(spec, folder, commit_id)
