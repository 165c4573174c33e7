import { describe, expect, it } from "vitest";
import { place } from "../src/panels/svgview";

describe("place", () => {
  it("centres what fits and clamps what does not", () => {
    expect(place(100, 300, 50)).toBe(100);
    expect(place(1000, 300, 500)).toBe(-350);
    expect(place(1000, 300, 10)).toBe(0);
    expect(place(1000, 300, 990)).toBe(-700);
  });
});
