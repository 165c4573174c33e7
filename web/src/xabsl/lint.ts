/// Diagnostics -> CodeMirror `Diagnostic`s (the REST compile's and the language server's), and
/// the as-you-type linter fed by the language server's published diagnostics.
///
/// The compiler reports positions in the file as it read it: 1-based `line`/`col` (exclusive
/// `end_col`) and `start`/`end` offsets in code points. The editor's document differs in two
/// ways: CodeMirror normalises `\r\n` to `\n`, and JavaScript strings count UTF-16 units. Lines
/// and columns survive both, so they are used first; offsets are the fallback (converted from
/// code points), and everything is clamped into the document so a stale diagnostic never throws.
import { type Diagnostic, setDiagnostics } from "@codemirror/lint";
import type { Extension, Text } from "@codemirror/state";
import { type EditorView, ViewPlugin, type ViewUpdate } from "@codemirror/view";
import type { DiagnosticJson } from "../messages.gen";
import { fromPosition } from "./complete";
import type { LspClient, LspDiagnostic } from "./lsp";

/// One diagnostic as the server sends it (engine/lang/diagnostics.py, `--format json`).
/// A diagnostic as the server sends it (the compiler's one JSON shape, `DiagnosticJson`), in a
/// save, a compile, the status, a compile event; the language server's are converted to it.
export type ServerDiagnostic = DiagnosticJson;

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
    const code = d.original_code ? `${d.code} ${d.original_code}` : d.code;
    out.push({ from, to, severity: d.severity, message: d.message, source: code });
  }
  return out.sort((a, b) => a.from - b.from || a.to - b.to);
}

/// The protocol's diagnostics of one document as CodeMirror diagnostics; a "did you mean" hint
/// (the server's `data.replacement`) becomes an action that puts the suggested name in.
export function lspToCodeMirror(diagnostics: readonly LspDiagnostic[], doc: Text): Diagnostic[] {
  const out: Diagnostic[] = [];
  for (const d of diagnostics) {
    const from = fromPosition(doc, d.range.start);
    let to = Math.max(from, fromPosition(doc, d.range.end));
    if (to === from && to < doc.length) to = from + 1;
    const replacement = d.data?.replacement;
    const code = d.data?.original_code ? `${d.code} ${d.data.original_code}` : String(d.code ?? "xabsl");
    out.push({
      from,
      to,
      severity: d.severity === 1 ? "error" : d.severity === 2 ? "warning" : d.severity === 3 ? "info" : "hint",
      message: d.message,
      source: code,
      ...(replacement
        ? { actions: [{ name: `Change to '${replacement}'`, apply: (view: EditorView, a: number, b: number) => view.dispatch({ changes: { from: a, to: b, insert: replacement } }) }] }
        : {}),
    });
  }
  return out.sort((a, b) => a.from - b.from || a.to - b.to);
}

/// The protocol's diagnostics of `path` in the shape of the REST compile's (the status bar's).
export function toServerDiagnostics(path: string, diagnostics: readonly LspDiagnostic[]): ServerDiagnostic[] {
  // The compiler gives errors and warnings only; a client-side hint or info counts as a warning.
  return diagnostics.map((d) => ({
    severity: d.severity === 1 ? "error" : "warning",
    code: String(d.code ?? ""),
    original_code: d.data?.original_code ?? "",
    lint: d.data?.lint ?? false,
    message: d.message,
    file: path,
    span: {
      file: path,
      line: d.range.start.line + 1,
      col: d.range.start.character + 1,
      end_line: d.range.end.line + 1,
      end_col: d.range.end.character + 1,
      start: 0,
      end: 0,
    },
    related: [],
  }));
}

/// Diagnostics as you type, from the language server: the buffer's text goes to the server
/// (after `delay` ms without typing); what it publishes for `path` and `keep` keeps is shown in
/// the editor, and `onResult` sees the diagnostics of every file of the behavior set.
export function xabslLinter(
  client: LspClient,
  path: string | null,
  onResult: (diagnostics: readonly ServerDiagnostic[] | Error) => void,
  delay = 150,
  keep: (d: LspDiagnostic) => boolean = () => true,
): Extension {
  return ViewPlugin.fromClass(
    class {
      private timer: ReturnType<typeof setTimeout> | null = null;
      private readonly unsubscribe: () => void;

      constructor(readonly view: EditorView) {
        this.unsubscribe = client.onDiagnostics((p) => {
          if (p === path) this.show();
        });
        this.schedule(0);
        if (path && client.diagnostics.has(path)) queueMicrotask(() => this.show());
      }

      show(): void {
        if (!path) return;
        const own = (client.diagnostics.get(path) ?? []).filter(keep);
        this.view.dispatch(setDiagnostics(this.view.state, lspToCodeMirror(own, this.view.state.doc)));
        const all: ServerDiagnostic[] = [];
        for (const [p, ds] of client.diagnostics) all.push(...toServerDiagnostics(p, ds));
        onResult(all);
      }

      schedule(ms: number): void {
        if (this.timer !== null) clearTimeout(this.timer);
        this.timer = setTimeout(() => {
          this.timer = null;
          if (path) client.sync(path, this.view.state.doc.toString()).catch((error: Error) => onResult(error));
        }, ms);
      }

      update(u: ViewUpdate): void {
        if (u.docChanged) this.schedule(delay);
      }

      destroy(): void {
        if (this.timer !== null) clearTimeout(this.timer);
        this.unsubscribe();
      }
    },
  );
}
