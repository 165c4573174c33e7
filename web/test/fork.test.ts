import { describe, expect, it } from "vitest";
import { divergenceLine, pathLine } from "../src/panels/fork";

describe("pathLine", () => {
  it("writes the original's path as option/state steps down to the basic behavior", () => {
    const line = pathLine([
      { depth: 0, option: "play_soccer", state: "playing" },
      { depth: 1, option: "striker", state: "kick" },
      { depth: 2, behavior: "kick" },
    ]);
    expect(line).toBe("play_soccer/playing › striker/kick › kick");
  });

  it("marks a state it cannot name and is empty for an empty path", () => {
    expect(pathLine([{ depth: 0, option: "root", state: null }])).toBe("root/?");
    expect(pathLine([])).toBe("");
  });
});

describe("divergenceLine", () => {
  const base = {
    robot: 1,
    name: "red2",
    seq: 906,
    t: 15100,
    original_seq: 700,
    fork_path: [],
    original_path: [],
    option: "chase_ball",
    why_fork: { decided_in: "chase", target: "search", stay: false, leaf: 2 },
    why_original: { decided_in: "chase", target: "chase", stay: true, leaf: 2 },
    uncompared_before: 0,
  };

  it("names the tick and what the parting option did on each side", () => {
    expect(divergenceLine(base)).toBe("red2: tick 906 (15.100 s), chase_ball: fork chase → search · original chase stays ");
  });

  it("says the paths may have parted in the ticks before it that were not sampled", () => {
    const line = divergenceLine({ ...base, uncompared_before: 2, why_fork: { decided_in: "search", target: "search", stay: true, leaf: 0 } });
    expect(line).toBe("red2: tick 906 (15.100 s), chase_ball: fork search stays · original chase stays (or in one of the 2 ticks before it, not sampled) ");
  });
});
