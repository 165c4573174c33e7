"""Which files the language server opens on a request's behalf: allowed roots, ``.xabsl`` regular files, a size bound.

One rule for every file the server reads itself (an agents file, an included file, a folder
looked through for agents files), whatever asked for it (a hover on an unopened URI, an
``include`` line in a buffer, the ``agents`` initialization option):

* its real location, links resolved (``..``, percent-encoded names and symlinks out of a root
  end up where they really point), lies inside one of the **allowed roots**;
* its name ends in ``.xabsl``;
* it is a **regular file**, read with :func:`xabsl_studio.engine.files.read_regular`: opened
  with ``O_NONBLOCK`` and its kind checked on the descriptor, so a FIFO or a device is refused
  without waiting on it;
* of at most :data:`MAX_SOURCE_BYTES`.

Texts the client sent (``didOpen``/``didChange``) are not files: they are served wherever they
say they are, but what they include is read under the same rule.

The roots: the studio's ``/lsp`` serves the behavior folders of the studio's behavior sets and
nothing the client says adds to them. ``xabsl lsp`` (stdio or ``--ws``, the user's own editor)
serves the folders of the agents files it was given (``--agents``, the ``agents``
initialization option) and the workspace folders and ``rootUri`` the client names; a client
that names none gets the server's current folder.
"""

from __future__ import annotations

import errno
import os
import stat
from collections.abc import Iterable

from xabsl_studio.engine.errors import XabslError
from xabsl_studio.engine.files import read_regular

#: The largest source file the language server reads (the studio's limit for a behavior file).
MAX_SOURCE_BYTES = 16 * 1024 * 1024
#: The only kind of file the language server reads.
SUFFIX = ".xabsl"


class OutsideRoots(XabslError, OSError):
    """A path whose real location is outside the allowed roots, or that names no ``.xabsl`` file.

    An ``OSError`` too, so the loader reports it like any file it cannot open.
    """

    def __init__(self, path: str) -> None:
        super().__init__(errno.EACCES, "outside the behavior folders the language server serves", path)


def real_path(path: str) -> str:
    """The real location of ``path`` (links resolved); a NUL byte is refused like an outside path."""
    try:
        return os.path.realpath(path)
    except (ValueError, OSError):  # an embedded NUL byte; a name too long to resolve
        raise OutsideRoots(path) from None


class FileAccess:
    """The allowed roots of one language server, and the reads the rule of this module allows.

    Args:
        roots: folders served from the start (the studio's behavior folders, the folder of
            ``--agents``).
        client_roots: whether the client's workspace folders and agents option add roots
            (``xabsl lsp``: yes; the studio: no).
    """

    def __init__(self, roots: Iterable[str] = (), *, client_roots: bool = False) -> None:
        self.fixed = tuple(dict.fromkeys(os.path.realpath(r) for r in roots))
        self.client_roots = client_roots
        self.given: tuple[str, ...] = ()

    @property
    def roots(self) -> tuple[str, ...]:
        """Every allowed root, real paths."""
        roots = self.fixed + self.given
        if not roots and self.client_roots:
            return (os.path.realpath(os.getcwd()),)
        return roots

    def grant(self, folders: Iterable[str]) -> None:
        """The client's workspace folders (ignored when the client may not add roots)."""
        if self.client_roots:
            self.given = tuple(dict.fromkeys(os.path.realpath(f) for f in folders if "\0" not in f))

    def add(self, folder: str) -> None:
        """One more folder the client named (the agents option's), when the client may add roots."""
        if self.client_roots and "\0" not in folder:
            self.given = tuple(dict.fromkeys((*self.given, os.path.realpath(folder))))

    def inside(self, real: str) -> bool:
        """Whether the real path ``real`` is one of the roots or below one."""
        return any(real == root or real.startswith(root.rstrip(os.sep) + os.sep) for root in self.roots)

    def allows(self, real: str) -> bool:
        """Whether the rule lets the server read the file at real path ``real`` (its kind aside)."""
        return real.endswith(SUFFIX) and self.inside(real)

    def check(self, path: str) -> str:
        """The real location of ``path`` if the rule allows it, else :class:`OutsideRoots`."""
        real = real_path(path)
        if not self.allows(real):
            raise OutsideRoots(path)
        return real

    def read(self, path: str) -> bytes:
        """The bytes of the file at ``path`` under the rule.

        Raises:
            OutsideRoots: outside the roots, or not a ``.xabsl`` name.
            NotRegularFile: a FIFO, device, socket or folder.
            FileTooLarge: over :data:`MAX_SOURCE_BYTES`.
            OSError: missing, unreadable.
        """
        return read_regular(self.check(path), MAX_SOURCE_BYTES)

    def is_file(self, path: str) -> bool:
        """Whether ``path`` is a regular ``.xabsl`` file the rule allows (``stat`` only, nothing opened)."""
        try:
            return stat.S_ISREG(os.stat(self.check(path)).st_mode)
        except OSError:
            return False

    def names(self, folder: str) -> list[str]:
        """The names in ``folder``, sorted, if the folder lies inside a root (else none)."""
        real = real_path(folder)
        if not self.inside(real):
            return []
        try:
            return sorted(os.listdir(real))
        except OSError:
            return []
