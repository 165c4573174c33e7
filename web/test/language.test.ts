import { describe, expect, it } from "vitest";
import { findReferences, definitionOf, wordAt } from "../src/xabsl/navigate";
import { KEYWORDS, tokenize } from "../src/xabsl/language";
import { indexDescription } from "../src/description";
import { description } from "./fake";

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

describe("navigation", () => {
  const index = indexDescription(description);
  const text = 'option approach_ball {\n  float @stop_at;\n  initial state go {\n    decision { if (ball.distance < @stop_at) goto kick; else stay; }\n    action { walk(speed = 1); }\n  }\n  state kick { action {} }\n}\n';

  it("finds the word at a position, with dots and @, without a trailing dot", () => {
    const p = text.indexOf("distance");
    expect(wordAt(text, p)?.word).toBe("ball.distance");
    expect(wordAt(text, text.indexOf("stop_at)"))?.word).toBe("@stop_at");
    expect(wordAt("see ball.seen.", 10)?.word).toBe("ball.seen");
    expect(wordAt("  ", 1)).toBeNull();
  });

  it("resolves local states and parameters in the text, the rest from the IR", () => {
    const state = definitionOf("kick", text, index);
    expect(state).toMatchObject({ kind: "local", what: "state kick" });
    if (state?.kind === "local") expect(text.slice(state.from, state.to)).toBe("kick");
    const param = definitionOf("@stop_at", text, index);
    expect(param?.kind === "local" && text.slice(param.from, param.to)).toBe("@stop_at");
    expect(definitionOf("ball.distance", text, index)).toMatchObject({ kind: "span", span: { file: "examples/demo/symbols.xabsl", line: 6 } });
    expect(definitionOf("walk", text, index)).toMatchObject({ kind: "span", what: "basic behavior walk" });
    expect(definitionOf("game.state.playing", "", index)).toMatchObject({ what: "element game.state.playing of game.state" });
    expect(definitionOf("nothing", text, index)).toBeNull();
  });

  it("finds whole-word references outside line comments", () => {
    const files = new Map([
      ["a.xabsl", "x = ball.distance;\n// ball.distance in a comment\ny = ball.distance2 + ball.distance;"],
      ["b.xabsl", "ball.distance"],
    ]);
    const refs = findReferences("ball.distance", files);
    expect(refs.map((r) => `${r.path}:${r.line}:${r.col}`)).toEqual(["a.xabsl:1:5", "a.xabsl:3:22", "b.xabsl:1:1"]);
  });
});
