import { describe, expect, it } from "vitest";
import { GroupMap } from "../src/graphgroups";

const groups = [
  { key: "Soccer", options: [0, 1], behaviors: [] },
  { key: "Soccer/Striker", options: [2, 3], behaviors: [] },
  { key: "(basic behaviors)", options: [], behaviors: [0, 1] },
];

describe("GroupMap", () => {
  it("draws options of a collapsed group as the group's node", () => {
    const map = new GroupMap(groups, new Set(["Soccer/Striker"]));
    expect(map.nodeId("option", 0)).toBe("option_0");
    expect(map.nodeId("option", 3)).toBe("group_1");
    expect(map.nodeId("behavior", 1)).toBe("behavior_1");
    expect(map.groupOf("option", 2)).toBe(1);
    expect(map.groupOf("option", 9)).toBeUndefined();
  });

  it("names calls as the server does", () => {
    const map = new GroupMap(groups, new Set(["Soccer/Striker", "(basic behaviors)"]));
    expect(map.callId(0, "option", 1)).toBe("call_0_o1");
    expect(map.callId(0, "option", 2)).toBe("gcall_o0_g1");
    expect(map.callId(2, "option", 3)).toBeNull();
    expect(map.callId(3, "behavior", 0)).toBe("gcall_g1_g2");
    expect(map.callId(1, "behavior", 0)).toBe("gcall_o1_g2");
  });

  it("makes the collapse query", () => {
    expect(new GroupMap(groups, new Set(["Soccer", "(basic behaviors)"])).query()).toBe("Soccer|(basic behaviors)");
    expect(new GroupMap(groups, new Set()).query()).toBe("");
  });
});
