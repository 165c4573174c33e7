"""Which behavior a tournament side plays: a folder, or a folder at a git revision.

``git:REV:PATH`` names the folder ``PATH`` (relative to the current directory, inside a git
work tree) as it was at revision ``REV`` (``HEAD~1``, a branch, a tag, a commit); it is extracted
with ``git archive`` into a temporary folder, so ``git:HEAD~1:examples/soccer/behavior`` against
``examples/soccer/behavior`` compares the last commit with the working tree. The extracted folder
must hold the agents file's whole include closure (the example team's does).

The tree is confined to its folder: ``tarfile``'s ``data`` filter extracts regular files,
folders and links that stay inside it; a link to an absolute path or out of the folder (or
anything else the filter refuses) is a :class:`~xabsl_studio.engine.cli.UsageError` naming the
entry. The archive ``git`` writes is read up to :data:`MAX_TREE_BYTES`.
"""

from __future__ import annotations

import io
import subprocess
import tarfile
import tempfile
from dataclasses import dataclass
from pathlib import Path

from xabsl_studio.engine.cli import UsageError

GIT_PREFIX = "git:"
#: The largest ``git archive`` of a behavior folder read (a team's folder is some hundred kB).
MAX_TREE_BYTES = 256 * 1024 * 1024


@dataclass(frozen=True, slots=True)
class Version:
    """One side of a tournament: what the user wrote (``spec``) and the folder it names on disk."""

    spec: str
    folder: Path
    #: the commit a ``git:`` version was extracted from (None for a plain folder)
    commit: str | None = None


def _git(args: list[str], cwd: Path, limit: int = MAX_TREE_BYTES) -> bytes:
    """What ``git ARGS`` writes (at most ``limit`` bytes), or UsageError with git's last line."""
    # stderr goes to a file: a pipe that filled up while stdout is read would stall git for good
    try:
        with (
            tempfile.TemporaryFile() as errors,
            subprocess.Popen(
                ["git", *args], cwd=cwd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=errors
            ) as process,
        ):
            assert process.stdout is not None
            out = process.stdout.read(limit + 1)
            if len(out) > limit:
                process.kill()
                raise UsageError(f"git {' '.join(args)}: more than {limit} bytes")
            returncode = process.wait()
            errors.seek(0)
            err = errors.read(64 * 1024)
    except FileNotFoundError as error:
        raise UsageError("git:REV:PATH needs the git command, which is not installed") from error
    if returncode != 0:
        message = err.decode("utf-8", "replace").strip().splitlines()
        raise UsageError(f"git {' '.join(args)}: {message[-1] if message else 'failed'}")
    return out


def _why(error: tarfile.FilterError) -> str:
    if isinstance(error, tarfile.AbsoluteLinkError):
        return "(an absolute path)"
    if isinstance(error, tarfile.LinkOutsideDestinationError | tarfile.OutsideDestinationError):
        return "(outside the folder)"
    return f"({error})"


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
        try:
            tar.extractall(out, filter="data")
        except tarfile.FilterError as error:
            member = error.tarinfo
            what = f"a link to {member.linkname}" if member.issym() or member.islnk() else "an entry"
            raise UsageError(
                f"{spec}: {member.name} at {rev} is {what} {_why(error)}; only files inside {path} are read"
            ) from None
    folder = out / relative
    if not folder.is_dir():
        raise UsageError(f"{spec}: {relative} is not a folder at {rev}")
    return Version(spec, folder, commit_id)
