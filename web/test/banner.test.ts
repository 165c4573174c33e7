import { describe, expect, it } from "vitest";
import type { ProgramStatus } from "../src/api";
import { problemHeadline } from "../src/panels/banner";
import { callsText } from "../src/panels/symbols";

const error = { severity: "error" as const, code: "syntax-error", original_code: "", lint: false, message: "unexpected 'else'", file: "a.xabsl", span: null, related: [] };
const warning = { ...error, severity: "warning" as const };
const status = (over: Partial<ProgramStatus>): ProgramStatus => ({ folder: "team", agents_file: "agents.xabsl", ok: false, running: false, partial: false, error: null, diagnostics: [], files: [], ...over });

describe("problemHeadline", () => {
  it("counts errors, not warnings, and says the robots stand when nothing runs", () => {
    expect(problemHeadline("team", status({ diagnostics: [error, warning, error] }))).toBe("Behavior team has 2 errors: its robots stand until it compiles. The graph shows what parsed.");
  });
  it("says the last good version keeps running after a broken hot reload", () => {
    expect(problemHeadline("team", status({ running: true, diagnostics: [error] }))).toBe("Behavior team has 1 error: the last good version keeps running until it compiles again.");
  });
  it("names a behavior that compiles but does not run on this host", () => {
    expect(problemHeadline("team", status({ ok: false, running: true, error: "in.jsonl:2: unknown input symbol 'x'" }))).toBe("Behavior team does not run here: in.jsonl:2: unknown input symbol 'x'");
  });
  it("is silent for a clean behavior with warnings", () => {
    expect(problemHeadline("team", status({ ok: true, running: true, diagnostics: [warning] }))).toBeNull();
  });
});

describe("callsText", () => {
  it("lists every call of the tick with its arguments and value", () => {
    const calls = { "geo.clamp": [[[600.123456, 50, true], 0] as [Array<number | boolean>, number], [[1, 2, false], 2] as [Array<number | boolean>, number]] };
    expect(callsText("geo.clamp", calls, (v) => String(v))).toBe("clamp(600.123, 50, true) = 0; clamp(1, 2, false) = 2");
  });
  it("says when the function was not called", () => {
    expect(callsText("clamp", {}, String)).toBe("not called");
  });
});
