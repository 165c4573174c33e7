"""Shared pieces of the fuzz suite: hypothesis settings, byte and JSON mutators, a time bound.

Each fuzz test feeds mutated real inputs to one reader of the project (the compiler, the trace
input, the Dual Dynamics model loader, the PDDL reader, the studio's file API) and asserts "a
diagnostic or a clean error, never another exception, within a time bound". Mutations are those that broke things
before (issue 18): deep nesting (one slice repeated thousands of times), huge and non-finite
numbers, lone surrogates, non-UTF-8 bytes, NUL, CR line ends, truncation.

Runs are bounded and derandomized (same examples every run, as in CI). ``XABSL_FUZZ_EXAMPLES=N``
multiplies the number of examples and ``XABSL_FUZZ_RANDOM=1`` draws new ones, for a longer
hunt by hand.
"""

from __future__ import annotations

import json
import os
import random
import signal
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from hypothesis import HealthCheck, settings

#: One probe of a small input takes milliseconds; over this it counts as a hang.
TIME_BOUND_SECONDS = 5.0
_SCALE = max(1, int(os.environ.get("XABSL_FUZZ_EXAMPLES", "1")))


def fuzz_settings(examples: int) -> settings:
    """Bounded examples, no per-example deadline (the time bound is asserted), derandomized."""
    return settings(
        max_examples=examples * _SCALE,
        deadline=None,
        derandomize=os.environ.get("XABSL_FUZZ_RANDOM") != "1",
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
        database=None,
    )


class Hang(AssertionError):
    """A probe ran past the time bound."""


@contextmanager
def time_bound(seconds: float = TIME_BOUND_SECONDS) -> Iterator[None]:
    """Fail a probe that takes longer than ``seconds`` (an alarm interrupts a real hang too)."""

    def alarm(signum: int, frame: Any) -> None:
        raise Hang(f"no answer within {2 * seconds:g} s")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, 2 * seconds)
    started = time.perf_counter()
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    elapsed = time.perf_counter() - started
    if elapsed > seconds:
        raise Hang(f"took {elapsed:.2f} s (bound {seconds:g} s)")


_NOISE = [b"\x00", b"\r", b"\r\n", b"\xff", b"\xe9", b"\xc3", b"\xed\xa0\x80", b"\\", b'"', b"{", b"}", b"(", b")",
          b"[", b"]", b";", b",", b":", b"-", b"e", b"9", b"NaN", b"1e999", b"\\ud800", b" ", b"\t"]  # fmt: skip


def mutate_bytes(data: bytes, rnd: random.Random) -> bytes:
    """One random edit of ``data``; amplifications repeat a slice up to 5,000 times (deep nesting)."""
    if not data:
        return rnd.choice(_NOISE)
    kind = rnd.randrange(8)
    at = rnd.randrange(len(data) + 1)
    if kind == 0:
        return data[:at] + data[at + rnd.randint(1, 4) :]
    if kind == 1:
        return data[:at] + b"".join(rnd.choice(_NOISE) for _ in range(rnd.randint(1, 4))) + data[at:]
    if kind == 2:
        return data[:at]
    if kind == 3:  # amplify: "((((((" or "a+a+a+a" or "[[[[["
        end = min(len(data), at + rnd.randint(1, 3))
        times = rnd.choice([2, 10, 200, 1000, 5000])
        return data[:at] + data[at:end] * times + data[at:]
    if kind == 4:
        end = min(len(data), at + rnd.randint(1, 60))
        return data[:end] + data[at:end] + data[end:]
    if kind == 5:
        return rnd.choice([data.replace(b"\n", b"\r\n"), data.replace(b"\n", b"\r"), data.replace(b"\r\n", b"\n")])
    if kind == 6:  # a bracket (or its partner) gets nested around a run of text
        opening, closing = rnd.choice([(b"(", b")"), (b"[", b"]"), (b"{", b"}")])
        times = rnd.choice([10, 300, 3000])
        return data[:at] + opening * times + data[at:] + closing * times
    i, j = sorted(rnd.randrange(len(data)) for _ in range(2))
    return data[:i] + data[j : j + 1] + data[i + 1 : j] + data[i : i + 1] + data[j + 1 :]


def mutate_many(data: bytes, rnd: random.Random, edits: int = 3) -> bytes:
    """One to ``edits`` mutations, capped at 4 MB so a probe stays a probe."""
    for _ in range(rnd.randint(1, edits)):
        data = mutate_bytes(data, rnd)[: 4 << 20]
    return data


#: JSON texts of odd values, spliced in where a value was.
ODD_JSON = [
    "NaN", "Infinity", "-Infinity", "1e999", "-1e400", "1" + "0" * 400, "9" * 5000, "-0.0", "5e-324",
    '"\\ud800"', '"\\u0000"', '""', "null", "true", "false", "{}", "[]", "[" * 3000 + "]" * 3000,
    '"' + "x" * 10_000 + '"', '"(((((((((((((((((((((((((((((((1"', '"' + "(" * 500 + "1" + ")" * 500 + '"',
    '"' + "1+" * 3000 + '1"', "-1", "4294967296", "18446744073709551616", "0.1",
]  # fmt: skip

_MARK = "\x00odd\x00"


def paths(value: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every key path into a parsed JSON value (the root included)."""
    out = [prefix]
    if isinstance(value, dict):
        for k, v in value.items():
            out += paths(v, (*prefix, k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            out += paths(v, (*prefix, i))
    return out


def splice_odd_value(document: Any, rnd: random.Random) -> str:
    """JSON text of ``document`` with one value (or a key's value) replaced by an odd JSON text."""
    doc = json.loads(json.dumps(document))
    path = rnd.choice(paths(doc))
    if not path:
        return rnd.choice(ODD_JSON)
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    parent[path[-1]] = _MARK
    return json.dumps(doc, ensure_ascii=False).replace(json.dumps(_MARK), rnd.choice(ODD_JSON), 1)
