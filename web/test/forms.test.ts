import { describe, expect, it } from "vitest";
import { diagnosticsFor, homeProgram, type SetDiagnostic } from "../src/behaviorsets";
import { checkNumber } from "../src/params";
import { formatClock, formatSpeed, SPEEDS } from "../src/ui";

describe("checkNumber", () => {
  it("accepts a number inside the declared range, bounds included", () => {
    expect(checkNumber("57", "-57..57")).toEqual({ ok: true, value: 57 });
    expect(checkNumber(" -57 ", "-57..57")).toEqual({ ok: true, value: -57 });
    expect(checkNumber("1e3", null)).toEqual({ ok: true, value: 1000 });
  });
  it("says why a value is refused", () => {
    expect(checkNumber("200", "-57..57")).toEqual({ ok: false, error: "200 is outside the declared range -57..57" });
    expect(checkNumber("", "-57..57")).toEqual({ ok: false, error: "a number is required" });
    expect(checkNumber("   ", null)).toEqual({ ok: false, error: "a number is required" });
    expect(checkNumber("abc", null)).toEqual({ ok: false, error: "abc is not a number" });
    expect(checkNumber("Infinity", null)).toEqual({ ok: false, error: "Infinity is not a number" });
  });
  it("checks one-sided ranges", () => {
    expect(checkNumber("-1", "0..")).toEqual({ ok: false, error: "-1 is outside the declared range 0.." });
    expect(checkNumber("1e9", "0..")).toEqual({ ok: true, value: 1e9 });
    expect(checkNumber("5", "..4").ok).toBe(false);
  });
});

describe("formatClock", () => {
  it("shows one 25 ms tick", () => {
    expect(formatClock(12_300)).toBe("12.300 s");
    expect(formatClock(12_325)).toBe("12.325 s");
    expect(formatClock(0)).toBe("0.000 s");
  });
  it("switches to minutes from ten minutes on", () => {
    expect(formatClock(600_000)).toBe("10:00.000");
    expect(formatClock(187_050 + 600_000)).toBe("13:07.050");
  });
});

describe("speeds", () => {
  it("span the server's 0.1..20", () => {
    expect(Math.min(...SPEEDS)).toBe(0.1);
    expect(Math.max(...SPEEDS)).toBe(20);
    expect(SPEEDS).toContain(1);
    expect(formatSpeed(0.25)).toBe("0.25×");
    expect(formatSpeed(20)).toBe("20×");
  });
});

const diagnostic = (program: string, severity: SetDiagnostic["severity"], message: string, line = 7): SetDiagnostic => ({
  severity,
  code: "x",
  original_code: "",
  lint: false,
  message,
  file: "behavior/basic_behaviors.xabsl",
  span: { file: "behavior/basic_behaviors.xabsl", line, col: 3, end_line: line, end_col: 9, start: 0, end: 0 },
  related: [],
  program,
});

describe("behavior sets of a file", () => {
  it("the home set is the one whose folder holds the file", () => {
    expect(homeProgram("behavior/symbols/ball_symbols.xabsl", ["behavior", "chase"])).toBe("behavior");
    expect(homeProgram("chase/agents.xabsl", ["behavior", "chase"])).toBe("chase");
    expect(homeProgram("behaviorx/a.xabsl", ["behavior"])).toBeNull();
    expect(homeProgram("a/b/c.xabsl", ["a", "a/b"])).toBe("a/b");
  });
  it("shows the home set's warnings and every set's errors, each once", () => {
    const all = [
      diagnostic("chase", "warning", "basic behavior 'walk' is never called"),
      diagnostic("behavior", "warning", "own warning", 9),
      diagnostic("chase", "error", "broken for chase", 10),
      diagnostic("behavior", "error", "broken", 11),
      diagnostic("chase", "error", "broken", 11),
    ];
    const shown = diagnosticsFor("behavior/basic_behaviors.xabsl", all, ["behavior", "chase"]).map((d) => d.message);
    expect(shown).toEqual(["own warning", "broken for chase", "broken"]);
  });
  it("drops nothing within one set: its count is what xabsl compile prints", () => {
    const twice = [diagnostic("behavior", "warning", "same", 9), diagnostic("behavior", "warning", "same", 9)];
    expect(diagnosticsFor("behavior/basic_behaviors.xabsl", twice, ["behavior", "chase"])).toHaveLength(2);
  });
  it("keeps everything for a file of no set", () => {
    const all = [diagnostic("chase", "warning", "w1"), diagnostic("behavior", "warning", "w2", 8)];
    expect(diagnosticsFor("lib/shared.xabsl", all, ["behavior", "chase"])).toHaveLength(2);
  });
});
