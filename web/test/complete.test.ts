// Completion tests in the manner of lang-sql's test-complete.ts: `|` marks the cursor in an
// EditorState, the result is a sorted, comma-joined list of labels. No DOM.
import { CompletionContext, type CompletionResult, type CompletionSource } from "@codemirror/autocomplete";
import { EditorState } from "@codemirror/state";
import { describe, expect, it } from "vitest";
import { currentOptionName, inCommentOrString, openCall, xabslCompletion } from "../src/xabsl/complete";
import { xabsl } from "../src/xabsl/language";
import { description } from "./fake";

function complete(doc: string, explicit = false, desc = description): CompletionResult | null {
  const cursor = doc.indexOf("|");
  const text = doc.slice(0, cursor) + doc.slice(cursor + 1);
  const state = EditorState.create({ doc: text, selection: { anchor: cursor }, extensions: [xabsl(), xabslCompletion(desc)] });
  const sources = state.languageDataAt<CompletionSource>("autocomplete", cursor);
  expect(sources).toHaveLength(1);
  return (sources[0] as CompletionSource)(new CompletionContext(state, cursor, explicit)) as CompletionResult | null;
}

function labels(doc: string, explicit = false): string {
  const result = complete(doc, explicit);
  return result ? result.options.map((o) => o.label).sort().join(", ") : "null";
}

const OPTION = (body: string): string => `option approach_ball {\n  float @stop_at [0..1000] "mm";\n  initial state go {\n    decision {\n${body}\n    }\n    action { }\n  }\n  state kick { action { } }\n  state extra_typed { action { } }\n}\n`;

describe("xabsl completion", () => {
  it("offers the option's states after goto, from the IR and from the text", () => {
    expect(labels(OPTION("      if (true) goto k|;"))).toBe("extra_typed, go, kick, kicked");
  });

  it("offers the option's parameters for @", () => {
    expect(labels(OPTION("      if (ball.distance < @|) goto kick;"))).toBe("@stop_at");
  });

  it("offers a callee's parameters as `name = ` inside a call", () => {
    const result = complete("option x { initial state a { action { walk(|) } } }", true);
    expect(result?.options.map((o) => o.label).sort()).toEqual(["direction", "speed"]);
    expect(result?.options.find((o) => o.label === "speed")?.apply).toBe("speed = ");
    expect(labels("option x { initial state a { action { walk(speed = 1, d|) } } }")).toBe("direction");
    expect(labels("option x { initial state a { action { approach_ball option(s|) } } }")).toBe("stop_at");
    expect(labels("x = clamp(v|")).toBe("hi, lo, value");
  });

  it("offers enum elements first where an enum is expected", () => {
    const cmp = complete("option x { initial state a { decision { if (game.state == p|) goto a; else stay; } action {} } }");
    const top = cmp?.options.filter((o) => (o.boost ?? 0) >= 5).map((o) => o.label).sort();
    expect(top).toEqual(["finished", "init", "playing", "ready", "set"]);
    const assign = complete("option x { initial state a { action { activity = w| } } }");
    expect(assign?.options.filter((o) => o.type === "enum").map((o) => o.label).sort()).toEqual(["approaching", "kicking", "searching", "waiting"]);
  });

  it("offers symbols, constants, options, basic behaviors and keywords elsewhere", () => {
    const all = labels("option x { initial state a { decision { if (b|", true);
    for (const name of ["ball.distance", "ball.seen", "kick_distance", "approach_ball", "walk", "state_time", "activity", "kicks"]) {
      expect(all.split(", ")).toContain(name);
    }
    const ball = complete("if (ball.d|");
    expect(ball?.from).toBe(4);
    const d = ball?.options.find((o) => o.label === "ball.distance");
    expect(d?.detail).toBe("input float");
    expect(String(d?.info)).toContain("0..10000 mm");
  });

  it("is quiet in comments and strings, and without a word unless asked", () => {
    expect(labels("// ball.d|")).toBe("null");
    expect(labels("/** ball| */")).toBe("null");
    expect(labels('include "ba|')).toBe("null");
    expect(labels("x = |")).toBe("null");
    expect(labels("x = |", true)).not.toBe("null");
  });

  it("offers keywords only before the first hello", () => {
    const result = complete("st|", false, null as never);
    expect(result?.options.map((o) => o.label)).toContain("state");
    expect(result?.options.map((o) => o.label)).not.toContain("ball.seen");
  });
});

describe("completion helpers", () => {
  it("finds the option, open calls and comments", () => {
    expect(currentOptionName("/** doc */\noption my.opt {")).toBe("my.opt");
    expect(currentOptionName("namespace x(\"y\") {}")).toBeNull();
    expect(openCall("walk(speed = f(a = 1), ")).toEqual({ callee: "walk", argText: "speed = f(a = 1), " });
    expect(openCall("walk(speed = 1); x")).toBeNull();
    expect(inCommentOrString("a /* b */ c", 10)).toBe(false);
    expect(inCommentOrString("a /* b ", 7)).toBe(true);
  });
});
