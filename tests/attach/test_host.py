"""The host library against a studio's end of the wire: a robot process of its own, checked message by message.

The robot is ``examples/attach/robot.py`` run as a separate OS process (a program that is not
the studio's worker); the studio's end is :class:`tests.attach.peer.Peer`.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path
from typing import Any

import pytest

from xabsl_studio.engine.emit.ic import emit_ic
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.runtime import Engine
from xabsl_studio.examples.attach.robot import DEMO, Body, bind
from xabsl_studio.server.protocol.attach import HEARTBEAT_TIMEOUT, Control, HostGeneration, Refused, Welcome
from xabsl_studio.server.protocol.commands import ForceOption, OverrideInput, Release
from xabsl_studio.server.protocol.host import LoadIntermediateCode, Sample
from xabsl_studio.server.simulation.host import serve_engines

from .peer import Peer, start_robot, stop_robot

TOKEN = "attach-test-token-0123456789"


def option_ids(generation: HostGeneration) -> dict[str, int]:
    import orjson

    structure = orjson.loads(generation.generation.structure)
    return {o["name"]: o["id"] for o in structure["programs"]["behavior"]["options"]}


def root_option(sample: Sample, robot: int = 0) -> int:
    import orjson

    return int(orjson.loads(sample.paths[robot])[0][2])


@pytest.fixture
def robot() -> object:
    process, port = start_robot("--hz", "100")
    yield port
    stop_robot(process)


def test_every_tick_arrives_in_order() -> None:
    process, port = start_robot("--hz", "200", "--ticks", "600")
    peer = Peer(port)
    try:
        assert isinstance(peer.welcome(), Welcome)
        while True:
            try:
                peer.read(1.0)
            except ConnectionError:
                break
            peer.heartbeat()
        seqs = [s.seq for s in peer.samples()]
        assert seqs, "no tick arrived"
        assert seqs == list(range(seqs[0], 601)), "a tick is missing or out of order"
        assert len(seqs) > 300  # attached while it ran, not after
    finally:
        peer.close()
        out = stop_robot(process, wait=10)
    assert '"ticks":600' in out


def test_forcing_takes_effect_on_the_next_tick_and_release_ends_it(robot: int) -> None:
    peer = Peer(robot)
    try:
        assert isinstance(peer.welcome(), Welcome)
        ids = option_ids(peer.until(lambda m: isinstance(m, HostGeneration)))
        peer.until(lambda m: isinstance(m, Sample))
        assert root_option(peer.samples()[-1]) == ids["play"]
        ident = peer.request(ForceOption(op="force_option", robot=0, option="search_ball", params={}))
        reply = peer.reply(ident)
        assert reply.ok, reply.error
        at = peer.received.index(reply)
        following = peer.until(lambda m: isinstance(m, Sample) and peer.received.index(m) > at)
        assert root_option(following) == ids["search_ball"]
        assert b'"forced"' in following.extras[0]
        reply = peer.call(Release(op="release", robot=0))
        assert reply.ok
        at = peer.received.index(reply)
        following = peer.until(lambda m: isinstance(m, Sample) and peer.received.index(m) > at)
        assert root_option(following) == ids["play"] and following.extras[0] == b""
    finally:
        peer.close()


def test_a_studio_that_goes_silent_loses_its_forces_and_control(robot: int) -> None:
    silent = Peer(robot, studio="laptop")
    watcher = Peer(robot, studio="watcher", control=False)
    try:
        assert isinstance(silent.welcome(), Welcome)
        assert isinstance(watcher.welcome(), Welcome)
        assert silent.call(ForceOption(op="force_option", robot=0, option="search_ball", params={})).ok
        value = OverrideInput(op="override_input", robot=0, symbol="ball.seen", value=True)
        assert silent.call(value).ok
        watcher.until(lambda m: isinstance(m, Sample) and b'"forced"' in m.extras[0] and b'"overrides"' in m.extras[0])
        # The watcher may not take over while the laptop holds control.
        refused = watcher.call(ForceOption(op="force_option", robot=0, option="play", params={}))
        assert not refused.ok and "controlled by laptop" in (refused.error or "")
        # The laptop's network goes away: it says nothing more (no close, no heartbeat).
        deadline = time.monotonic() + HEARTBEAT_TIMEOUT + 5.0
        released = None
        while time.monotonic() < deadline and released is None:
            for message in watcher.read(0.5):
                if isinstance(message, Sample) and message.extras[0] == b"":
                    released = message
            watcher.heartbeat()
        assert released is not None, "the silent studio's forcing was not released"
        assert any(isinstance(m, Control) and m.holder is None for m in watcher.received)
    finally:
        silent.close()
        watcher.close()


def test_a_wrong_or_missing_token_is_refused() -> None:
    process, port = start_robot("--token", TOKEN)
    try:
        for token in (None, "nope", TOKEN[:-1] + "x"):
            peer = Peer(port, token=token)
            answer = peer.welcome()
            assert isinstance(answer, Refused) and "token" in answer.reason
            with pytest.raises(ConnectionError):
                peer.read(5.0)
            peer.close()
        peer = Peer(port, token=TOKEN)
        assert isinstance(peer.welcome(), Welcome)
        peer.close()
    finally:
        stop_robot(process)


def demo_ic(tmp_path: Path, edit: tuple[str, str] | None = None, behaviors: str = "") -> str:
    folder = tmp_path / "demo"
    folder.mkdir(exist_ok=True)
    for path in DEMO.parent.rglob("*.xabsl"):
        target = folder / path.relative_to(DEMO.parent)
        target.parent.mkdir(exist_ok=True)
        text = path.read_text()
        if edit is not None and path.name == "search_ball.xabsl":
            text = text.replace(*edit)
        if path.name == "basic_behaviors.xabsl" and behaviors:
            text = text.rstrip().rstrip("}") + behaviors + "}\n"
        target.write_text(text)
    compilation = compile_file(str(folder / "agents.xabsl"))
    assert compilation.program is not None, [d.format() for d in compilation.diagnostics]
    return emit_ic(compilation.program)


def test_a_reload_that_fails_on_the_host_is_answered_and_the_old_behavior_runs_on(robot: int, tmp_path: Path) -> None:
    peer = Peer(robot)
    try:
        assert isinstance(peer.welcome(), Welcome)
        first = peer.until(lambda m: isinstance(m, HostGeneration))
        ids = option_ids(first)
        # A basic behavior the robot program does not have: the host cannot link it.
        ic = demo_ic(tmp_path, ("turn(rate = 45);", "dance(style = 1);"), "\n  behavior dance { float style; }\n")
        reply = peer.call(LoadIntermediateCode("behavior", ic))
        assert reply.ok and "does not run on this host" in reply.result and "dance" in reply.result
        garbage = peer.call(LoadIntermediateCode("behavior", "this is not intermediate code"))
        assert garbage.ok and "does not read" in garbage.result
        at = len(peer.received)
        later = peer.until(lambda m: isinstance(m, Sample) and peer.received.index(m) > at + 2)
        assert later.gen == first.generation.number and root_option(later) == ids["play"]
        assert not [m for m in peer.received[at:] if isinstance(m, HostGeneration)]
    finally:
        peer.close()


def test_a_clean_reload_swaps_between_two_ticks(robot: int, tmp_path: Path) -> None:
    peer = Peer(robot)
    try:
        assert isinstance(peer.welcome(), Welcome)
        first = peer.until(lambda m: isinstance(m, HostGeneration))
        ic = demo_ic(tmp_path, ("state_time > 4000", "state_time > 1500"))
        ident = peer.request(LoadIntermediateCode("behavior", ic))
        generation = peer.until(lambda m: isinstance(m, HostGeneration) and m is not first)
        assert generation.generation.reason == "reload" and "1500" in generation.ics["behavior"]
        reply = peer.reply(ident)
        assert reply.ok and reply.result is None
        after = peer.until(lambda m: isinstance(m, Sample) and m.gen == generation.generation.number)
        assert after.seq > 0
    finally:
        peer.close()


def test_a_studio_that_never_reads_does_not_block_the_host_and_the_others_get_every_tick() -> None:
    program = compile_file(str(DEMO)).program
    assert program is not None
    body = Body(1)
    engine = Engine(bind(body), program)
    link = serve_engines({"robot1": engine}, port=0, backlog_bytes=64 * 1024)
    slow = Peer(link.port, studio="slow", control=False)
    fast = Peer(link.port, studio="fast", control=False)
    try:
        for peer in (slow, fast):
            peer.sock.settimeout(5)
        assert isinstance(fast.welcome(), Welcome)
        while link.studios < 2:
            time.sleep(0.01)
        done = threading.Event()

        def read_fast() -> None:
            while not done.is_set() or (fast.samples()[-1:] and fast.samples()[-1].seq < engine_ticks):
                fast.read(0.2)
                fast.heartbeat()

        # The slow studio's backlog (and the socket's buffers) overflow many times over, while the
        # reading one -- a thread of this process, which a loop that never lets go of the GIL
        # would starve -- keeps up, as a real studio does with a real robot.
        engine_ticks = 20_000
        reader = threading.Thread(target=read_fast)
        reader.start()
        beat = time.monotonic()
        for _ in range(engine_ticks):
            engine.execute(body.now_ms)
            link.publish()  # the slow studio never reads: this must never wait for it
            body.step(10)
            time.sleep(0)  # let the reading studio's thread run, as a robot's other work would
            if time.monotonic() - beat > 0.5:  # by the wall clock: a loaded machine ticks slower
                slow.heartbeat()
                beat = time.monotonic()
        done.set()
        reader.join(timeout=30)
        stats = {s["studio"]: s for s in link.stats()["studios"]}
        assert stats["slow"]["dropped"] > 0
        assert stats["fast"]["dropped"] == 0
        seqs = [s.seq for s in fast.samples()]
        assert seqs == list(range(seqs[0], engine_ticks + 1))
    finally:
        slow.close()
        fast.close()
        link.close()


def test_samples_carry_what_each_decision_read_as_plain_json(robot: int) -> None:
    """Read as a program written from docs/attach.md would: raw frames, json.loads, no project decoder."""
    import json
    import socket
    import struct

    sock = socket.create_connection(("127.0.0.1", robot), timeout=10)
    body = json.dumps({"type": "attach", "protocol": 2, "token": None, "studio": "raw", "control": False}).encode()
    sock.sendall(struct.pack(">I", len(body)) + body)
    buffer = b""
    messages: list[dict[str, object]] = []
    try:
        while sum(m["type"] == "sample" for m in messages) < 50:
            received = sock.recv(1 << 16)
            assert received, f"the host closed the connection: {messages[-1:]}"
            buffer += received
            while len(buffer) >= 4 and len(buffer) >= 4 + struct.unpack(">I", buffer[:4])[0]:
                size = struct.unpack(">I", buffer[:4])[0]
                messages.append(json.loads(buffer[4 : 4 + size]))
                buffer = buffer[4 + size :]
    finally:
        sock.close()
    generation = next(m for m in messages if m["type"] == "generation")
    structure: dict[str, Any] = generation["structure"]  # type: ignore[assignment]
    enums: dict[str, Any] = generation["enums"]  # type: ignore[assignment]
    assert generation["raw_values"] is True  # the symbols come as the host read them
    # game.state's host values (the robot's own numbering) name its elements
    assert set(enums["behavior"]["game.state"].values()) >= {"game.state.playing", "game.state.ready"}
    options = {o["id"]: o["name"] for o in structure["programs"]["behavior"]["options"]}
    inputs = {s["id"]: s["name"] for s in structure["programs"]["behavior"]["inputs"]}
    samples = [m for m in messages if m["type"] == "sample"]
    # The decisions record their reads from the first tick a studio watches: null (unknown) before.
    unknown = [s for s in samples if s["robots"][0][4] is None]  # type: ignore[index]
    assert unknown == samples[: len(unknown)] and len(unknown) <= 2
    for sample in samples[len(unknown) :]:
        [path, _, _, _, reads] = sample["robots"][0]  # type: ignore[index]
        assert isinstance(reads, list) and reads and reads[0] == path[0][2]  # the root option decides first
        ran = {n[2] for n in path if n[0] == 0}
        assert {r for r in reads if isinstance(r, int)} <= ran
        read_inputs = {inputs[r[0]] for r in reads if isinstance(r, list) and r[0] in inputs and len(r) == 2}
        assert "game.state" in read_inputs  # play's common decision reads it every tick
        assert all(options[r] for r in reads if isinstance(r, int))
        # the symbols are raw: each plain input a decision read has exactly the value it read
        ids: list[int] = generation["input_ids"][0]  # type: ignore[index]
        values = dict(zip(ids, sample["robots"][0][2], strict=True))  # type: ignore[index]
        read_values = {r[0]: r[1] for r in reads if isinstance(r, list) and r[0] in inputs and len(r) == 2}
        assert read_values and all(values[i] == v for i, v in read_values.items())
