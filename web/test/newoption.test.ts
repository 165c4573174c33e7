import { describe, expect, it } from "vitest";
import { addInclude, insertionDiff, optionSource, problems, relativePath } from "../src/newoption";

describe("new option", () => {
  it("writes parameters with types, ranges and units", () => {
    const text = optionSource({
      name: "turn_to",
      doc: "Turns to a heading.",
      params: [
        { name: "angle", type: "float", min: -180, max: 180, unit: "deg", doc: "where to" },
        { name: "fast", type: "bool" },
        { name: "mode", type: "game.state" },
      ],
    });
    expect(text).toContain("/** Turns to a heading. */\noption turn_to {");
    expect(text).toContain('  /** where to */\n  float @angle [-180..180] "deg";');
    expect(text).toContain("  bool @fast;");
    expect(text).toContain("  enum game.state @mode;");
    expect(text).toContain("initial state start");
  });

  it("says what is wrong", () => {
    expect(problems({ name: "2x", doc: "", params: [] }, [], [])[0]).toMatch(/^name:/);
    expect(problems({ name: "kick", doc: "", params: [] }, ["kick"], [])).toEqual(["name: an option 'kick' exists already"]);
    const wrong = problems({ name: "ok", doc: "", params: [{ name: "a", type: "float", min: 5, max: 1 }, { name: "a", type: "bool", unit: "mm" }, { name: "b", type: "colour" }] }, [], ["game.state"]);
    expect(wrong).toEqual([
      "parameter 1: the range 5..1 is empty",
      "parameter 2: 'a' is there twice",
      "parameter 2: only decimal (float) parameters have a range or unit",
      "parameter 3: unknown type 'colour'",
    ]);
    expect(problems({ name: "ok", doc: "", params: [{ name: "a", type: "float", min: 1, max: null }] }, [], [])).toEqual(["parameter 1: a range needs both ends"]);
  });

  it("adds the include after the options of the same folder and shows the diff", () => {
    const agents = 'include "symbols.xabsl";\ninclude "options/a.xabsl";\ninclude "options/b.xabsl";\n\nagent x("X", a);\n';
    const { text, line, include } = addInclude(agents, "behavior/agents.xabsl", "behavior/options/c.xabsl");
    expect(include).toBe('include "options/c.xabsl";');
    expect(line).toBe(4);
    expect(text.split("\n")[3]).toBe(include);
    const diff = insertionDiff(agents, text);
    expect(diff.filter((d) => d.kind === "+")).toEqual([{ kind: "+", line: 4, text: include }]);
    expect(diff.filter((d) => d.kind === "-")).toEqual([]);
    expect(relativePath("behavior/agents.xabsl", "shared/x.xabsl")).toBe("../shared/x.xabsl");
  });
});
