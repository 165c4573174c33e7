"""The parallel read of a recording's columns gives the single pass's columns, array for array."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from xabsl_studio.engine.query import query_recording, scan
from xabsl_studio.engine.record import Recording
from xabsl_studio.engine.record.columns import Codes, RobotColumns, Selection


def _same(a: RobotColumns, b: RobotColumns) -> None:
    for field in ("seq", "t", "gen"):
        assert np.array_equal(getattr(a, field), getattr(b, field)), field
    assert a.values.keys() == b.values.keys()
    for name, (values, known) in a.values.items():
        other, other_known = b.values[name]
        assert np.array_equal(known, other_known), name
        assert np.array_equal(values[known], other[known]), name
    for field in a.nodes.__dataclass_fields__:
        left, right = getattr(a.nodes, field), getattr(b.nodes, field)
        assert np.array_equal(left, right, equal_nan=left.dtype.kind == "f"), field
    assert a.calls.keys() == b.calls.keys()
    for name, table in a.calls.items():
        other_table = b.calls[name]
        assert np.array_equal(table.row, other_table.row) and table.args == other_table.args, name
        assert np.array_equal(table.known, other_table.known), name
        assert np.array_equal(table.result[table.known], other_table.result[other_table.known]), name
    assert {g: v.gen for g, v in a.programs.items()} == {g: v.gen for g, v in b.programs.items()}
    assert (a.has_reads, a.functions) == (b.has_reads, b.functions)


def _read(match: Path, workers: int, seeded: bool = True, selection: Selection | None = None) -> Any:
    with Recording(match) as recording:
        codes = Codes()
        if seeded:
            scan.seed_codes(recording, codes)
        columns = scan.read_columns(recording, recording.agents, codes, selection, workers=workers)
        return columns, codes.by_name


@pytest.mark.parametrize("workers", [2, 3, 7])
def test_ranges_read_in_parallel_join_into_the_single_pass(match: Path, workers: int) -> None:
    one, codes_one = _read(match, 1)
    parallel, codes_parallel = _read(match, workers)
    assert one.keys() == parallel.keys()
    for name in one:
        _same(one[name], parallel[name])
    assert codes_one == codes_parallel


def test_a_selection_is_read_alike_in_parallel(match: Path) -> None:
    selection = Selection(frozenset({"ball.distance", "team.role"}), frozenset({"striker"}), frozenset(), frozenset())
    one, _ = _read(match, 1, selection=selection)
    parallel, _ = _read(match, 3, selection=selection)
    for name in one:
        _same(one[name], parallel[name])


def test_parts_that_number_elements_on_their_own_are_read_again_in_one_pass(match: Path) -> None:
    """Unseeded codes: each worker would number the elements it meets itself; the parts are not joined."""
    one, codes_one = _read(match, 1, seeded=False)
    parallel, codes_parallel = _read(match, 3, seeded=False)
    assert codes_one == codes_parallel  # the numbering of the single pass, not a mix of the workers'
    for name in one:
        _same(one[name], parallel[name])


def test_a_query_answers_the_same_read_in_parallel(match: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    condition = "striker.active && ball.distance < 800 || team.role == supporter"
    one = query_recording(match, condition)
    monkeypatch.setattr(scan, "_workers", lambda _ticks: 3)
    assert query_recording(match, condition) == one
    assert one.intervals


def test_a_process_with_threads_reads_in_one_pass(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(scan, "PARALLEL_FROM", 10)
    stop = threading.Event()
    other = threading.Thread(target=stop.wait)
    other.start()
    try:
        assert scan._workers(10**6) == 1  # forking beside a thread could inherit a held lock
    finally:
        stop.set()
        other.join()
    assert scan._workers(5) == 1  # too small to be worth a fork
