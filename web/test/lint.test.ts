import { Text } from "@codemirror/state";
import { describe, expect, it } from "vitest";
import type { Span } from "../src/description";
import { offsetOf, positionOf, samePath, type ServerDiagnostic, toCodeMirror } from "../src/xabsl/lint";

const source = "option play {\n  initial state wait {\n    decision { else goto serch; }\n    action { }\n  }\n}\n";
const doc = Text.of(source.split("\n"));

function diag(line: number, col: number, endCol: number, extra: Partial<ServerDiagnostic> = {}): ServerDiagnostic {
  const start = source.split("\n").slice(0, line - 1).join("\n").length + 1 + col - 1;
  return {
    severity: "error",
    code: "unknown-state",
    original_code: "X5552",
    lint: false,
    message: "option 'play' has no state 'serch' (did you mean 'search'?)",
    file: "behavior/options/play.xabsl",
    span: { file: "behavior/options/play.xabsl", line, col, end_line: line, end_col: endCol, start, end: start + endCol - col },
    related: [],
    ...extra,
  };
}

describe("toCodeMirror", () => {
  it("maps line and column to document offsets", () => {
    const [d] = toCodeMirror([diag(3, 26, 31)], doc, "behavior/options/play.xabsl");
    expect(source.slice(d?.from, d?.to)).toBe("serch");
    expect(d).toMatchObject({ severity: "error", source: "unknown-state X5552" });
  });

  it("keeps only the open file's diagnostics, matching absolute and relative paths", () => {
    const other = diag(1, 1, 2, { span: { ...(diag(1, 1, 2).span as Span), file: "behavior/options/kick.xabsl" } });
    const absolute = diag(3, 26, 31, { span: { ...(diag(3, 26, 31).span as Span), file: "/home/u/soccer/behavior/options/play.xabsl" } });
    const out = toCodeMirror([other, absolute, diag(1, 1, 1, { span: null })], doc, "behavior/options/play.xabsl");
    expect(out).toHaveLength(1);
    expect(samePath("./a/b.xabsl", "a/b.xabsl")).toBe(true);
    expect(samePath("a/bb.xabsl", "b.xabsl")).toBe(false);
  });

  it("survives CRLF files: lines and columns, not raw offsets, are used", () => {
    const crlf = source.replace(/\n/g, "\r\n");
    // CodeMirror splits on \r\n too; the server's offsets count the \r, its lines do not.
    const cmDoc = Text.of(crlf.split(/\r\n/));
    const [d] = toCodeMirror([diag(3, 26, 31)], cmDoc, "behavior/options/play.xabsl");
    expect(cmDoc.sliceString(d?.from ?? 0, d?.to ?? 0)).toBe("serch");
  });

  it("counts columns in code points (astral characters take two UTF-16 units)", () => {
    const t = Text.of(["// 🤖 x", "ab"]);
    expect(t.sliceString(positionOf(t, 1, 6), positionOf(t, 1, 7))).toBe("x");
    expect(offsetOf(t, 5)).toBe(6);
  });

  it("clamps stale positions and widens empty ranges", () => {
    const [d] = toCodeMirror([diag(99, 1, 1)], doc, "behavior/options/play.xabsl");
    expect(d?.from).toBe(doc.length);
    const [e] = toCodeMirror([diag(1, 1, 1)], doc, "behavior/options/play.xabsl");
    expect([e?.from, e?.to]).toEqual([0, 1]);
    const [w] = toCodeMirror([diag(1, 1, 7, { severity: "warning", original_code: "" })], doc, "behavior/options/play.xabsl");
    expect(w).toMatchObject({ severity: "warning", source: "unknown-state" });
  });

  it("falls back to code-point offsets without a line", () => {
    const d = diag(3, 26, 31);
    const [m] = toCodeMirror([{ ...d, span: { ...(d.span as Span), line: 0 } }], doc, "behavior/options/play.xabsl");
    expect(source.slice(m?.from, m?.to)).toBe("serch");
  });
});
