import { describe, expect, it } from "vitest";
import { type LabelBox, placeLabels } from "../src/labels";

const overlap = (a: LabelBox, b: LabelBox): boolean => a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;

describe("placeLabels", () => {
  it("puts a lone label under its robot", () => {
    const [box] = placeLabels([{ cx: 100, cy: 100, radius: 10, w: 40, h: 10, text: "striker" }]);
    expect(box).toEqual({ x: 80, y: 112, w: 40, h: 10, text: "striker" });
  });
  it("moves a label that would cover another one", () => {
    const boxes = placeLabels([
      { cx: 100, cy: 100, radius: 10, w: 40, h: 10, text: "a" },
      { cx: 110, cy: 100, radius: 10, w: 40, h: 10, text: "b" },
    ]);
    expect(boxes[0]).not.toBeNull();
    expect(boxes[1]).not.toBeNull();
    expect(overlap(boxes[0] as LabelBox, boxes[1] as LabelBox)).toBe(false);
  });
  it("never overlaps in a crowd, leaving out what does not fit", () => {
    const requests = Array.from({ length: 10 }, (_, i) => ({ cx: 200 + (i % 3) * 6, cy: 200 + Math.floor(i / 3) * 6, radius: 8, w: 50, h: 10, text: `r${i}` }));
    const boxes = placeLabels(requests).filter((b): b is LabelBox => b !== null);
    expect(boxes.length).toBeGreaterThan(0);
    for (let i = 0; i < boxes.length; i++) for (let j = i + 1; j < boxes.length; j++) expect(overlap(boxes[i] as LabelBox, boxes[j] as LabelBox)).toBe(false);
  });
  it("keeps labels off the robots", () => {
    const boxes = placeLabels([
      { cx: 100, cy: 100, radius: 10, w: 40, h: 10, text: "a" },
      { cx: 100, cy: 125, radius: 10, w: 40, h: 10, text: "b" },
    ]);
    // below robot a is robot b: a's label goes above
    expect((boxes[0] as LabelBox).y).toBeLessThan(100);
  });
});
