import { describe, expect, it } from "vitest";
import { lineDiff } from "../src/linediff";

const show = (before: string, after: string, context = 1): string[] => lineDiff(before, after, context).map((l) => `${l.kind}${l.text}`);

describe("lineDiff", () => {
  it("shows a changed line with its context, removals first", () => {
    expect(show("a\nb\nc\nd\ne", "a\nb\nC\nd\ne")).toEqual([" b", "-c", "+C", " d"]);
  });
  it("marks the lines left out between two changes", () => {
    expect(show("1\n2\n3\n4\n5\n6\n7", "0\n2\n3\n4\n5\n6\n8")).toEqual(["-1", "+0", " 2", " …", " 6", "-7", "+8"]);
  });
  it("is empty for equal texts and reads every line end", () => {
    expect(lineDiff("a\r\nb", "a\nb")).toEqual([]);
    expect(show("a", "a\nb")).toEqual([" a", "+b"]);
  });
});
