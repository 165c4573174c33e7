"""What one side of a comparison names: a behavior folder, an agents file, or ``git:REV[:PATH]``.

``xabsl diff`` and the studio's Compare view read a side as the tournament reads a version
(:mod:`xabsl_studio.engine.cli.versions`), and more:

* a folder: its ``agents.xabsl``; an agents file of any name: that file;
* ``git:REV:PATH``: the folder or agents file ``PATH`` as it was at revision ``REV`` (extracted
  with ``git archive``; PATH relative to the current directory);
* ``git:REV`` alone: the other side's path at ``REV`` (``xabsl diff git:HEAD~1 behavior``), or
  the current directory when the other side is a ``git:`` spec too.

Display names (the file:line of each change) are relative to the agents file's folder, so both
sides name their files alike.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from xabsl_studio.engine.cli import UsageError
from xabsl_studio.engine.cli.versions import GIT_PREFIX, resolve
from xabsl_studio.engine.lang import Compilation, compile_file

__all__ = ["AGENTS_FILE", "Side", "compile_side", "resolve_side"]

#: The agents file a folder stands for.
AGENTS_FILE = "agents.xabsl"


@dataclass(frozen=True, slots=True)
class Side:
    """One side: what the user wrote, the agents file on disk, the commit of a ``git:`` side."""

    spec: str
    agents_file: Path
    commit: str | None = None

    @property
    def base(self) -> Path:
        """The folder the side's display names are relative to."""
        return self.agents_file.parent

    def describe(self) -> dict[str, str | None]:
        """The side as the diff document names it."""
        return {"spec": self.spec, "agents_file": self.agents_file.name, "commit": self.commit}


def _path_of(spec: str) -> str | None:
    """The PATH a spec names (None for ``git:REV`` alone)."""
    if not spec.startswith(GIT_PREFIX):
        return spec
    _rev, colon, path = spec[len(GIT_PREFIX) :].partition(":")
    return path if colon and path else None


def resolve_side(spec: str, scratch: Path, cwd: Path | None = None, other: str | None = None) -> Side:
    """The :class:`Side` ``spec`` names; ``git:`` sides are extracted below ``scratch``.

    ``other``: the other side's spec (its PATH completes a ``git:REV`` without one).

    Raises:
        UsageError: no such folder or file, no agents file in a folder, or a ``git:`` problem
            (not a work tree, an unknown revision, a path that is not there at that revision).
    """
    cwd = (cwd or Path.cwd()).resolve()
    if spec.startswith(GIT_PREFIX):
        rev, _colon, path = spec[len(GIT_PREFIX) :].partition(":")
        if not rev:
            raise UsageError(f"{spec}: expected git:REV or git:REV:PATH, e.g. git:HEAD~1:examples/soccer/behavior")
        if not path:
            path = (_path_of(other) if other is not None else None) or "."
        file_name = None
        if path.endswith(".xabsl"):
            parent, _slash, file_name = path.rpartition("/")
            path = parent or "."
        version = resolve(f"{GIT_PREFIX}{rev}:{path}", scratch, cwd)
        agents = version.folder / (file_name or AGENTS_FILE)
        if not agents.is_file():
            raise UsageError(f"{spec}: no {file_name or AGENTS_FILE} in {path} at {rev}")
        return Side(spec, agents, version.commit)
    target = (cwd / spec).resolve()
    if target.is_dir():
        agents = target / AGENTS_FILE
        if not agents.is_file():
            raise UsageError(f"no {AGENTS_FILE} in {spec}: name the agents file")
        return Side(spec, agents)
    if target.is_file():
        return Side(spec, target)
    raise UsageError(f"no such behavior folder or agents file: {spec}")


def compile_side(side: Side) -> Compilation:
    """Compile the side's agents file, display names relative to its folder."""
    return compile_file(str(side.agents_file), base=str(side.base))
