import { describe, expect, it } from "vitest";
import { shapesOf } from "../src/panels/field";

describe("shapesOf", () => {
  it("keeps the generic shapes of a scene and drops anything else", () => {
    const shapes = shapesOf([
      { shape: "circle", x: 1500, y: 1500, r: 600, stroke: "#ffd54a", dash: true },
      { shape: "rect", x: 4000, y: 4000, w: 1200, h: 1000, fill: "#6b5a4a" },
      { shape: "segment", x1: 0, y1: 0, x2: 10, y2: 10 },
      { shape: "polygon", points: [] },
      null,
      3,
    ]);
    expect(shapes.map((s) => s.shape)).toEqual(["circle", "rect", "segment"]);
  });

  it("reads a missing or malformed shapes value as none", () => {
    expect(shapesOf(undefined)).toEqual([]);
    expect(shapesOf({ shape: "circle" })).toEqual([]);
  });
});
