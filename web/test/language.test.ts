import { describe, expect, it } from "vitest";
import { KEYWORDS, tokenize } from "../src/xabsl/language";

describe("xabsl tokenizer", () => {
  it("highlights keywords, definitions, parameters, units and comments", () => {
    const tokens = tokenize('/** doc */\noption approach { float @stop_at [0..1000] "mm"; initial state go {');
    expect(tokens).toEqual([
      ["docComment", "/** doc */"],
      ["keyword", "option"],
      ["definition", "approach"],
      ["bracket", "{"],
      ["typeName", "float"],
      ["parameter", "@stop_at"],
      ["unit", "[0..1000]"],
      ["string", '"mm"'],
      ["separator", ";"],
      ["keyword", "initial"],
      ["keyword", "state"],
      ["definition", "go"],
      ["bracket", "{"],
    ]);
  });

  it("keeps the keyword-run rule: state_time-500 is an identifier", () => {
    expect(tokenize("state_time-500")[0]).toEqual(["variableName", "state_time"]);
    expect(tokenize("state_time - 500").slice(0, 2)).toEqual([["atom", "state_time"], ["operator", "-"]]);
    expect(tokenize("ball.distance <= 1.5E3").map((t) => t[0])).toEqual(["variableName", "operator", "number", "variableName"]);
  });

  it("continues block comments across lines and marks illegal characters", () => {
    expect(tokenize("/* a\n b */ goto x; $").map((t) => t[0])).toEqual(["blockComment", "blockComment", "controlKeyword", "variableName", "separator", "invalid"]);
    expect(KEYWORDS).toContain("synchronized");
  });
});
