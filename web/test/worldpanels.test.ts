import { describe, expect, it } from "vitest";
import { explainCause } from "../src/panels/facts";
import { commandsOf, ddOf, panelsOf } from "../src/panels/world";

describe("world panels", () => {
  it("shows only the panels and commands a world announces", () => {
    expect(panelsOf(null)).toEqual([]);
    expect(panelsOf({ kind: "soccer" })).toEqual([]);
    expect(panelsOf({ kind: "x", panels: ["plan", 3, "facts"] })).toEqual(["plan", "facts"]);
    expect(commandsOf({ kind: "x", commands: "nope" })).toEqual([]);
    expect(ddOf({ kind: "x", dd: { behaviors: ["roam"], actuators: [], theta: [0.5], terms: [] } })?.behaviors).toEqual(["roam"]);
    expect(ddOf({ kind: "x", dd: {} })).toBeNull();
  });

  it("says why a fact changed from its cause", () => {
    const why = explainCause({
      i: 3,
      t: 32300,
      fact: "at mug c",
      value: false,
      cause: { rule: "at mug c", phase: "cleared", signals: { "alpha.gather_mug": 0.7912, "γ_mug": 0 }, facts: ["fact(at-robot c)"], held: 12 },
    });
    expect(why).toBe("−at mug c: cleared · by rule at mug c · while alpha.gather_mug=0.79, γ_mug=0.00 · given fact(at-robot c) · held 12.00 s");
    const implied = explainCause({ i: 4, t: 1, fact: "at book b", value: false, cause: { rule: "has-robot book", phase: "implied", by: "has-robot book" } });
    expect(implied).toBe("−at book b: cleared as implied · by rule has-robot book · because has-robot book became true");
    expect(explainCause({ i: 5, t: 1, fact: "at mug a", value: true, cause: { rule: "by hand", phase: "forced" } })).toBe("+at mug a: set by hand");
  });
});
