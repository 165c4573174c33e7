"""The statistics every comparison of two runs uses: Wilson intervals, their difference, the order.

* :func:`wilson`: the Wilson score interval of a binomial proportion: the tournament report's
  function for win and loss rates, unchanged, so that report can import it from here instead of
  keeping its own;
* :func:`difference_interval`: Newcombe's interval for the difference of two proportions, built
  from the two Wilson intervals (Newcombe 1998, method 10: the "hybrid score" interval);
* :func:`rate_test`: whether two counts over two lengths of time differ in rate (the count of
  side A out of both, against the share of time A had, with a Wilson interval);
* :func:`change_key`: the order of every comparison table: rows that only one side has first
  (something ran only there), then by the size of the change, largest first, then by name.
  The tournament's report (``examples/soccer/tournament/report.py``) can sort its activation
  tables with it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from typing import TypeVar

__all__ = ["Z95", "change_key", "difference_interval", "rate_test", "sort_by_change", "wilson"]

#: z for a two-sided 95 % interval.
Z95 = 1.959963984540054

T = TypeVar("T")


def wilson(successes: int, n: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval of a binomial proportion ``successes / n`` ((0, 1) when n is 0)."""
    if n == 0:
        return (0.0, 1.0)
    p = successes / n
    denominator = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denominator
    half = z * math.sqrt(p * (1.0 - p) / n + z * z / (4 * n * n)) / denominator
    return (max(0.0, centre - half), min(1.0, centre + half))


def difference_interval(k1: int, n1: int, k2: int, n2: int, z: float = Z95) -> tuple[float, float]:
    """Newcombe's interval for ``k1/n1 - k2/n2`` from the Wilson intervals of both proportions.

    A side without trials (``n`` 0) has the proportion 0 and the whole interval (0, 1).
    """
    p1 = k1 / n1 if n1 else 0.0
    p2 = k2 / n2 if n2 else 0.0
    l1, u1 = wilson(k1, n1, z)
    l2, u2 = wilson(k2, n2, z)
    d = p1 - p2
    return (
        max(-1.0, d - math.sqrt((p1 - l1) ** 2 + (u2 - p2) ** 2)),
        min(1.0, d + math.sqrt((u1 - p1) ** 2 + (p2 - l2) ** 2)),
    )


def rate_test(k1: int, t1: float, k2: int, t2: float, z: float = Z95) -> bool:
    """True when ``k1`` events in time ``t1`` and ``k2`` in ``t2`` differ in rate at the level of ``z``.

    Given ``k1 + k2`` events, equal rates make ``k1`` binomial with the share ``t1 / (t1 + t2)``;
    the rates differ when that share lies outside the Wilson interval of ``k1 / (k1 + k2)``.
    """
    if k1 + k2 == 0 or t1 <= 0 or t2 <= 0:
        return False
    low, high = wilson(k1, k1 + k2, z)
    expected = t1 / (t1 + t2)
    return not low <= expected <= high


def change_key(one_sided: bool, change: float, *names: str) -> tuple[bool, float, tuple[str, ...]]:
    """The sort key of a comparison row: one-sided rows first, then the largest change, then by name."""
    return (not one_sided, -abs(change), names)


def sort_by_change(
    rows: Iterable[T], one_sided: Callable[[T], bool], change: Callable[[T], float], name: Callable[[T], str]
) -> list[T]:
    """``rows`` in the order of :func:`change_key`."""
    return sorted(rows, key=lambda row: change_key(one_sided(row), change(row), name(row)))
