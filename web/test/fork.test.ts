import { describe, expect, it } from "vitest";
import { pathLine } from "../src/panels/fork";

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
