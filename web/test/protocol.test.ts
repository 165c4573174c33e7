import { describe, expect, it } from "vitest";
import { applyValues, decodePath, FrameDecoder, parseServerMessage, pathParents, pathShape } from "../src/protocol";
import { frame, playPath } from "./fake";

describe("decodePath", () => {
  it("decodes option and basic behavior nodes in pre-order", () => {
    const path = decodePath(playPath(1, 2));
    expect(path.map((n) => n.kind)).toEqual(["option", "option", "behavior"]);
    expect(path[0]).toEqual({ kind: "option", depth: 0, option: 1, state: 1, optionTime: 5000, stateTime: 800, decidedIn: 1, leaf: 2, params: [] });
    expect(path[1]).toMatchObject({ option: 0, state: 2, params: [250], depth: 1 });
    expect(path[2]).toEqual({ kind: "behavior", depth: 2, behavior: 1, time: 800, params: [120.5, -3] });
  });

  it("drops malformed nodes instead of throwing", () => {
    const wire = [[0, 0, 1], "x", [1, 0, 2, 10], [7, 1]] as never;
    expect(decodePath(wire)).toEqual([{ kind: "behavior", depth: 0, behavior: 2, time: 10, params: [] }]);
    expect(decodePath(undefined)).toEqual([]);
  });

  it("gives parents from depths and a shape without times", () => {
    const path = decodePath(playPath(1));
    expect(pathParents(path)).toEqual([-1, 0, 1]);
    const later = decodePath(playPath(1).map((n) => (n[0] === 0 ? ([...n.slice(0, 4), 9999, 9999, ...n.slice(6)] as never) : n)));
    expect(pathShape(later)).toBe(pathShape(path));
    expect(pathShape(decodePath(playPath(2)))).not.toBe(pathShape(path));
  });

  it("handles two roots and siblings", () => {
    const path = decodePath([
      [0, 0, 1, 0, 0, 0, 0, -1, []],
      [1, 1, 0, 0, []],
      [1, 1, 2, 0, [5]],
      [1, 0, 3, 0, [1]],
    ]);
    expect(pathParents(path)).toEqual([-1, 0, 0, -1]);
  });
});

describe("applyValues", () => {
  it("replaces on a full frame", () => {
    expect(applyValues([1, 2, 3], { "1": 5 }, true)).toEqual([undefined, 5]);
  });

  it("patches a delta and shares unchanged arrays", () => {
    const before = [1, true, 3];
    const same = applyValues(before, { "0": 1 }, false);
    expect(same).toBe(before);
    const after = applyValues(before, { "2": 4.5, "4": false }, false);
    expect(after).not.toBe(before);
    expect(after).toEqual([1, true, 4.5, undefined, false]);
    expect(before).toEqual([1, true, 3]);
    expect(applyValues(before, undefined, false)).toBe(before);
  });
});

describe("FrameDecoder", () => {
  it("applies deltas against the previous frame of its stream", () => {
    const d = new FrameDecoder();
    const a = d.decode({ ...frame(10, 250, [{ id: 0, path: playPath(0), inputs: { "0": false, "1": 3000 }, outputs: { "0": 0 } }], true), status: { game_state: "playing" }, scene: { t: 250, ball: [0, 0] } });
    const b = d.decode(frame(12, 300, [{ id: 0, path: playPath(1), inputs: { "0": true } }]));
    expect(b.robots[0]?.inputs).toEqual([true, 3000]);
    expect(b.robots[0]?.outputs).toBe(a.robots[0]?.outputs);
    expect(b.status).toEqual({ game_state: "playing" });
    expect(b.scene).toEqual({ t: 250, ball: [0, 0] });
    const c = d.decode(frame(13, 325, [{ id: 0, path: [], inputs: { "1": 10 } }], true));
    expect(c.robots[0]?.inputs).toEqual([undefined, 10]);
    expect(c.status).toBeNull();
  });

  it("treats a new agent in a delta as full and keeps fault, forced and overrides", () => {
    const d = new FrameDecoder();
    d.decode(frame(1, 25, [{ id: 0, path: [] }], true));
    const t = d.decode(frame(2, 50, [{ id: 0, path: [] }, { id: 3, path: [], inputs: { "2": 1 }, fault: { message: "boom", option: "play", state: "wait" }, forced: [0, 2], overrides: { "2": 1 } }]));
    expect(t.robots[1]).toMatchObject({ id: 3, inputs: [undefined, undefined, 1], fault: { message: "boom" }, forced: [0, 2], overrides: { "2": 1 } });
    d.reset();
    expect(d.previous).toBeNull();
  });
});

describe("parseServerMessage", () => {
  it("accepts known types and refuses the rest", () => {
    expect(parseServerMessage('{"type":"reply","id":1,"ok":true}')).toMatchObject({ type: "reply" });
    expect(parseServerMessage('{"type":"bogus"}')).toBeNull();
    expect(parseServerMessage("not json")).toBeNull();
    expect(parseServerMessage("3")).toBeNull();
  });
});
