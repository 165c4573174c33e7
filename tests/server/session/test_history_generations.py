"""History across generations: the ring's ticks of earlier generations, their descriptions, diffs."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import httpx2 as httpx

from tests.server.conftest import LiveServer, WsClient
from xabsl_studio.server.session.frames import Entry, Generation, Ring
from xabsl_studio.server.session.generations import MAX_GENERATIONS, Generations, changed_files, unified_diff

PLAY = "options/play.xabsl"


def _history(client: WsClient, **args: Any) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    reply = client.command("history", **args)
    assert reply["ok"], reply
    frames: list[dict[str, Any]] = []
    if reply["result"]["chunks"]:
        while True:
            message = client.until(lambda m: m["type"] == "history")
            frames.extend(message["frames"])
            if message["last"]:
                break
    return reply["result"], frames


def _edit(server: LiveServer, demo_dir: Path) -> tuple[str, str]:
    """Save play.xabsl with one line changed (a hot reload); the line before and after."""
    text = (demo_dir / PLAY).read_text()
    old = next(line for line in text.splitlines() if "goto search" in line)
    new = old.replace("goto search", "goto wait")
    with httpx.Client(base_url=server.url) as http:
        version = http.get(f"/api/files/{PLAY}").headers["etag"]
        response = http.put(f"/api/files/{PLAY}", json={"text": text.replace(old, new)}, headers={"If-Match": version})
        assert response.status_code == 200, response.text
    return old, new


def test_history_serves_earlier_generations_with_their_descriptions(
    live_demo: LiveServer, client_for: Any, demo_dir: Path
) -> None:
    client = client_for(live_demo)
    hello = client.until(lambda m: m["type"] == "hello")
    first = hello["generation"]
    client.wait_frame(lambda f: f["t"] > 800)
    old, new = _edit(live_demo, demo_dir)
    reloaded = client.wait_hello("reload")
    assert reloaded["generation"] == first + 1 and reloaded["session"]["offset"] == 0
    client.wait_frame(lambda f: f["gen"] == first + 1 and f["t"] > reloaded["session"]["t"] + 200)

    result, frames = _history(client)
    gens = {g["number"]: g for g in result["generations"]}
    assert sorted(gens) == [first, first + 1]
    # The old generation comes with what reads its ticks; the current one's is in the hello.
    assert gens[first]["structure"]["programs"]["demo"]["options"] and "structure" not in gens[first + 1]
    assert gens[first]["reason"] == "connect" and gens[first + 1]["reason"] == "reload"
    assert gens[first + 1]["changed_files"] == [PLAY] and gens[first]["changed_files"] == []
    # Per generation: a full frame, then deltas in seq order; the old ticks come first.
    by_gen = [[f for f in frames if f["gen"] == g] for g in (first, first + 1)]
    assert all(run and run[0]["full"] is True and not any(f["full"] for f in run[1:]) for run in by_gen)
    assert frames == by_gen[0] + by_gen[1]
    seqs = [f["seq"] for f in frames]
    assert seqs == sorted(seqs) and seqs == list(range(seqs[0], seqs[0] + len(seqs)))
    assert by_gen[0][0]["t"] <= 100 and by_gen[0][-1]["t"] >= 800
    assert len(frames) == result["frames"]
    # A window of timeline time: the reload's tick and after only.
    result, frames = _history(client, t0=reloaded["session"]["t"] + 1)
    assert [g["number"] for g in result["generations"]] == [first + 1] and {f["gen"] for f in frames} == {first + 1}

    with httpx.Client(base_url=live_demo.url) as http:
        diff = http.get(f"/api/generations/{first + 1}/diff")
        assert diff.status_code == 200, diff.text
        body = diff.json()
        assert body["reason"] == "reload" and body["previous"] == first
        [changed] = body["files"]
        assert changed["path"] == PLAY and changed["change"] == "changed" and changed["program"] == "demo"
        assert f"-{old}" in changed["diff"].splitlines() and f"+{new}" in changed["diff"].splitlines()
        assert changed["diff"].startswith(f"--- {PLAY} (generation {first})")
        # The first generation has no previous one to compare with; a future one does not exist.
        assert http.get(f"/api/generations/{first}/diff").status_code == 404
        missing = http.get(f"/api/generations/{first + 50}/diff")
        assert missing.status_code == 404 and "not kept" in missing.json()["detail"]
        assert http.get("/api/generations/-1/diff").status_code == 422


def test_a_reset_continues_the_timeline_and_keeps_the_ticks_before(live_demo: LiveServer, client_for: Any) -> None:
    client = client_for(live_demo)
    hello = client.until(lambda m: m["type"] == "hello")
    first = hello["generation"]
    before = client.wait_frame(lambda f: f["t"] > 1000)
    assert client.command("reset")["ok"]
    reset = client.wait_hello("reset")
    client.wait_frame(lambda f: f["gen"] == reset["generation"] and f["t"] > 300)
    result, frames = _history(client)
    gens = {g["number"]: g for g in result["generations"]}
    assert sorted(gens) == [first, first + 1] and gens[first + 1]["reason"] == "reset"
    assert gens[first + 1]["changed_files"] == []  # a reset with the same behavior changes no file
    # The world's clock restarted; the timeline (t + offset) goes on one tick after the last old tick.
    offset = gens[first + 1]["offset"]
    assert offset == reset["session"]["offset"] > before["t"]
    last_old = max(f["t"] + gens[first]["offset"] for f in frames if f["gen"] == first)
    first_new = min(f["t"] + offset for f in frames if f["gen"] == first + 1)
    assert first_new == last_old + 1000 // live_demo.session.behavior_hz
    # Timeline windows select by t + offset: only the new generation's ticks lie past the old ones.
    result, frames = _history(client, t0=last_old + 1)
    assert {f["gen"] for f in frames} == {first + 1} and frames[0]["full"] is True


def _gen(number: int, reason: Any = "reload") -> Generation:
    return Generation(number, reason, {"programs": {}, "robots": []}, b"{}", b"{}", (), ())


def test_generations_share_unchanged_texts_and_are_bounded() -> None:
    kept = Generations()
    a, b = "option a {}\n", "option b {}\n"
    kept.add(_gen(1, "connect"), {"x": {"a.xabsl": a, "b.xabsl": b}})
    g2 = _gen(2)
    kept.add(g2, {"x": {"a.xabsl": "".join(["option a ", "{}\n"]), "b.xabsl": "option b { }\n", "c.xabsl": ""}})
    assert g2.changed == {"x": ["b.xabsl", "c.xabsl"]}
    g1 = kept.get(1)
    assert g1 is not None and g2.sources["x"]["a.xabsl"] is g1.sources["x"]["a.xabsl"]  # one string kept
    diff = kept.diff(2)
    assert [(f["path"], f["change"]) for f in diff["files"]] == [("b.xabsl", "changed"), ("c.xabsl", "added")]
    for n in range(3, MAX_GENERATIONS + 10):
        kept.add(_gen(n), {"x": {"a.xabsl": a}})
    assert len(kept) == MAX_GENERATIONS and kept.get(1) is None
    assert kept.get(MAX_GENERATIONS + 9) is not None


def test_generations_older_than_the_ring_are_dropped_but_the_one_before_it() -> None:
    ring = Ring(1.0, 10)
    kept = Generations()
    gens = [_gen(n) for n in range(1, 6)]
    for gen in gens[:4]:
        kept.add(gen, {})
    assert len(kept) == 4  # an empty ring keeps everything up to the bounds
    ring.append(Entry(1, gens[2], 0, 0.0, (), (), False, True, b"{}"))
    kept.add(gens[4], {}, ring)
    assert [n for n in range(1, 6) if kept.get(n)] == [2, 3, 4, 5]


def test_changed_files_and_diff_of_added_and_removed_files() -> None:
    assert changed_files({}, {"k": {"a": "x"}}) == {"k": ["a"]}
    assert changed_files({"k": {"a": "x", "b": "y"}}, {"k": {"a": "x"}}) == {"k": ["b"]}
    assert changed_files({"k": {"a": "x"}}, {"k": {"a": "x"}}) == {}
    text = unified_diff("a", "one\ntwo", "one\nthree", 4)
    assert text.splitlines() == [
        "--- a (generation 3)",
        "+++ a (generation 4)",
        "@@ -1,2 +1,2 @@",
        " one",
        "-two",
        "+three",
    ]


def test_explain_of_a_tick_before_a_reload_uses_that_ticks_ids(
    live_demo: LiveServer, client_for: Any, demo_dir: Path
) -> None:
    client = client_for(live_demo)
    client.until(lambda m: m["type"] == "hello")
    old_play = client.option_id("play")
    before = client.wait_frame(lambda f: f["t"] > 800 and f["robots"][0]["path"][0][2] == old_play)
    # A new option sorted first renumbers every option: play's id changes.
    (demo_dir / "options" / "aaa_idle.xabsl").write_text(
        "/** Stands. */\noption aaa_idle {\n  initial state idle {\n    action {\n      stand();\n    }\n  }\n}\n"
    )
    agents = demo_dir / "agents.xabsl"
    agents.write_text(
        agents.read_text().replace(
            'include "options/play.xabsl";', 'include "options/aaa_idle.xabsl";\ninclude "options/play.xabsl";'
        )
    )
    assert client.command("reload")["ok"]
    client.wait_hello("reload")
    assert client.option_id("play") != old_play
    for option in ("play", old_play):
        reply = client.command("explain", robot=0, option=option, seq=before["seq"])
        assert reply["ok"], reply
        assert reply["result"]["option_name"] == "play" and reply["result"]["seq"] == before["seq"]
