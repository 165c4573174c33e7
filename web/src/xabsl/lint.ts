/// Server diagnostics -> CodeMirror `Diagnostic`s, and the as-you-type linter.
///
/// The compiler reports positions in the file as it read it: 1-based `line`/`col` (exclusive
/// `end_col`) and `start`/`end` offsets in code points. The editor's document differs in two
/// ways: CodeMirror normalises `\r\n` to `\n`, and JavaScript strings count UTF-16 units. Lines
/// and columns survive both, so they are used first; offsets are the fallback (converted from
/// code points), and everything is clamped into the document so a stale diagnostic never throws.
import { type Diagnostic, linter } from "@codemirror/lint";
import type { Extension, Text } from "@codemirror/state";
import type { EditorView } from "@codemirror/view";
import type { Span } from "../description";

/// One diagnostic as the server sends it (engine/lang/diagnostics.py, `--format json`).
export interface ServerDiagnostic {
  severity: "error" | "warning" | "info" | "hint";
  code: string;
  original_code?: string;
  message: string;
  file: string | null;
  span: Span | null;
  related?: Array<{ message: string; span: Span | null }>;
}

/// Whether two behavior file paths name the same file (server paths may be absolute or relative
/// to the behavior root; the editor knows the root-relative one).
export function samePath(serverPath: string | null | undefined, editorPath: string): boolean {
  if (!serverPath) return false;
  const a = serverPath.replace(/\\/g, "/").replace(/^\.\//, "");
  const b = editorPath.replace(/\\/g, "/").replace(/^\.\//, "");
  return a === b || a.endsWith("/" + b) || b.endsWith("/" + a);
}

/// UTF-16 offset in `line` of the code-point column `col` (0-based).
function utf16Column(line: string, col: number): number {
  let units = 0;
  for (let points = 0; points < col && units < line.length; points++) {
    const code = line.charCodeAt(units);
    units += code >= 0xd800 && code <= 0xdbff ? 2 : 1;
  }
  return Math.min(units, line.length);
}

/// Document offset of a 1-based line and column (code points), clamped into `doc`.
export function positionOf(doc: Text, line: number, col: number): number {
  if (line < 1) return 0;
  if (line > doc.lines) return doc.length;
  const l = doc.line(line);
  return l.from + utf16Column(l.text, Math.max(0, col - 1));
}

/// Document offset of a code-point offset of the file (fallback when there is no line).
export function offsetOf(doc: Text, codePoints: number): number {
  const text = doc.toString();
  let units = 0;
  for (let points = 0; points < codePoints && units < text.length; points++) {
    const code = text.charCodeAt(units);
    units += code >= 0xd800 && code <= 0xdbff ? 2 : 1;
  }
  return Math.min(units, doc.length);
}

/// The CodeMirror diagnostics of `path` among the server's `diagnostics`.
///
/// A diagnostic without a span, or of another file, is skipped here (the editor's status bar
/// lists those). An empty range is widened to one character so it stays visible.
export function toCodeMirror(diagnostics: readonly ServerDiagnostic[], doc: Text, path: string): Diagnostic[] {
  const out: Diagnostic[] = [];
  for (const d of diagnostics) {
    const span = d.span;
    if (!span || !samePath(span.file ?? d.file, path)) continue;
    let from: number;
    let to: number;
    if (span.line > 0) {
      from = positionOf(doc, span.line, span.col);
      to = positionOf(doc, span.end_line || span.line, span.end_col || span.col);
    } else {
      from = offsetOf(doc, span.start);
      to = offsetOf(doc, span.end);
    }
    if (to < from) to = from;
    if (to === from && to < doc.length) to = from + 1;
    const severity = d.severity === "error" || d.severity === "warning" || d.severity === "info" || d.severity === "hint" ? d.severity : "error";
    const code = d.original_code ? `${d.code} ${d.original_code}` : d.code;
    out.push({ from, to, severity, message: d.message, source: code });
  }
  return out.sort((a, b) => a.from - b.from || a.to - b.to);
}

/// A compile function: the buffer's text for `path` in, the server's diagnostics out.
export type CompileFn = (path: string, text: string) => Promise<readonly ServerDiagnostic[]>;

/// The as-you-type linter: after `delay` ms without typing, compile the buffer on the server
/// (the other files as saved) and show what it says about this file.
///
/// `onResult` sees every answer (the editor shows counts and other files' problems).
export function xabslLinter(
  path: () => string | null,
  compile: CompileFn,
  onResult: (diagnostics: readonly ServerDiagnostic[] | Error) => void,
  delay = 350,
): Extension {
  return linter(
    async (view: EditorView) => {
      const p = path();
      if (!p) return [];
      const doc = view.state.doc;
      try {
        const diagnostics = await compile(p, doc.toString());
        onResult(diagnostics);
        return toCodeMirror(diagnostics, view.state.doc.length === doc.length ? view.state.doc : doc, p);
      } catch (error) {
        onResult(error instanceof Error ? error : new Error(String(error)));
        return [];
      }
    },
    { delay },
  );
}
