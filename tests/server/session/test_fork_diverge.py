"""A live fork against its original: no divergence with the same behavior, the edited decision found with one."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest
from pydantic import TypeAdapter

from tests.server.conftest import LiveServer
from tests.server.session.test_fork import Joined
from xabsl_studio.engine.emit.json import program_to_json
from xabsl_studio.examples.soccer.studio import SoccerExample
from xabsl_studio.server.protocol.commands import Pause, Step
from xabsl_studio.server.protocol.host import Apply, FromWorker, Sample
from xabsl_studio.server.protocol.replies import ForkOrigin
from xabsl_studio.server.protocol.rest import ForkDivergenceJson, NamedNode
from xabsl_studio.server.session.forkdiff import ForkDivergence, parting_option
from xabsl_studio.server.session.frames import FrameRecorder, Ring
from xabsl_studio.server.session.live import Session


def _fork(client: Any, session: Session, back: int) -> dict[str, Any]:
    """Fork ``back`` kept ticks before the newest one, run on 60 ticks; the fork's hello."""
    held = session.ring.snapshot()  # at speed 20 the pipe may drop samples: fork at a tick it kept
    reply = client.command("fork", seq=held[-back].seq)
    assert reply["ok"], reply
    hello: dict[str, Any] = client.wait_hello("fork")
    assert client.command("step", ticks=60)["ok"]
    client.wait_frame(lambda f: f["gen"] == hello["generation"] and f["seq"] >= reply["result"]["start"] + 59)
    return hello


def _diverge(http: httpx.Client) -> ForkDivergenceJson:
    answer = http.get("/api/fork/diverge")
    assert answer.status_code == 200, answer.text
    # the one definition of the shape, no key it lacks (rest.py: extra="forbid")
    return TypeAdapter(ForkDivergenceJson).validate_python(answer.json())


def test_a_fork_with_the_same_behavior_never_diverges_and_an_edited_one_does(soccer_dir: Path, client_for: Any) -> None:
    session = Session(SoccerExample(soccer_dir, players_per_team=2), seed=3, speed=20.0)
    with LiveServer(session) as server, httpx.Client(base_url=server.url) as http:
        assert http.get("/api/fork/diverge").status_code == 404  # no fork yet
        client = client_for(server)
        client.wait_hello("connect")
        client.wait_frame(lambda f: f["t"] > 14_000)  # playing: the chasers chase
        assert client.command("pause")["ok"]
        hello = _fork(client, session, 120)
        same = _diverge(http)
        assert same["start"] == hello["fork"]["start"] and same["scanned"] >= same["start"] + 59
        assert same["robots"] == [] and same["earliest"] is None, "the same behavior from the same state acts alike"

        # The chasers now leave `chase` for `search` on every tick: their decision in chase_ball differs.
        listing = http.get("/api/files").json()["files"]
        path = next(f["path"] for f in listing if f["path"].endswith("chase_ball.xabsl"))
        file = http.get(f"/api/files/{path}").json()
        text = file["text"].replace("      else\n        stay;", "      else\n        goto search;", 1)
        assert text != file["text"]
        saved = http.put(f"/api/files/{path}", json={"text": text}, headers={"If-Match": f'"{file["version"]}"'})
        assert saved.status_code == 200, saved.text
        client.wait_hello("reload")
        hello = _fork(client, session, 200)
        deadline = time.monotonic() + 30
        while not (found := _diverge(http))["robots"] and time.monotonic() < deadline:
            time.sleep(0.2)
        chasers = {r["name"]: r for r in found["robots"]}
        structure = hello["structure"]
        chase = {r["name"] for r in structure["robots"] if r["program"] == "chase"}
        # a chaser in `chase` leaves it at once (one searching for the ball may not, in these ticks)
        assert chasers and set(chasers) <= chase, found
        for name in chasers:
            divergence = chasers[name]
            assert divergence["option"] == "chase_ball"
            assert divergence["seq"] >= hello["fork"]["start"] and divergence["original_seq"] < hello["fork"]["start"]
            fork_states = {n.get("state") for n in divergence["fork_path"] if n.get("option") == "chase_ball"}
            original_states = {n.get("state") for n in divergence["original_path"] if n.get("option") == "chase_ball"}
            assert fork_states != original_states
            assert divergence["why_fork"] is not None and divergence["why_original"] is not None
            assert divergence["why_original"]["decided_in"] == "chase"
            assert (divergence["why_fork"]["decided_in"], divergence["why_fork"]["target"]) == ("chase", "search")
        assert found["earliest"] == min(found["robots"], key=lambda r: (r["seq"], r["robot"]))


def _option(depth: int, option: str, state: str) -> NamedNode:
    return {"depth": depth, "option": option, "state": state}


@pytest.mark.parametrize(
    ("fork", "original", "option"),
    [
        # the same option in another state: its decision
        ([_option(0, "a", "x"), _option(1, "b", "p")], [_option(0, "a", "x"), _option(1, "b", "q")], "b"),
        # another option called: the caller's decision
        ([_option(0, "a", "x"), _option(1, "b", "p")], [_option(0, "a", "y"), _option(1, "c", "p")], "a"),
        ([_option(0, "a", "x"), _option(1, "b", "p")], [_option(0, "a", "x"), _option(1, "c", "p")], "a"),
        # one calls a basic behavior more
        ([_option(0, "a", "x"), {"depth": 1, "behavior": "kick"}], [_option(0, "a", "x")], "a"),
        ([_option(0, "a", "x")], [_option(0, "a", "x")], None),
    ],
)
def test_the_parting_option(fork: list[NamedNode], original: list[NamedNode], option: str | None) -> None:
    assert parting_option(fork, original) == option


class Lossy(Joined):
    """The joined harness with a second ring that misses the samples of ``lost`` seqs, and a pipe
    that drops what the simulation lets it drop when ``congested``."""

    def __init__(self, example: Any) -> None:
        self.lost: set[int] = set()
        self.congested = False
        self.received: list[int] = []
        self.lossy_ring: Ring | None = None
        super().__init__(example)
        # from here on every sample but the lost ones, with the generation the harness records under
        self.lossy_ring = Ring(4800 / self.sim.behavior_hz, self.sim.behavior_hz)
        self.lossy = FrameRecorder(self.lossy_ring)

    def _emit(self, message: FromWorker, droppable: bool = False) -> bool:
        if isinstance(message, Sample) and self.congested and droppable:
            return False
        super()._emit(message, droppable)
        if isinstance(message, Sample):
            self.received.append(message.seq)
            if self.lossy_ring is not None and message.seq not in self.lost:
                self.lossy.record(self.generation, message)
        return True


def _search_at_once(joined: Joined, root: Path) -> Apply:
    """The chasers' behavior leaving `chase` for `search` on every tick (compiled clean)."""
    path = root / "chase" / "chase_ball.xabsl"
    text = path.read_text(encoding="utf-8").replace("      else\n        stay;", "      else\n        goto search;", 1)
    compilation = joined.session.compile("chase", {str(path.resolve()): text})
    assert compilation.program is not None, [d.as_dict() for d in compilation.diagnostics]
    return Apply("chase", compilation.program, program_to_json(compilation.program, compilation.source_text))


def test_a_divergence_behind_dropped_samples_says_the_ticks_it_could_not_compare(soccer_dir: Path) -> None:
    """CI (a loaded machine) dropped the fork's first samples: the divergence was named at a later
    tick, "fork search stays", as if that were where the paths part."""
    joined = Lossy(SoccerExample(soccer_dir, players_per_team=2))
    joined.run(900)  # playing: the chasers chase
    fork_at = max(joined.samples) - 60
    joined.do(_search_at_once(joined, soccer_dir))
    result = joined.fork(fork_at)
    start = result["start"]
    joined.lost = {start + 1, start + 2}
    joined.run(60)
    fork = ForkOrigin(seq=fork_at, t=joined.samples[fork_at].t, start=start)
    whole, lossy = ForkDivergence(fork), ForkDivergence(fork)
    whole.update(joined.ring)
    assert joined.lossy_ring is not None
    lossy.update(joined.lossy_ring)
    parted = [d for d in whole.found.values() if d["seq"] == start + 1]
    assert parted and all(d["uncompared_before"] == 0 for d in parted), "all compared: the very tick, nothing unsure"
    for divergence in parted:
        seen = lossy.found[divergence["robot"]]
        assert (seen["seq"], seen["uncompared_before"]) == (start + 3, 2)
        assert seen["option"] == divergence["option"] == "chase_ball"


def test_a_new_generations_first_second_of_samples_is_never_dropped(soccer_dir: Path) -> None:
    """A fork's parting tick and what a reload changed are in a generation's first ticks, when the
    server is busiest: a congested pipe drops samples only after them."""
    joined = Lossy(SoccerExample(soccer_dir, players_per_team=2))
    joined.run(200)
    fork_at = max(joined.samples) - 60
    hz = joined.sim.behavior_hz
    joined.do(Pause(op="pause"))
    joined.congested = True
    start = joined.fork(fork_at)["start"]
    joined.received.clear()
    joined.do(Step(op="step", ticks=hz + 20))
    kept = list(range(start + 1, start + 1 + hz))
    # the first second arrives whole, the rest is dropped but the tick a paused client shows
    assert joined.received == [*kept, start + hz + 20]
