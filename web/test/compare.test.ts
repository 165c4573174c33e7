import { describe, expect, it } from "vitest";
import { type Change, type Comparison, changedOptions, changePlace, changeSummary, compareQuery, place } from "../src/panels/compare";

const condition: Change = {
  kind: "condition",
  change: "changed",
  name: "battery < 20",
  option: "patrol",
  state: "to_post_a",
  path: ["battery < 20"],
  details: [{ field: "condition", old: "battery < 10", new: "battery < 20" }],
  old: { file: "options/patrol.xabsl", line: 13, col: 12 },
  new: { file: "options/patrol.xabsl", line: 13, col: 12 },
};

describe("compare view", () => {
  it("says where and what each change is, as the command line does", () => {
    expect(changePlace(condition)).toBe("patrol/to_post_a");
    expect(changeSummary(condition)).toBe("condition: battery < 10 → battery < 20");
    expect(place(condition.old)).toBe("options/patrol.xabsl:13");
    expect(place(null)).toBe("");
    const added: Change = { ...condition, kind: "transition", change: "added", path: ["ball.distance > 5000"], details: [{ field: "target", old: null, new: "to_post_b" }], old: null };
    expect(changeSummary(added)).toBe("[ball.distance > 5000] → to_post_b");
    const input: Change = { kind: "input", change: "added", name: "ball.angle", option: null, state: null, path: null, details: [], old: null, new: null };
    expect(changePlace(input)).toBe("ball.angle");
    expect(changeSummary(input)).toBe("ball.angle");
  });

  it("asks for the recordings only as a pair", () => {
    expect(compareQuery("patrol", "git:HEAD", "")).toBe("compare?program=patrol&old=git%3AHEAD&new=running");
    expect(compareQuery("patrol", "git:HEAD", "running", "a.mcap", "")).toBe("compare?program=patrol&old=git%3AHEAD&new=running");
    expect(compareQuery("patrol", "git:HEAD", "running", "a.mcap", "b.mcap")).toBe("compare?program=patrol&old=git%3AHEAD&new=running&recording=a.mcap&against=b.mcap");
  });

  it("shows the state machines drawn, in the order of the changes", () => {
    const comparison: Comparison = {
      program: "patrol",
      diff: { format: "xabsl-diff/1", old: {}, new: {}, counts: {}, changes: [condition, { ...condition, option: "rest" }, { ...condition, option: "gone" }] },
      svg: { option_graph: "<svg/>", state_machines: { rest: "<svg/>", patrol: "<svg/>" } },
      note: null,
    };
    expect(changedOptions(comparison)).toEqual(["patrol", "rest"]);
  });
});
