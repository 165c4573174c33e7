"""The process's recursion limit, raised while deep input is parsed, checked or emitted.

Long ``else if`` chains and deeply nested expressions recurse in the parser, the checker and the
emitters. Python 3.11 keeps pure-Python frames off the C stack, so a higher limit is safe; deeper
input still gets a ``nesting-too-deep`` diagnostic instead of a RecursionError.

The limit is one value for the whole process. Two threads that each raised it and put back "the
limit they found" could leave it raised for good (the studio compiles in worker threads, the
language server in its own): then every later guard that relies on the normal limit stops
working. :func:`deep_recursion` therefore counts the sections that are open: the first one in
raises the limit, the last one out restores what it was.
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["RECURSION_LIMIT", "deep_recursion"]

#: The recursion limit while deep input is handled.
RECURSION_LIMIT = 12_000

_lock = threading.Lock()
#: how many deep sections are open, in every thread
_open = 0
#: the limit before the first of them opened
_saved = 0


@contextmanager
def deep_recursion() -> Iterator[None]:
    """Allow :data:`RECURSION_LIMIT` nested calls while in the block (never lowers the limit)."""
    global _open, _saved
    with _lock:
        if _open == 0:
            _saved = sys.getrecursionlimit()
        _open += 1
        if sys.getrecursionlimit() < RECURSION_LIMIT:
            sys.setrecursionlimit(RECURSION_LIMIT)
    try:
        yield
    finally:
        with _lock:
            _open -= 1
            if _open == 0:
                sys.setrecursionlimit(_saved)
