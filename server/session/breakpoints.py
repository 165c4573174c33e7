"""The studio's breakpoints: kept per behavior set in the server process, stored per agents file.

The simulation process checks breakpoints (``xabsl_studio.engine.runtime.breakpoints``, fed by
:class:`~xabsl_studio.server.protocol.host.SetBreakpoints`); this module owns what outlives it: the breakpoints of
every behavior set, checked against its running program when set, and their file. One JSON file
per behavior (``<state folder>/breakpoints/<digest of the agents file path>.json``, written
atomically) holds ``{"agents_file", "breakpoints": [...]}``; the state folder is
``$XABSL_STATE_DIR``, else ``$XDG_STATE_HOME/xabsl-studio``, else ``~/.local/state/xabsl-studio``.
A file that cannot be read is reported in the log and ignored (never fatal).
"""

from __future__ import annotations

import hashlib
import logging
import os
from collections.abc import Iterable
from pathlib import Path

import orjson

from xabsl_studio.engine.files import write_atomically
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.runtime.breakpoints import Breakpoint, BreakpointError, check_breakpoint

__all__ = ["BreakpointStore", "state_folder", "validate"]

log = logging.getLogger("xabsl.server")


def state_folder() -> Path:
    """Where the studio keeps state between sessions (see the module docstring)."""
    explicit = os.environ.get("XABSL_STATE_DIR")
    if explicit:
        return Path(explicit)
    xdg = os.environ.get("XDG_STATE_HOME")
    base = Path(xdg) if xdg else Path.home() / ".local" / "state"
    return base / "xabsl-studio"


def validate(program: Program | None, point: Breakpoint) -> None:
    """Check ``point`` against ``program`` (its names, its condition's symbols).

    Raises:
        BreakpointError: it names nothing of the program, or the condition has errors.
    """
    if program is None:
        point.require_fields()
        return
    check_breakpoint(program, point)


class BreakpointStore:
    """Reads and writes the breakpoints file of each agents file under ``folder``."""

    def __init__(self, folder: Path | None = None) -> None:
        self.folder = (folder or state_folder()) / "breakpoints"

    def path(self, agents_file: Path) -> Path:
        """The file that holds the breakpoints of ``agents_file``."""
        digest = hashlib.sha256(str(agents_file.resolve()).encode()).hexdigest()[:16]
        return self.folder / f"{digest}.json"

    def load(self, agents_file: Path) -> list[Breakpoint]:
        """The stored breakpoints of ``agents_file`` (none when there is no file or it is unreadable)."""
        path = self.path(agents_file)
        try:
            data = orjson.loads(path.read_bytes())
        except FileNotFoundError:
            return []
        except (OSError, orjson.JSONDecodeError) as error:
            log.warning("ignoring the breakpoints file %s: %s", path, error)
            return []
        points: list[Breakpoint] = []
        for item in data.get("breakpoints", []) if isinstance(data, dict) else []:
            try:
                points.append(Breakpoint.from_dict(item))
            except BreakpointError as error:
                log.warning("ignoring a breakpoint in %s: %s", path, error)
        return points

    def save(self, agents_file: Path, points: Iterable[Breakpoint]) -> None:
        """Write the breakpoints of ``agents_file`` (atomically)."""
        path = self.path(agents_file)
        path.parent.mkdir(parents=True, exist_ok=True)
        document = {"agents_file": str(agents_file.resolve()), "breakpoints": [p.as_dict() for p in points]}
        write_atomically(path, orjson.dumps(document, option=orjson.OPT_INDENT_2))
