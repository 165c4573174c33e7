import { describe, expect, it } from "vitest";
import { LintFilter } from "../src/panels/lintfilter";

class MemoryStorage {
  data = new Map<string, string>();
  getItem(k: string): string | null {
    return this.data.get(k) ?? null;
  }
  setItem(k: string, v: string): void {
    this.data.set(k, v);
  }
  removeItem(k: string): void {
    this.data.delete(k);
  }
}

describe("LintFilter", () => {
  it("hides per code and per behavior set, remembered across pages", () => {
    const storage = new MemoryStorage();
    const a = LintFilter.setKey("soccer", "behavior");
    const b = LintFilter.setKey("soccer", "chase");
    const filter = new LintFilter(storage as unknown as Storage);
    filter.setCode(a, "unused-symbol", true);
    expect(filter.hides(a, { severity: "warning", code: "unused-symbol" })).toBe(true);
    expect(filter.hides(b, { severity: "warning", code: "unused-symbol" })).toBe(false);
    const again = new LintFilter(storage as unknown as Storage);
    expect(again.hides(a, { severity: 2, code: "unused-symbol" })).toBe(true);
  });

  it("as the original compiler: every lint code, never an error nor the original's warnings", () => {
    const filter = new LintFilter(new MemoryStorage() as unknown as Storage);
    const set = LintFilter.setKey("x", "y");
    filter.setAllLint(set, true);
    expect(filter.hides(set, { severity: "warning", code: "naming" })).toBe(true);
    expect(filter.hides(set, { severity: "warning", code: "parameter-missing" })).toBe(true);
    expect(filter.hides(set, { severity: "warning", code: "empty-namespace" })).toBe(false);
    expect(filter.hides(set, { severity: "error", code: "unused-symbol" })).toBe(false);
    filter.setAllLint(set, false);
    expect(filter.hides(set, { severity: "warning", code: "naming" })).toBe(false);
  });
});
