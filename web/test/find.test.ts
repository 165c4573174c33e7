import { describe, expect, it } from "vitest";
import type { Option } from "../src/description";
import { find, matchRank } from "../src/find";

function option(id: number, name: string, states: string[]): Option {
  return { id, name, states: states.map((s, i) => ({ id: i, name: s })) } as unknown as Option;
}

const options = [
  option(0, "play_soccer", ["situation_0", "ready", "kick_off"]),
  option(1, "striker_approach_ball", ["approach", "align_to_goal"]),
  option(2, "goalie_dive", ["wait", "dive_left"]),
  option(3, "kick", ["kick"]),
  option(4, "penalty_kick_taker", ["approachKick"]),
];

describe("matchRank", () => {
  it("ranks exact, prefix, word start, anywhere", () => {
    expect(matchRank("kick", "kick")).toBe(0);
    expect(matchRank("kick_off", "kick")).toBe(1);
    expect(matchRank("penalty_kick_taker", "kick")).toBe(2);
    expect(matchRank("approachKick", "kick")).toBe(2);
    expect(matchRank("sidekick", "kick")).toBe(3);
    expect(matchRank("walk", "kick")).toBeNull();
    expect(matchRank("walk", "")).toBeNull();
  });
});

describe("find", () => {
  it("finds options and states across options, best first", () => {
    const found = find(options, "Kick");
    expect(found.map((f) => [f.kind, f.name, f.optionName])).toEqual([
      ["option", "kick", "kick"],
      ["state", "kick", "kick"],
      ["state", "kick_off", "play_soccer"],
      ["option", "penalty_kick_taker", "penalty_kick_taker"],
      ["state", "approachKick", "penalty_kick_taker"],
    ]);
    expect(found[2]).toMatchObject({ option: 0, state: 2 });
  });

  it("caps the list and ignores blank queries", () => {
    expect(find(options, "a", 3)).toHaveLength(3);
    expect(find(options, "   ")).toEqual([]);
  });
});
