"""Fork: run from a tick of the live history (the session log replayed from the seed, checked, then live).

The simulation and the server's ring are joined in one process (no pipe), as in test_frames:
every sample goes through the real FrameRecorder, and ``fork`` gets what the ring recorded, as
the session sends it. The soccer world (pymunk, contacts) runs 2 vs 2 into the playing phase.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import httpx2 as httpx
import orjson
import pytest

from tests.server.conftest import LiveServer
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.examples.soccer.studio import SoccerExample
from xabsl_studio.server.protocol.commands import (
    Explain,
    ForceOption,
    OverrideInput,
    Pause,
    Release,
    Reset,
    Speed,
    Step,
    WorldCommand,
)
from xabsl_studio.server.protocol.host import Apply, FromWorker, NewGeneration, Sample
from xabsl_studio.server.session.frames import FrameRecorder, Generation, Ring
from xabsl_studio.server.session.live import CommandError, Session, fork_request
from xabsl_studio.server.simulation.worker import Simulation, WorkerConfig

#: the soccer game is in its playing phase (robots and ball in contact) from about tick 340
PLAYING = 360


class Joined:
    """A simulation and the server's ring in one process; every sample kept by seq."""

    def __init__(self, example: Any, seed: int = 3, ring_ticks: int = 4800) -> None:
        self.session = Session(example, seed=seed)  # compiles; its process is never started
        programs = {k: (s.running, s.running_json) for k, s in self.session.programs.items()}
        config = WorkerConfig(self.session.example, seed=seed, programs=programs, history_ticks=ring_ticks)  # type: ignore[arg-type]
        self.sim = Simulation(config)
        self.ring = Ring(ring_ticks / self.sim.behavior_hz, self.sim.behavior_hz)
        self.recorder = FrameRecorder(self.ring)
        self.samples: dict[int, Sample] = {}
        self.generations: list[NewGeneration] = []
        self.sim.emit = self._emit
        self._emit(self.sim.generation("connect"))
        self._emit(self.sim.sample())

    def _emit(self, message: FromWorker, droppable: bool = False) -> bool:
        if isinstance(message, NewGeneration):
            self.generations.append(message)
            self.generation = Generation.from_message(message)
        elif isinstance(message, Sample):
            self.recorder.record(self.generation, self.generation.shown(message))
            self.samples[message.seq] = message
        return True

    def run(self, ticks: int) -> None:
        for _ in range(ticks):
            self._emit(self.sim.tick())

    def do(self, command: Any) -> Any:
        return self.sim.execute(command, "tab-1")

    def fork(self, seq: int) -> Any:
        return self.sim.execute(fork_request(self.ring, seq))

    def tick_samples(self, first: int, last: int) -> dict[int, Sample]:
        """The samples of seqs first..last by time (the last one of each time: a reload's sample follows its tick)."""
        return {s.t: s for seq, s in sorted(self.samples.items()) if first <= seq <= last}


def _same(a: Sample, b: Sample) -> bool:
    return (a.paths, a.extras, a.inputs, a.outputs, a.scene, a.status) == (
        b.paths,
        b.extras,
        b.inputs,
        b.outputs,
        b.scene,
        b.status,
    )


def _edited(joined: Joined, root: Path) -> Apply:
    """The home team's behavior with the playing state standing still (compiled clean)."""
    path = root / "behavior" / "options" / "play_soccer.xabsl"
    text = path.read_text(encoding="utf-8").replace("game_playing();", "stand();")
    compilation = joined.session.compile("behavior", {str(path.resolve()): text})
    assert compilation.program is not None, [d.as_dict() for d in compilation.diagnostics]
    from xabsl_studio.engine.emit.json import program_to_json

    return Apply("behavior", compilation.program, program_to_json(compilation.program, compilation.source_text))


def test_a_fork_with_the_unchanged_behavior_continues_exactly_like_the_original(soccer_dir: Path) -> None:
    joined = Joined(SoccerExample(soccer_dir, players_per_team=2))
    # Pause, step and speed change when ticks run, not what they compute: the log leaves them out.
    joined.do(Pause(op="pause"))
    joined.do(Step(op="step", ticks=40))
    joined.do(Speed(op="speed", speed=4.0))
    joined.run(PLAYING + 50)
    # Nor does asking why: explain re-evaluates conditions, it changes nothing (not logged).
    for option in ("play_soccer", "game_playing", "role_selection"):
        joined.do(Explain(op="explain", robot=0, option=option))
    joined.run(50)
    fork_at = max(joined.samples) - 120
    joined.run(200)
    original = joined.tick_samples(fork_at, max(joined.samples))
    result = joined.fork(fork_at)
    # The build's sample is seq 1 and tick k's is seq k + 1: ticks 1..fork_at - 2 are re-simulated.
    assert result["seq"] == fork_at and result["ticks"] == fork_at - 2
    gen = joined.generations[-1]
    assert gen.reason == "fork" and gen.fork == (fork_at, joined.samples[fork_at].t, result["start"])
    joined.run(330)
    forked = joined.tick_samples(result["start"] + 1, max(joined.samples))
    compared = [t for t in forked if t in original]
    start_t = joined.samples[fork_at].t
    assert compared == sorted(t for t in original if t >= start_t), "every original tick since the fork point"
    assert min(compared) == start_t and len(compared) == 321, "the fork's first tick is the tick forked at"
    assert all(_same(forked[t], original[t]) for t in compared), "paths, symbols and scene equal, tick for tick"
    # The fork really runs: its ticks go beyond the world time the original had reached.
    assert max(forked) > max(original)


def test_forcing_overrides_world_commands_and_reloads_before_the_fork_point_are_replayed(soccer_dir: Path) -> None:
    joined = Joined(SoccerExample(soccer_dir, players_per_team=2))
    joined.run(PLAYING)
    joined.do(ForceOption(op="force_option", robot=0, option="search_ball"))
    joined.do(OverrideInput(op="override_input", robot=1, symbol="ball.seen", value=False))
    joined.run(30)
    joined.do(Release(op="release", robot=0))
    joined.run(20)
    edit = _edited(joined, soccer_dir)
    joined.do(edit)  # a hot reload: its sample is no tick
    joined.run(40)
    fork_at = max(joined.samples) - 30  # after all of them, the override still on
    joined.run(60)
    original = joined.tick_samples(fork_at, max(joined.samples))
    assert b'"overrides"' in joined.samples[fork_at].extras[1]
    result = joined.fork(fork_at)
    joined.run(90)
    forked = joined.tick_samples(result["start"] + 1, max(joined.samples))
    compared = [t for t in forked if t in original]
    assert len(compared) == 90
    assert all(_same(forked[t], original[t]) for t in compared)
    # The fork keeps the override (its owner too: a disconnect releases it).
    assert b'"overrides"' in forked[min(compared)].extras[1]
    assert joined.sim.release_owner("tab-1") == 1


def test_a_fork_after_an_edit_differs_from_the_fork_tick_on(soccer_dir: Path) -> None:
    joined = Joined(SoccerExample(soccer_dir, players_per_team=2))
    joined.run(PLAYING + 100)
    fork_at = max(joined.samples) - 60
    original = joined.tick_samples(fork_at, max(joined.samples))
    joined.do(_edited(joined, soccer_dir))  # the edit applies now, after the fork point
    result = joined.fork(fork_at)
    # The fork starts where the original was before tick fork_at, with the edited behavior.
    first = joined.samples[result["start"]]
    assert first.scene == joined.samples[fork_at - 1].scene
    joined.run(60)
    forked = joined.tick_samples(result["start"] + 1, max(joined.samples))
    assert min(forked) == joined.samples[fork_at].t
    structure = orjson.loads(joined.generations[-1].structure)
    names = {o["id"]: o["name"] for o in structure["programs"]["behavior"]["options"]}
    for t in sorted(forked)[:60]:
        assert forked[t].paths[0] != original[t].paths[0], f"the edited behavior runs from the fork tick on (t={t})"
        assert "game_playing" not in [names.get(n[2]) for n in orjson.loads(forked[t].paths[0]) if n[0] == 0]
    # Robots of the unedited team keep deciding as before until the world differs.
    assert forked[min(forked)].paths[2] == original[min(forked)].paths[2]


def test_world_commands_before_the_fork_point_are_replayed(demo_dir: Path) -> None:
    joined = Joined(BenchExample(demo_dir), seed=5)
    joined.run(60)
    joined.do(Pause(op="pause"))  # paused, a world command makes a sample of its own (no tick)
    before = max(joined.samples)
    args = {"robot": 0, "symbol": "ball.distance", "value": 50}
    joined.do(WorldCommand(op="world_command", name="set_input", args=args))
    assert max(joined.samples) == before + 1
    joined.do(WorldCommand(op="world_command"))  # only the list: changes nothing
    joined.do(Step(op="step", ticks=30))
    fork_at = max(joined.samples) - 10
    joined.do(Step(op="step", ticks=20))
    original = joined.tick_samples(fork_at, max(joined.samples))
    result = joined.fork(fork_at)
    joined.do(Step(op="step", ticks=25))
    forked = joined.tick_samples(result["start"] + 1, max(joined.samples))
    compared = [t for t in forked if t in original]
    assert len(compared) == 25 and all(_same(forked[t], original[t]) for t in compared)
    # Forking the world command's own sample restores it as it was, the command included.
    again = joined.fork(before + 1)
    assert joined.samples[again["start"]].scene == joined.samples[before + 1].scene


def test_a_fork_of_a_fork_and_of_the_original_after_it(soccer_dir: Path) -> None:
    joined = Joined(SoccerExample(soccer_dir, players_per_team=2))
    joined.run(PLAYING)
    first_at = max(joined.samples) - 100
    head = max(joined.samples)
    original = joined.tick_samples(first_at - 10, head)
    first = joined.fork(first_at)
    joined.run(50)
    # Fork the fork at its tick 20: the log holds the original's commands and the switch.
    second_at = first["start"] + 20
    fork_one = joined.tick_samples(first["start"] + 1, max(joined.samples))
    second = joined.fork(second_at)
    joined.run(30)
    fork_two = joined.tick_samples(second["start"] + 1, max(joined.samples))
    assert all(_same(fork_two[t], original[t]) for t in fork_two if t in original)
    assert all(_same(fork_two[t], fork_one[t]) for t in fork_two if t in fork_one)
    # The original's own ticks after the first fork point are still forkable (its log is kept).
    third = joined.fork(head - 10)
    joined.run(20)
    fork_three = joined.tick_samples(third["start"] + 1, max(joined.samples))
    assert min(fork_three) == joined.samples[head - 10].t
    assert all(_same(fork_three[t], original[t]) for t in fork_three if t in original)


def test_forks_outside_the_history_or_the_log_are_refused_and_change_nothing(soccer_dir: Path) -> None:
    joined = Joined(SoccerExample(soccer_dir, players_per_team=2), ring_ticks=200)
    joined.run(100)
    before_reset = max(joined.samples) - 5
    joined.do(Reset(op="reset"))
    joined.run(300)
    world = joined.sim.world
    # Left the ring: the server refuses it before asking the simulation.
    with pytest.raises(CommandError, match="not in the history"):
        joined.fork(before_reset)
    # The simulation refuses what its log dropped (the run before the reset left the window).
    from xabsl_studio.server.protocol.host import ForkAt

    with pytest.raises(CommandError, match="older than the session log"):
        joined.sim.execute(ForkAt(before_reset, {}))
    with pytest.raises(CommandError, match="has not run yet"):
        joined.sim.execute(ForkAt(max(joined.samples) + 5, {}))
    assert len(joined.sim.logs) == 1, "the run before the reset is dropped once its ticks left the ring"
    # What the ring recorded is what the re-simulation must reach: a differing record is refused.
    request = fork_request(joined.ring, max(joined.samples) - 50)
    paths, scene = request.recorded[request.seq - 1]
    tampered = dict(request.recorded)
    tampered[request.seq - 1] = (paths, {**scene, "ball": [123456, 7]})
    with pytest.raises(CommandError, match=r"differs from the history at tick \d+ \(the world's scene\)"):
        joined.sim.execute(ForkAt(request.seq, tampered))
    assert joined.sim.world is world, "a refused fork leaves the running world alone"
    joined.run(1)
    assert joined.fork(request.seq)["seq"] == request.seq


def test_fork_over_the_websocket_announces_the_fork_and_serves_the_original(soccer_dir: Path, client_for: Any) -> None:
    session = Session(SoccerExample(soccer_dir, players_per_team=2), seed=3, speed=20.0)
    with LiveServer(session) as server, httpx.Client(base_url=server.url) as http:
        client = client_for(server)
        client.wait_hello("connect")
        client.wait_frame(lambda f: f["t"] > 12_000)
        assert client.command("pause")["ok"]
        held = session.ring.snapshot()  # at speed 20 the pipe may drop samples: fork at a tick it kept
        fork_at, t = held[-100].seq, held[-100].t
        reply = client.command("fork", seq=fork_at)
        assert reply["ok"], reply
        assert reply["result"]["seq"] == fork_at and reply["result"]["t"] == t
        hello = client.wait_hello("fork")
        assert hello["fork"] == {"seq": fork_at, "t": t, "start": reply["result"]["start"]}
        assert http.get("/api/status").json()["fork"] == hello["fork"]
        assert client.command("step", ticks=10)["ok"]
        frame = client.wait_frame(lambda f: f["gen"] == hello["generation"] and f["t"] > t)
        answer = http.get("/api/fork/original", params={"seq": frame["seq"]})
        assert answer.status_code == 200, answer.text
        body = answer.json()
        assert body["t"] == frame["t"] and body["seq"] < reply["result"]["start"]
        assert body["fork"] == hello["fork"]
        # Unchanged behavior: the original's paths are the fork's (compared by name), every robot.
        structure = hello["structure"]
        roots = set()
        for robot in frame["robots"]:
            program = structure["programs"][structure["robots"][robot["id"]]["program"]]
            options = {o["id"]: o for o in program["options"]}
            own = [(options[n[2]]["name"], options[n[2]]["states"][n[3]]["name"]) for n in robot["path"] if n[0] == 0]
            theirs = [(n["option"], n["state"]) for n in body["robots"][robot["id"]]["path"] if "option" in n]
            assert own and own == theirs
            roots.add(own[0][0])
        assert roots == {"play_soccer", "chase_play"}
        refused = client.command("fork", seq=0)
        assert refused["ok"] is False and "not in the history" in refused["error"]
        assert http.get("/api/fork/original", params={"seq": 1}).status_code == 404
        assert client.command("reset")["ok"]
        client.wait_hello("reset")
        gone = http.get("/api/fork/original", params={"seq": frame["seq"]})
        assert gone.status_code == 404 and "not a fork" in gone.json()["detail"]


def test_the_log_bounds_refuse_with_the_reason(soccer_dir: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from xabsl_studio.server.simulation import runlog, worker

    monkeypatch.setattr(runlog, "MAX_EVENTS", 3)
    joined = Joined(SoccerExample(soccer_dir, players_per_team=2))
    joined.run(20)
    for value in (True, False, True):
        joined.do(OverrideInput(op="override_input", robot=1, symbol="ball.seen", value=value))
        joined.run(10)
    within = max(joined.samples)
    joined.do(OverrideInput(op="override_input", robot=1, symbol="ball.seen", value=False))  # not kept any more
    joined.run(10)
    with pytest.raises(CommandError, match=r"session log stopped at tick \d+ \(more than 3 commands"):
        joined.fork(max(joined.samples) - 2)
    assert joined.fork(within)["seq"] == within, "ticks before the log filled up still fork"
    joined.run(10)
    monkeypatch.setattr(worker, "FORK_MAX_SECONDS", 1.0)
    with pytest.raises(CommandError, match=r"re-simulates \d+ s since the world was built \(at most 1 s\)"):
        joined.fork(max(joined.samples) - 1)
    joined.sim.logs[-1].problem = "the world started from a recording"
    with pytest.raises(CommandError, match="cannot be forked: the world started from a recording"):
        joined.fork(max(joined.samples) - 1)


def test_the_errands_world_forks_exactly_with_its_commands_replayed() -> None:
    from xabsl_studio.examples.errands.studio import example

    joined = Joined(example(Path(__file__).resolve().parents[3] / "examples" / "errands"), seed=2)
    joined.run(200)
    joined.do(WorldCommand(op="world_command", name="teleport", args={"object": "mug", "to": "c"}))
    joined.run(40)
    joined.do(Pause(op="pause"))
    joined.do(WorldCommand(op="world_command", name="block", args={"from": "a", "to": "b"}))
    joined.do(WorldCommand(op="world_command", name="plan_stats", args={}))  # a query: replayed, harmless
    joined.run(100)
    fork_at = max(joined.samples) - 60
    joined.run(50)
    original = joined.tick_samples(fork_at, max(joined.samples))
    result = joined.fork(fork_at)
    joined.run(150)
    forked = joined.tick_samples(result["start"] + 1, max(joined.samples))
    compared = [t for t in forked if t in original]
    assert len(compared) == 111 and all(_same(forked[t], original[t]) for t in compared)
