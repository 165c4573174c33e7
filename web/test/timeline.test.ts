import { describe, expect, it } from "vitest";
import { indexDescription } from "../src/description";
import { TickBuffer } from "../src/history";
import { FrameDecoder, type Hello, type Tick } from "../src/protocol";
import type { GenerationInfo } from "../src/messages.gen";
import { Session } from "../src/session";
import { buildRobotTimeline, buildTeamTimeline } from "../src/timeline";
import { description, editedDescription, frame, hello, playPath } from "./fake";

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

describe("history across generations", () => {
  function next(generation: number, reason: "reload" | "reset", offset = 0, programs = { behavior: editedDescription() }): Hello {
    const h = hello(generation);
    return { ...h, reason, session: { ...h.session, offset }, structure: { ...h.structure, programs } };
  }

  it("keeps the ticks of a reload's previous generation and reads each tick with its own ids", () => {
    const s = new Session();
    s.applyHello(hello(1));
    s.applyFrame(frame(1, 0, [{ id: 0, path: playPath(0) }], true));
    s.applyFrame(frame(2, 25, [{ id: 0, path: playPath(0) }]));
    s.applyHello(next(2, "reload"));
    s.applyFrame(frame(3, 25, [{ id: 0, path: playPath(0) }], true, 2));
    s.applyFrame(frame(4, 50, [{ id: 0, path: playPath(0) }], false, 2));
    expect(s.buffer.all.map((t) => [t.seq, t.gen])).toEqual([[1, 1], [2, 1], [3, 2], [4, 2]]);
    expect(s.buffer.starts().map((t) => t.seq)).toEqual([3]);
    expect(s.generations.get(2)?.reason).toBe("reload");
    const stateName = (): string | undefined => {
      const node = s.robotInView()?.path[0];
      return node?.kind === "option" ? s.indexOf(0)?.optionById.get(node.option)?.states[node.state]?.name : undefined;
    };
    expect(s.indexOf(0)?.optionById.get(1)?.name).toBe("play_edited");
    const live = stateName();
    s.takeChanges();
    s.setCursor(10);
    expect(s.view?.seq).toBe(1);
    expect(s.shownGeneration?.number).toBe(1);
    expect(s.indexOf(0)?.optionById.get(1)?.name).toBe("play");
    expect(stateName()).toBe("wait");
    expect(live).not.toBe("wait"); // the same state id names another state in the edited behavior
    expect(s.takeChanges().has("hello")).toBe(true); // panels rebuild with the old ids
    expect(s.currentIds(0).option(1)).toBe(-1); // "play" is gone from the current generation
    expect(s.currentIds(0).option(0)).toBe(0); // approach_ball kept its name and id
    s.setCursor(null);
    expect(s.indexOf(0)?.optionById.get(1)?.name).toBe("play_edited");
    const rows = buildRobotTimeline(s.buffer.all, 0, (gen) => s.indexIn(gen, 0));
    expect(rows.map((r) => r.label).slice(0, 2)).toEqual(["play", "play_edited"]);
  });

  it("puts a reset's ticks after the earlier ones on the timeline (x = t + offset)", () => {
    const s = new Session();
    s.applyHello(hello(1));
    s.applyFrame(frame(1, 0, [{ id: 0, path: playPath(0) }], true));
    s.applyFrame(frame(2, 25, [{ id: 0, path: playPath(1) }]));
    s.applyHello(next(2, "reset", 50, { behavior: description }));
    s.applyFrame(frame(3, 0, [{ id: 0, path: playPath(2) }], true, 2));
    s.applyFrame(frame(4, 25, [{ id: 0, path: playPath(2) }], false, 2));
    expect(s.buffer.all.map((t) => [t.t, t.x])).toEqual([[0, 0], [25, 25], [0, 50], [25, 75]]);
    s.setCursor(30);
    expect(s.view?.seq).toBe(2);
    s.setCursor(60);
    expect(s.view?.seq).toBe(3);
    expect(s.buffer.range(40, 100).map((t) => t.seq)).toEqual([3, 4]);
    // A server time (a breakpoint hit, a fact): of the current generation, or of its tick's seq.
    s.seekTick(25);
    expect(s.view?.seq).toBe(4);
    s.seekTick(25, 2);
    expect(s.view?.seq).toBe(2);
  });

  it("takes earlier generations' descriptions from a history answer and drops ticks it cannot read", () => {
    const s = new Session();
    s.applyHello(next(3, "reload"));
    s.applyFrame(frame(10, 250, [{ id: 0, path: playPath(1) }], true, 3));
    const info = (number: number, reason: "connect" | "reload", withStructure: boolean): GenerationInfo => ({
      number,
      reason,
      offset: 0,
      seq: 0,
      t: 0,
      changed_files: reason === "reload" ? ["options/play.xabsl"] : [],
      ...(withStructure ? { structure: hello(number).structure as unknown as GenerationInfo["structure"], scene: hello(number).scene as unknown as Record<string, unknown> } : {}),
    });
    s.applyHistory(
      [frame(7, 175, [{ id: 0, path: playPath(0) }], true, 2), frame(8, 200, [{ id: 0, path: playPath(0) }], false, 2), frame(5, 100, [], true, 1), frame(9, 225, [{ id: 0, path: playPath(1) }], true, 3)],
      [info(2, "connect", true), info(3, "reload", false)],
    );
    expect(s.buffer.all.map((t) => t.seq)).toEqual([7, 8, 9, 10]); // generation 1 is unknown
    expect(s.generations.get(3)?.changedFiles).toEqual(["options/play.xabsl"]);
    expect(s.indexIn(2, 0)?.optionById.get(1)?.name).toBe("play");
    expect(s.indexIn(3, 0)?.optionById.get(1)?.name).toBe("play_edited");
    // A reconnect may be another server: it starts over.
    s.applyHello(hello(1));
    expect(s.buffer.length).toBe(0);
    expect([...s.generations.keys()]).toEqual([1]);
  });
});
