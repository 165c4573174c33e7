"""Frames: compact paths, per-client deltas that converge, the bounded ring buffer, history."""

from __future__ import annotations

import itertools
from pathlib import Path

import orjson

from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.protocol.host import FromWorker, NewGeneration, Sample
from xabsl_studio.server.protocol.limits import FULL_EVERY
from xabsl_studio.server.session.frames import Entry, FrameEncoder, FrameRecorder, Generation, Ring, history
from xabsl_studio.server.session.live import Session
from xabsl_studio.server.simulation.worker import Simulation, WorkerConfig


class _Recorded:
    """The simulation's core and the server's recorder joined in one process (no pipe between)."""

    def __init__(self, demo_dir: Path, ring_seconds: float) -> None:
        session = Session(BenchExample(demo_dir), seed=4)  # compiles; its process is never started
        programs = {k: (s.running, s.running_json) for k, s in session.programs.items()}
        self.sim = Simulation(WorkerConfig(session.example, seed=4, programs=programs))  # type: ignore[arg-type]
        self.ring = Ring(ring_seconds, self.sim.behavior_hz)
        self.recorder = FrameRecorder(self.ring)
        self.sim.emit = self._emit
        self._emit(self.sim.generation("connect"))
        self._emit(self.sim.sample())

    def _emit(self, message: FromWorker, droppable: bool = False) -> bool:
        if isinstance(message, NewGeneration):
            self.generation = Generation.from_message(message)
        elif isinstance(message, Sample):
            self.latest = self.recorder.record(self.generation, self.generation.shown(message))
        return True

    def _tick(self) -> Entry:
        self._emit(self.sim.tick())
        return self.latest


def _session(demo_dir: Path, ring_seconds: float = 120.0) -> _Recorded:
    return _Recorded(demo_dir, ring_seconds)


def _apply(state: dict[int, dict[str, dict[str, object]]], frame: dict) -> None:
    for agent in frame["robots"]:
        values = state.setdefault(agent["id"], {"inputs": {}, "outputs": {}})
        for kind in ("inputs", "outputs"):
            if frame["full"]:
                values[kind] = {}
            values[kind].update(agent.get(kind, {}))


def test_path_nodes_use_program_ids(demo_dir: Path) -> None:
    session = _session(demo_dir)
    for _ in range(30):
        session._tick()
    frame = orjson.loads(session.ring.latest.delta)  # type: ignore[union-attr]
    program = session.generation.structure["programs"]["demo"]
    options = {o["id"]: o for o in program["options"]}
    root = frame["robots"][0]["path"][0]
    kind, depth, option_id, state_id, option_time, state_time, decided_in, leaf, params = root
    assert (kind, depth) == (0, 0) and options[option_id]["name"] == "play"
    assert options[option_id]["states"][state_id]["name"] in {"wait", "chase", "search"}
    assert option_time == 725 and 0 <= state_time <= option_time and leaf >= 0 and decided_in >= 0
    assert params == []
    depths = [node[1] for node in frame["robots"][0]["path"]]
    assert depths[0] == 0 and all(b <= a + 1 for a, b in itertools.pairwise(depths))


def test_a_client_skipping_frames_converges_to_exact_values(demo_dir: Path) -> None:
    session = _session(demo_dir)
    encoder = FrameEncoder(session.ring)
    every_tick: dict = {}
    skipping: dict = {}
    last_fast = last_slow = None
    gen = session.generation.number
    for tick in range(1, 260):
        entry = session._tick()
        fast = orjson.loads(encoder.frame(last_fast, gen, entry, None))
        _apply(every_tick, fast)
        last_fast = entry.seq
        if tick % 7 == 0:
            slow = orjson.loads(encoder.frame(last_slow, gen, entry, None))
            _apply(skipping, slow)
            last_slow = entry.seq
            assert skipping == every_tick, f"diverged at tick {tick}"
    full = orjson.loads(encoder.frame(None, gen, session.ring.latest, None))  # type: ignore[arg-type]
    expected: dict = {}
    _apply(expected, full)
    assert every_tick == expected
    assert encoder.cache_hits == 0 or encoder.encoded > 0


def test_full_frames_at_least_every_full_every_ticks_and_for_filters(demo_dir: Path) -> None:
    session = _session(demo_dir)
    encoder = FrameEncoder(session.ring)
    last = None
    fulls = []
    for _ in range(FULL_EVERY * 2 + 5):
        entry = session._tick()
        frame = orjson.loads(encoder.frame(last, session.generation.number, entry, frozenset({1})))
        if frame["full"]:
            fulls.append(entry.seq)
        assert "inputs" not in frame["robots"][0] and "inputs" in frame["robots"][1]
        last = entry.seq
    assert len(fulls) >= 3 and all(b - a <= FULL_EVERY for a, b in itertools.pairwise(fulls))


def test_ring_is_bounded_and_history_rebuilds_full_frames(demo_dir: Path) -> None:
    session = _session(demo_dir, ring_seconds=2.0)
    for _ in range(300):
        session._tick()
    ring = session.ring
    assert len(ring) == ring.capacity == 80
    assert ring.nbytes() < 80 * 4000
    live = [e for e in ring.snapshot() if e.paths is not None]
    assert len(live) <= 64, "only the newest entries keep their values as objects"
    entries = ring.snapshot()
    first_key = next(k for k, e in enumerate(entries) if e.full is not None)
    start = first_key + 10  # not a key frame: history merges deltas from the key frame before it
    t0 = entries[start - 1].t + 1
    frames = [orjson.loads(f) for f in history(ring, t0, entries[-1].t)]
    assert frames[0]["full"] and frames[0]["t"] == entries[start].t
    assert [f["seq"] for f in frames] == [e.seq for e in entries[start:]]
    older = [orjson.loads(f) for f in history(ring, 0, entries[-1].t)]
    assert older[0]["full"] and older[0]["seq"] == entries[first_key].seq, "starts at the oldest key frame"
    state: dict = {}
    for f in frames:
        _apply(state, f)
    expected: dict = {}
    _apply(expected, orjson.loads(FrameEncoder(ring).frame(None, session.generation.number, entries[-1], None)))
    assert state == expected
    assert len(list(history(ring, t0, entries[-1].t, every=10))) == 1 + (len(frames) - 1) // 10


def test_the_ring_finds_ticks_behind_a_gap() -> None:
    """Samples the pipe dropped leave gaps; the ticks before them must stay reachable by seq.

    The lookup counted back from the newest entry as if seqs had no gaps, so after one dropped
    sample every older tick read as gone: a fork, an explain or the fork's original at such a tick
    failed under load (tests/server/session/test_fork.py flaked so at speed 20).
    """
    ring = Ring(10, 40)
    gen = object()
    seqs = [*range(0, 50), *range(53, 80), *range(81, 90)]  # two gaps
    for seq in seqs:
        ring.append(Entry(seq, gen, seq * 25, 0.0, (), (), False, False, b""))  # type: ignore[arg-type]
    assert [ring.get(seq).seq for seq in seqs] == seqs  # type: ignore[union-attr]
    assert ring.get(51) is None and ring.get(80) is None and ring.get(90) is None and ring.get(-1) is None
