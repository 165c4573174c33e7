import { describe, expect, it } from "vitest";
import type { Option } from "../src/description";
import type { Tick } from "../src/protocol";
import { lastTransitionBefore, transitionsOf } from "../src/transitions";

const leaf = (n: number, to: string | null, stay = false) => ({ to, stay, leaf: n, span: null });
const option = {
  id: 3,
  name: "o",
  file: "o.xabsl",
  doc: null,
  span: null,
  params: [],
  initial_state: "a",
  states: [
    { id: 0, name: "a", initial: true, target: false, coop: "", coop_count: 0, doc: null, span: null, actions: [], decision: { if: "x < 1", doc: null, span: null, then: leaf(0, "b"), else: { if: "y", doc: null, span: null, then: leaf(1, "a"), else: leaf(2, "b") } } },
    { id: 1, name: "b", initial: false, target: false, coop: "", coop_count: 0, doc: null, span: null, actions: [], decision: leaf(0, "a") },
    { id: 2, name: "c", initial: false, target: false, coop: "", coop_count: 0, doc: null, span: null, actions: [], decision: leaf(0, null, true) },
  ],
} as unknown as Option;

describe("transitionsOf", () => {
  it("lists every state-changing leaf with its whole condition", () => {
    expect(transitionsOf(option)).toEqual([
      { from: 0, to: 1, leaf: 0, condition: "x < 1" },
      { from: 0, to: 1, leaf: 2, condition: "!(x < 1) && !(y)" },
      { from: 1, to: 0, leaf: 0, condition: "always" },
    ]);
  });
});

const tick = (t: number, state: number, decidedIn: number, leafId: number): Tick =>
  ({ t, robots: [{ id: 7, path: [{ kind: "option", depth: 0, option: 3, state, decidedIn, leaf: leafId, optionTime: 0, stateTime: 0, params: [] }] }] }) as unknown as Tick;

describe("lastTransitionBefore", () => {
  const ticks = [tick(0, 0, 0, 1), tick(25, 1, 0, 0), tick(50, 1, 1, 1), tick(75, 0, 1, 0), tick(100, 0, 0, 1)];
  it("finds the last change at or before a tick", () => {
    expect(lastTransitionBefore(ticks, 2, 7, 3)).toEqual({ from: 0, to: 1, leaf: 0, t: 25 });
    expect(lastTransitionBefore(ticks, 4, 7, 3)).toEqual({ from: 1, to: 0, leaf: 0, t: 75 });
  });
  it("is null before any change, for another agent or option", () => {
    expect(lastTransitionBefore(ticks, 0, 7, 3)).toBeNull();
    expect(lastTransitionBefore(ticks, 4, 8, 3)).toBeNull();
    expect(lastTransitionBefore(ticks, 4, 7, 4)).toBeNull();
  });
});
