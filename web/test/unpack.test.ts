import { describe, expect, it } from "vitest";
import { type BehaviorDescription, unpackDescription } from "../src/description";

describe("unpackDescription", () => {
  it("restores the span objects of a description the studio sent packed", () => {
    const packed = {
      options: [
        { name: "a", span: [0, 1, 2, 1, 9, 0, 7], states: [{ name: "s", span: null, decision: { if: "x", span: [1, 3, 4, 3, 8, 20, 24], then: { leaf: 0, span: [0, 5, 1, 5, 2, 40, 41] } } }] },
      ],
      span_files: ["options/a.xabsl", "options/b.xabsl"],
    } as unknown as BehaviorDescription & { span_files: string[] };
    const plain = unpackDescription(packed) as unknown as Record<string, unknown>;
    expect(plain).toEqual({
      options: [
        {
          name: "a",
          span: { file: "options/a.xabsl", line: 1, col: 2, end_line: 1, end_col: 9, start: 0, end: 7 },
          states: [
            {
              name: "s",
              span: null,
              decision: {
                if: "x",
                span: { file: "options/b.xabsl", line: 3, col: 4, end_line: 3, end_col: 8, start: 20, end: 24 },
                then: { leaf: 0, span: { file: "options/a.xabsl", line: 5, col: 1, end_line: 5, end_col: 2, start: 40, end: 41 } },
              },
            },
          ],
        },
      ],
    });
  });
  it("derives the transitions and calls the server left off the wire, as the server derives them", () => {
    const leaf = (to: string, n: number, stay = false): Record<string, unknown> => ({ to, stay, leaf: n, span: null });
    const packed = {
      options: [
        {
          name: "a",
          span: null,
          states: [
            {
              name: "s",
              span: null,
              actions: [{ type: "assign", symbol: "x", value: "1", span: null }, { type: "option", name: "b", args: [], span: null }, { type: "behavior", name: "kick", args: [], span: null }],
              decision: { if: "p", span: null, then: leaf("t", 0), else: { if: "q", span: null, then: leaf("u", 1), else: leaf("s", 2, true) } },
            },
            { name: "t", span: null, actions: [], decision: leaf("s", 0) },
          ],
        },
      ],
      span_files: [],
      derived: ["transitions", "calls"],
    } as unknown as BehaviorDescription & { span_files: string[] };
    const [option] = unpackDescription(packed).options;
    expect(option?.transitions).toEqual([
      { from: "s", to: "t", leaf: 0, stay: false, span: null },
      { from: "s", to: "u", leaf: 1, stay: false, span: null },
      { from: "s", to: "s", leaf: 2, stay: true, span: null },
      { from: "t", to: "s", leaf: 0, stay: false, span: null },
    ]);
    expect(option?.calls).toEqual([
      { state: "s", type: "option", name: "b" },
      { state: "s", type: "behavior", name: "kick" },
    ]);
    expect("derived" in unpackDescription(packed)).toBe(false);
  });
  it("leaves a plain description as it is", () => {
    const plain = { options: [{ name: "a", span: { file: "f", line: 1, col: 1, end_line: 1, end_col: 2, start: 0, end: 1 } }] } as unknown as BehaviorDescription;
    expect(unpackDescription(plain)).toBe(plain);
  });
});
