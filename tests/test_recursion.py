"""The recursion limit raised for deep input goes back to what it was, also when threads overlap."""

from __future__ import annotations

import sys
import threading

from xabsl_studio.engine.lang import deep_recursion  # the name every compile uses
from xabsl_studio.engine.recursion import RECURSION_LIMIT


def test_overlapping_sections_restore_the_limit_once_the_last_closes() -> None:
    """Found by CI: two compiles in two threads left the process's limit at 12,000 for good."""
    before = sys.getrecursionlimit()
    first, second = deep_recursion(), deep_recursion()
    first.__enter__()
    second.__enter__()  # another thread's compile, while the first runs
    assert sys.getrecursionlimit() == max(before, RECURSION_LIMIT)
    first.__exit__(None, None, None)
    assert sys.getrecursionlimit() == max(before, RECURSION_LIMIT), "the second is still deep"
    second.__exit__(None, None, None)
    assert sys.getrecursionlimit() == before


def test_threads_compiling_at_once_leave_the_limit_as_it_was() -> None:
    before = sys.getrecursionlimit()
    start = threading.Barrier(8)
    inside: list[int] = []  # the limit each section saw (asserts in threads would not fail the test)

    def deep() -> None:
        start.wait()
        for _ in range(200):
            with deep_recursion():
                inside.append(sys.getrecursionlimit())

    threads = [threading.Thread(target=deep) for _ in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert len(inside) == 1600 and min(inside) >= RECURSION_LIMIT, "every section ran deep"
    assert sys.getrecursionlimit() == before
