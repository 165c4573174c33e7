import { describe, expect, it } from "vitest";
import { type DescriptionIndex, indexDescription } from "../src/description";
import { TickBuffer } from "../src/history";
import type { PathNode, RobotState, Tick } from "../src/protocol";
import { buildRobotTimeline, buildTeamTimeline, type TimelineContext, TimelineBuilder, type TimelineRow, type TimelineUpdate } from "../src/timeline";
import { description, editedDescription } from "./fake";

const DEMO = indexDescription(description);
const EDITED = indexDescription(editedDescription());
const ROBOTS = [0, 1, 2];

/// Descriptions by generation: 1 the demo, 2 the edited demo (robot 2 still reads the demo), 3 unknown.
function indexOf(robotId: number, gen: number): DescriptionIndex | null {
  if (gen === 1) return DEMO;
  if (gen === 2) return robotId === 2 ? DEMO : EDITED;
  return null;
}

/// A seeded random source (mulberry32), so a failure names the seed that reproduces it.
function random(seed: number): () => number {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

function option(depth: number, id: number, state: number): PathNode {
  return { kind: "option", depth, option: id, state, optionTime: 0, stateTime: 0, decidedIn: state, leaf: 0, params: [] };
}

function behavior(depth: number, id: number): PathNode {
  return { kind: "behavior", depth, behavior: id, time: 0, params: [] };
}

/// A path as the demo runs them (play over approach_ball or a behavior), now and then an odd
/// one: unknown ids, a behavior as root, a behavior twice (two branches), nothing active.
function randomPath(rnd: () => number): PathNode[] {
  const pick = (n: number): number => Math.floor(rnd() * n);
  const odd = rnd();
  if (odd < 0.04) return [];
  if (odd < 0.07) return [behavior(0, pick(4))];
  if (odd < 0.1) return [option(0, 1, pick(3)), behavior(1, 1), behavior(1, 1)];
  if (odd < 0.13) return [option(0, 7, pick(2)), option(1, pick(3), pick(3)), behavior(2, 9)];
  const play = pick(3);
  if (play === 1) return [option(0, 1, 1), option(1, 0, pick(3)), behavior(2, 1 + pick(3))];
  if (play === 2 && rnd() < 0.5) return [option(0, 1, 2), option(1, 2, pick(2)), behavior(2, 2)];
  return [option(0, 1, play), behavior(1, pick(2))];
}

function robotState(id: number, path: PathNode[]): RobotState {
  return { id, path, shape: "", inputs: [], outputs: [], fault: null, forced: null, overrides: null };
}

/// A live session's ticks: robots keep their path a while, reloads and resets change the
/// generation, time mostly goes on by 25 ms (now and then not at all, a jump, or back a bit).
class Stream {
  seq = 0;
  x = 0;
  gen = 1;
  private readonly paths = new Map<number, PathNode[]>();

  constructor(private readonly rnd: () => number) {}

  next(): Tick {
    const r = this.rnd();
    this.x += r < 0.04 ? 0 : r < 0.06 ? 400 + Math.floor(this.rnd() * 600) : r < 0.07 ? -10 : 25;
    if (this.rnd() < 0.03) this.gen = 1 + Math.floor(this.rnd() * 3);
    const robots: RobotState[] = [];
    for (const id of ROBOTS) {
      if (this.rnd() < 0.05) continue; // not in this frame
      if (!this.paths.has(id) || this.rnd() < 0.25) this.paths.set(id, randomPath(this.rnd));
      robots.push(robotState(id, this.paths.get(id) ?? []));
    }
    if (this.rnd() < 0.3) robots.reverse(); // robots' order in a tick ties team labels
    this.seq += 1 + (this.rnd() < 0.1 ? 1 : 0);
    return { seq: this.seq, gen: this.gen, t: this.x, x: this.x, wall: 0, robots, scene: null, status: null };
  }
}

/// Rows as data (the panel draws these fields).
function plain(rows: readonly TimelineRow[]): unknown {
  return rows.map((r) => ({ kind: r.kind, id: r.id, label: r.label, depth: r.depth, segments: r.segments.map((s) => ({ t0: s.t0, t1: s.t1, key: s.key, label: s.label })) }));
}

function expectFullBuild(builder: TimelineBuilder, ticks: readonly Tick[], context: TimelineContext, where: string): void {
  const rows = buildRobotTimeline(ticks, context.robotId, (gen) => indexOf(context.robotId, gen));
  const team = buildTeamTimeline(ticks, context.agents, indexOf);
  expect(plain(builder.rows), `${where}: robot rows`).toEqual(plain(rows));
  expect(plain(builder.team), `${where}: team rows`).toEqual(plain(team));
}

const AGENTS = [
  { id: 0, name: "blue1" },
  { id: 1, name: "blue2" },
  { id: 2, name: "red1" },
];

/// One random session against a builder: what each kind of update was, for the assertions.
function session(seed: number, steps: number): Map<TimelineUpdate | "trimmed", number> {
  const rnd = random(seed);
  const stream = new Stream(rnd);
  const buffer = new TickBuffer(150 + Math.floor(rnd() * 600));
  const builder = new TimelineBuilder();
  const counts = new Map<TimelineUpdate | "trimmed", number>();
  let context: TimelineContext = { robotId: 0, agents: AGENTS, indexOf };
  for (let step = 0; step < steps; step++) {
    const r = rnd();
    if (r < 0.03) context = { ...context, robotId: ROBOTS[Math.floor(rnd() * ROBOTS.length)] as number }; // select
    else if (r < 0.04) context = { ...context, agents: rnd() < 0.5 ? AGENTS.slice(0, 2) : AGENTS }; // another generation's robots
    else if (r < 0.06) builder.invalidate(); // hello, history
    else if (r < 0.07) buffer.merge(buffer.all.slice(0, 3)); // a history answer: a new array
    else if (r < 0.075) buffer.clear();
    const oldest = buffer.oldest;
    const n = Math.floor(rnd() * 8); // ticks between two updates (0: an update without new ticks)
    for (let i = 0; i < n; i++) buffer.push(stream.next());
    const how = builder.update(buffer.all, context);
    counts.set(how, (counts.get(how) ?? 0) + 1);
    if (how === "appended" && oldest && buffer.oldest !== oldest) counts.set("trimmed", (counts.get("trimmed") ?? 0) + 1);
    expectFullBuild(builder, buffer.all, context, `seed ${seed}, step ${step}`);
  }
  return counts;
}

describe("TimelineBuilder", () => {
  it("equals a full build after every update of random sessions (front drops, generations, selection)", () => {
    const total = new Map<string, number>();
    for (let seed = 1; seed <= 60; seed++) {
      for (const [how, n] of session(seed, 200)) total.set(how, (total.get(how) ?? 0) + n);
    }
    // Most updates are incremental, many of them after front drops, so the test checks them.
    const appended = total.get("appended") ?? 0;
    expect(appended).toBeGreaterThan(0.6 * 60 * 200);
    expect(total.get("trimmed") ?? 0).toBeGreaterThan(0.4 * appended);
    expect(total.get("rebuilt") ?? 0).toBeGreaterThan(0);
    expect(total.get("unchanged") ?? 0).toBeGreaterThan(0);
  });

  it("sets the newest tick's end again when the next tick arrives, and trims the segment over a front cut", () => {
    const buffer = new TickBuffer(60);
    const builder = new TimelineBuilder();
    const context: TimelineContext = { robotId: 0, agents: AGENTS.slice(0, 1), indexOf };
    const tick = (seq: number, x: number, state: number): Tick => ({ seq, gen: 1, t: x, x, wall: 0, robots: [robotState(0, [option(0, 1, state)])], scene: null, status: null });
    buffer.push(tick(1, 0, 0));
    expect(builder.update(buffer.all, context)).toBe("rebuilt");
    expect(builder.rows[0]?.segments).toEqual([{ t0: 0, t1: 25, key: expect.any(Number), label: "wait" }]); // one tick: 25 ms
    buffer.push(tick(2, 40, 0));
    expect(builder.update(buffer.all, context)).toBe("appended");
    expect(builder.rows[0]?.segments.map((s) => [s.t0, s.t1])).toEqual([[0, 80]]); // the next starts at 40, lasts as long
    buffer.push(tick(3, 70, 1)); // drops the first (older than 70 - 60)
    expect(builder.update(buffer.all, context)).toBe("appended");
    expect(builder.rows[0]?.segments.map((s) => [s.label, s.t0, s.t1])).toEqual([
      ["wait", 40, 70],
      ["chase", 70, 100],
    ]);
    expectFullBuild(builder, buffer.all, context, "after the drop");
    buffer.push(tick(4, 200, 1)); // drops every tick the builder read
    expect(builder.update(buffer.all, context)).toBe("rebuilt");
    expect(builder.rows[0]?.segments.map((s) => [s.label, s.t0, s.t1])).toEqual([["chase", 200, 225]]);
  });

  it("orders rows and numbers team labels by first appearance in what is still buffered", () => {
    const buffer = new TickBuffer(100);
    const builder = new TimelineBuilder();
    const context: TimelineContext = { robotId: 0, agents: AGENTS.slice(0, 2), indexOf };
    const tick = (seq: number, x: number, path: PathNode[], other: PathNode[]): Tick => ({ seq, gen: 1, t: x, x, wall: 0, robots: [robotState(1, other), robotState(0, path)], scene: null, status: null });
    // stand (behavior 0) runs first, then walk (1) beside it; the team sees wait, then search.
    buffer.push(tick(1, 0, [option(0, 1, 0), behavior(1, 0)], [option(0, 1, 0)]));
    buffer.push(tick(2, 25, [option(0, 1, 0), behavior(1, 1), behavior(1, 0)], [option(0, 1, 2)]));
    builder.update(buffer.all, context);
    expect(builder.rows.map((r) => r.label)).toEqual(["play", "stand", "walk"]);
    for (let i = 3; i <= 6; i++) buffer.push(tick(i, (i - 1) * 25, [option(0, 1, 0), behavior(1, 1), behavior(1, 0)], [option(0, 1, 2)]));
    expect(builder.update(buffer.all, context)).toBe("appended");
    // Now both first ran in the oldest tick: walk comes first in its path.
    expect(builder.rows.map((r) => r.label)).toEqual(["play", "walk", "stand"]);
    // play/wait (key 0) is gone: play/search now appeared first.
    expect(builder.team[1]?.segments).toEqual([{ t0: 25, t1: 150, key: 0, label: "play/search" }]);
    expectFullBuild(builder, buffer.all, context, "after the drop");
  });

  it("rebuilds when the buffer was replaced, the context changed or after invalidate", () => {
    const stream = new Stream(random(7));
    const buffer = new TickBuffer(1000);
    const builder = new TimelineBuilder();
    const context: TimelineContext = { robotId: 0, agents: AGENTS, indexOf };
    for (let i = 0; i < 20; i++) buffer.push(stream.next());
    expect(builder.update(buffer.all, context)).toBe("rebuilt");
    expect(builder.update(buffer.all, context)).toBe("unchanged");
    buffer.merge([buffer.all[0] as Tick]);
    expect(builder.update(buffer.all, context)).toBe("rebuilt");
    expect(builder.update(buffer.all, { ...context, robotId: 1 })).toBe("rebuilt");
    expect(builder.update(buffer.all, { ...context, robotId: 1, agents: AGENTS.slice(1) })).toBe("rebuilt");
    builder.invalidate();
    expect(builder.update(buffer.all, { ...context, robotId: 1, agents: AGENTS.slice(1) })).toBe("rebuilt");
    buffer.clear();
    expect(builder.update(buffer.all, context)).toBe("rebuilt");
    expect(builder.rows).toEqual([]);
  });
});
