import { describe, expect, it } from "vitest";
import { indexDescription } from "../src/description";
import { TickBuffer } from "../src/history";
import { FrameDecoder, type Tick } from "../src/protocol";
import { Session } from "../src/session";
import { buildRobotTimeline, buildTeamTimeline } from "../src/timeline";
import { description, frame, hello, playPath } from "./fake";

const index = indexDescription(description);

/// play: wait (ticks 0-1), chase with approach_ball go (2-3), chase/kick (4), search (5).
function ticks(): Tick[] {
  const d = new FrameDecoder();
  const states: Array<[number, number]> = [[0, 0], [0, 0], [1, 0], [1, 0], [1, 1], [2, 0]];
  return states.map(([play, approach], i) => d.decode(frame(i + 1, i * 25, [{ id: 0, path: playPath(play, approach) }, { id: 1, path: playPath(2) }], i === 0)));
}

describe("buildRobotTimeline", () => {
  it("has one row per option and behavior, root first, segments per state", () => {
    const rows = buildRobotTimeline(ticks(), 0, index);
    expect(rows.map((r) => `${r.kind}:${r.label}`)).toEqual(["option:play", "option:approach_ball", "behavior:stand", "behavior:walk"]);
    const play = rows[0];
    expect(play?.segments.map((s) => [s.label, s.t0, s.t1])).toEqual([
      ["wait", 0, 50],
      ["chase", 50, 125],
      ["search", 125, 150],
    ]);
    const approach = rows[1];
    expect(approach?.segments.map((s) => [s.label, s.t0, s.t1])).toEqual([
      ["go", 50, 100],
      ["kick", 100, 125],
    ]);
    const stand = rows[2];
    expect(stand?.segments.map((s) => [s.t0, s.t1])).toEqual([
      [0, 50],
      [125, 150],
    ]);
  });

  it("works without a description and for an unknown agent", () => {
    expect(buildRobotTimeline(ticks(), 0, null)[0]?.label).toBe("option 1");
    expect(buildRobotTimeline(ticks(), 9, index)).toEqual([]);
  });
});

describe("buildTeamTimeline", () => {
  it("labels each agent's root option/state", () => {
    const rows = buildTeamTimeline(ticks(), [{ id: 0, name: "blue1" }, { id: 1, name: "blue2" }], () => index);
    expect(rows[0]?.segments.map((s) => s.label)).toEqual(["play/wait", "play/chase", "play/search"]);
    expect(rows[1]?.segments).toHaveLength(1);
    expect(rows[1]?.segments[0]).toMatchObject({ label: "play/search", t0: 0, t1: 150 });
    expect(rows[0]?.segments[2]?.key).toBe(rows[1]?.segments[0]?.key);
  });
});

describe("TickBuffer", () => {
  it("keeps order, drops old ticks, merges history and finds ticks by time", () => {
    const buffer = new TickBuffer(100);
    const all = ticks();
    for (const t of all.slice(3)) buffer.push(t);
    buffer.push(all[1] as Tick); // older than the newest: ignored
    expect(buffer.all.map((t) => t.seq)).toEqual([4, 5, 6]);
    buffer.merge(all.slice(0, 5));
    expect(buffer.all.map((t) => t.seq)).toEqual([2, 3, 4, 5, 6]); // t=0 is more than 100 ms old
    expect(buffer.all[2]).toBe(all[3]); // the live tick won
    expect(buffer.at(60)?.seq).toBe(3);
    expect(buffer.at(-5)?.seq).toBe(2);
    expect(buffer.bySeq(5)?.t).toBe(100);
    expect(buffer.range(50, 100).map((t) => t.seq)).toEqual([3, 4, 5]);
  });
});

describe("Session", () => {
  it("notes state changes, scrubs, and forgets everything on a hello", () => {
    const s = new Session();
    s.applyHello(hello(1));
    s.applyFrame(frame(1, 0, [{ id: 0, path: playPath(0) }], true));
    s.applyFrame(frame(2, 25, [{ id: 0, path: playPath(1, 0, 0, 1) }]));
    s.applyFrame(frame(3, 50, [{ id: 0, path: playPath(1) }]));
    expect(s.transitions.get(0)?.get(1)).toEqual({ from: 0, to: 1, leaf: 1, t: 25 });
    expect(s.isLive).toBe(true);
    s.setCursor(10);
    expect(s.view?.seq).toBe(1);
    s.stepCursor(1);
    expect(s.view?.seq).toBe(2);
    s.stepCursor(1);
    expect(s.isLive).toBe(true);
    s.stepCursor(-2);
    expect(s.view?.seq).toBe(1);
    expect([...s.takeChanges()].sort()).toEqual(["cursor", "hello", "tick"]);
    s.applyHello(hello(2));
    expect(s.buffer.length).toBe(0);
    expect(s.isLive).toBe(true);
    expect(s.transitions.size).toBe(0);
  });

  it("merges history of the current generation only", () => {
    const s = new Session();
    s.applyHello(hello(3));
    s.applyFrame(frame(10, 250, [{ id: 0, path: playPath(1) }], true, 3));
    s.applyHistory([frame(8, 200, [{ id: 0, path: playPath(0) }], true, 3), frame(9, 225, [{ id: 0, path: playPath(0) }], false, 3), frame(7, 175, [], true, 2)]);
    expect(s.buffer.all.map((t) => t.seq)).toEqual([8, 9, 10]);
  });
});
