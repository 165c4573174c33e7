// Files as they are (issue 11): each buffer keeps its file's line separator, so a document
// round-trips byte for byte and Enter inserts the file's own separator.
import { EditorState } from "@codemirror/state";
import { describe, expect, it } from "vitest";
import { lineSeparatorOf } from "../src/panels/editor";

const texts = [
  "option o {\r  state s {}\r}\r",
  "option o {\r\n  state s {}\r\n}\r\n",
  "option o {\n  state s {}\n}\n",
  "option o {\r\n mixed \r lone cr \n lf\r\n}",
  "no line break at all",
  "",
  "\r\r\n\n\r",
];

describe("lineSeparatorOf", () => {
  it("picks the most frequent separator", () => {
    expect(lineSeparatorOf(texts[0])).toBe("\r");
    expect(lineSeparatorOf(texts[1])).toBe("\r\n");
    expect(lineSeparatorOf(texts[2])).toBe("\n");
    expect(lineSeparatorOf(texts[3])).toBe("\r\n");
    expect(lineSeparatorOf(texts[4])).toBe("\n");
  });

  it.each(texts)("round-trips %j through an editor state", (text) => {
    const state = EditorState.create({ doc: text, extensions: [EditorState.lineSeparator.of(lineSeparatorOf(text))] });
    expect(state.sliceDoc()).toBe(text);
    const enter = state.update({ changes: { from: state.doc.length, insert: state.lineBreak + "x" } }).state;
    expect(enter.sliceDoc()).toBe(text + lineSeparatorOf(text) + "x");
  });

  it("a CR file in the default state would not round-trip (the bug)", () => {
    expect(EditorState.create({ doc: texts[0] }).sliceDoc()).not.toBe(texts[0]);
  });
});
