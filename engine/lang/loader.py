"""The include closure (§1.1): read the agents file and every file it includes, once each.

Include paths are relative to the including file. Unlike the original compiler, which compared
joined path strings, files are identified by their resolved real path, so a file reached through
``../`` or a symlink is still read once (§1.7). Including one file twice *from the same file* is
an error, as in the original.

Display names (what diagnostics print) are paths relative to a base folder (the behavior root
or the working directory), ``../`` included for a file beside it (see :func:`display_path`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass

from xabsl_studio.engine.lang import ast
from xabsl_studio.engine.lang.diagnostics import Diagnostics
from xabsl_studio.engine.lang.parser import parse_file
from xabsl_studio.engine.lang.tokens import decode_source


@dataclass
class LoadedProgram:
    """The parsed files of one program: includes before includers, the root file last."""

    root: ast.SourceFile | None
    files: list[ast.SourceFile]


def display_path(real: str, base: str) -> str:
    """How diagnostics name the file ``real``: relative to ``base``, as the user who named it writes it.

    A file beside the named folder is ``../common/symbols.xabsl`` (it printed absolute, unlike
    the files inside); only a file that meets ``base`` at the filesystem's root (``/usr/...``
    against ``/home/...``), or on another drive, is named by its absolute path.
    """
    try:
        relative = os.path.relpath(real, base)
        meets = os.path.commonpath([os.path.abspath(real), os.path.abspath(base)])
    except ValueError:  # another drive
        return real
    if relative.startswith("..") and os.path.dirname(meets) == meets:  # only at the root
        return real
    return relative


def load(
    path: str,
    diagnostics: Diagnostics,
    base: str | None = None,
    overrides: Mapping[str, str] | None = None,
) -> LoadedProgram:
    """Parse ``path`` and its include closure.

    Args:
        path: the agents file (or any single file) to compile.
        diagnostics: receives I/O and syntax problems.
        base: folder that display names are relative to (default: the working directory).
        overrides: text to use instead of the file contents, keyed by real path (unsaved
            editor buffers).
    """
    base = os.path.realpath(base or os.getcwd())
    overrides = {os.path.realpath(k): v for k, v in (overrides or {}).items()}
    files: list[ast.SourceFile] = []
    seen: set[str] = set()
    real_folders: dict[str, str] = {}

    def resolve(folder: str, relative: str) -> str:
        """``os.path.realpath(folder/relative)``, each folder resolved once.

        ``realpath`` checks every component of a path for a symlink; a set includes hundreds
        of files from a few folders, so the folder part is resolved once and only the file
        name itself is checked (a symlinked file is resolved in full, as before).
        """
        joined = os.path.join(folder, relative)
        head, tail = os.path.split(joined)
        if tail in ("", ".", ".."):
            return os.path.realpath(joined)
        real_head = real_folders.get(head)
        if real_head is None:
            real_head = real_folders[head] = os.path.realpath(head)
        candidate = os.path.join(real_head, tail)
        return os.path.realpath(candidate) if os.path.islink(candidate) else candidate

    def read(real: str) -> str | None:
        if real in overrides:
            return overrides[real]
        with open(real, "rb") as handle:
            return decode_source(handle.read())

    def visit(real: str) -> ast.SourceFile | None:
        seen.add(real)
        shown = display_path(real, base)
        try:
            text = read(real)
        except OSError as error:
            diagnostics.add("unreadable-file", f"unable to read file: {error.strerror}", None, shown)
            return None
        assert text is not None
        source = parse_file(shown, text, diagnostics)
        included_here: set[str] = set()
        for include in source.includes:
            if "\0" in include.path:
                diagnostics.add(
                    "missing-include-file", "unable to open file: the name contains a NUL byte", include.span
                )
                continue
            target = resolve(os.path.dirname(real), include.path)
            if target in included_here:
                diagnostics.add("include-twice", f"'{include.path}' is included twice from this file", include.span)
                continue
            included_here.add(target)
            if target in seen:
                continue
            if not os.path.isfile(target) and target not in overrides:
                diagnostics.add("missing-include-file", f"unable to open file '{include.path}'", include.span)
                continue
            visit(target)
        files.append(source)
        return source

    real_root = os.path.realpath(path)
    root = visit(real_root)
    return LoadedProgram(root, files)
