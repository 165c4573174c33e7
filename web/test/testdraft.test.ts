import { describe, expect, it } from "vitest";
import { type BehaviorDescription, indexDescription } from "../src/description";
import { testDraftBody } from "../src/panels/testdraft";
import type { RobotState } from "../src/protocol";
import demo from "./fixtures/demo.json";

const description = demo as unknown as BehaviorDescription;
const index = indexDescription(description);

function robot(over: Partial<RobotState>): RobotState {
  return { id: 0, path: [], shape: "", inputs: [], outputs: [], fault: null, forced: null, overrides: null, ...over };
}

describe("Save as test: the draft's body", () => {
  it("names the forced option, its parameters, the active states and basic behaviors", () => {
    const state = robot({
      forced: [0, 0],
      path: [
        { kind: "option", depth: 0, option: 0, state: 0, optionTime: 0, stateTime: 0, decidedIn: 0, leaf: -1, params: [180] },
        { kind: "behavior", depth: 1, behavior: 1, time: 0, params: [200, 10] },
      ],
      overrides: { "1": 300, "4": 3 },
    });
    const body = testDraftBody("robot1", state, index, 4);
    expect(body.force).toEqual({ kind: "option", name: "approach_ball", params: { stop_at: 180 } });
    expect(body.active).toEqual([["approach_ball", "go"]]);
    expect(body.behaviors).toEqual(["walk"]);
    expect(body.overrides).toEqual({ "ball.distance": 300, "game.state": "game.state.playing" });
    expect(body.duration).toBe(4);
    expect(body.name).toBe("robot1 approach_ball");
  });

  it("without forcing: the agent's path, no force", () => {
    const state = robot({ path: [{ kind: "option", depth: 0, option: 1, state: 1, optionTime: 0, stateTime: 0, decidedIn: 1, leaf: 0, params: [] }] });
    const body = testDraftBody("robot2", state, index);
    expect(body.force).toBeNull();
    expect(body.active).toEqual([["play", "chase"]]);
    expect(body.overrides).toEqual({});
  });
});
