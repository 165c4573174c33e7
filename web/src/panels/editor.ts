/// The behavior editor: a file tree of the behavior folders, CodeMirror with XABSL highlighting,
/// completion from the IR (reconfigured on every hello), diagnostics as you type (compiled on
/// the server, nothing saved), go to definition (F12, Ctrl+click), find references (Shift+F12),
/// save (Ctrl+S) = PUT with If-Match -> hot reload, conflicts shown, never overwritten silently,
/// and a new option (the New option dialog, panels/newoption.ts).
///
/// Files are edited as they are: each buffer keeps its file's line separator (CodeMirror's
/// `lineSeparator` facet, so Enter inserts it and `sliceDoc()` joins with it), so a file with CR
/// or CRLF line ends opens unmodified and a save writes exactly the edited text. `doc.toString()`
/// (always "\n", one unit per line break, like document positions) stays what the language
/// features and the as-you-type linter read.
import { autocompletion, closeBrackets, closeBracketsKeymap, closeCompletion, completionKeymap } from "@codemirror/autocomplete";
import { defaultKeymap, history, historyKeymap, indentWithTab } from "@codemirror/commands";
import { bracketMatching, HighlightStyle, indentOnInput, syntaxHighlighting } from "@codemirror/language";
import { lintGutter, lintKeymap, setDiagnostics } from "@codemirror/lint";
import { highlightSelectionMatches, searchKeymap } from "@codemirror/search";
import { EditorSelection, EditorState } from "@codemirror/state";
import { drawSelection, EditorView, highlightActiveLine, highlightActiveLineGutter, keymap, lineNumbers } from "@codemirror/view";
import { tags as t } from "@lezer/highlight";
import { compile, type FileEntry, listFiles, programStatus, readFile, token, writeFile } from "../api";
import { diagnosticsFor, homeProgram, type SetDiagnostic } from "../behaviorsets";
import type { Span } from "../description";
import type { CompileEvent, FileEvent } from "../protocol";
import type { Session, SessionEvent } from "../session";
import { lineDiff } from "../linediff";
import { h, toast } from "../ui";
import { toPosition, xabslCompletion } from "../xabsl/complete";
import { xabsl } from "../xabsl/language";
import { lspToCodeMirror, samePath, type ServerDiagnostic, xabslLinter } from "../xabsl/lint";
import { LspClient, lspUrl, websocketTransport } from "../xabsl/lsp";
import { definitionAt, lspHover, referencesAt, renameAt, toChanges } from "../xabsl/navigate";
import { LINT_CODES, LintFilter } from "./lintfilter";
import { NewOptionDialog } from "./newoption";

const highlight = HighlightStyle.define([
  { tag: [t.keyword, t.controlKeyword], color: "var(--tok-keyword)", fontWeight: "600" },
  { tag: t.typeName, color: "var(--tok-type)" },
  { tag: [t.bool, t.atom], color: "var(--tok-atom)" },
  { tag: t.number, color: "var(--tok-number)" },
  { tag: [t.string, t.unit], color: "var(--tok-string)" },
  { tag: [t.lineComment, t.blockComment], color: "var(--tok-comment)", fontStyle: "italic" },
  { tag: t.docComment, color: "var(--tok-doc)", fontStyle: "italic" },
  { tag: t.definition(t.variableName), color: "var(--tok-def)", fontWeight: "600" },
  { tag: t.special(t.variableName), color: "var(--tok-param)" },
  { tag: t.operator, color: "var(--tok-operator)" },
  { tag: t.invalid, color: "#ff5555", textDecoration: "underline wavy" },
]);


/// The line separator of a file's text: the most frequent of CRLF, CR and LF ("\n" for none).
/// The others, if the file mixes them, stay in the text as characters and round-trip too.
export function lineSeparatorOf(text: string): string {
  const crlf = text.split("\r\n").length - 1;
  const cr = text.split("\r").length - 1 - crlf;
  const lf = text.split("\n").length - 1 - crlf;
  if (crlf >= cr && crlf >= lf && crlf > 0) return "\r\n";
  return cr > lf ? "\r" : "\n";
}

interface Buffer {
  path: string;
  state: EditorState;
  version: string;
  saved: string;
  /// the file changed on disk while this buffer has unsaved edits: its version there, and its
  /// text once read (for the diff of the choice)
  conflict: { version: string; theirs?: string } | null;
}

/// Scroll back to the left edge once the cursor would be in view there. CodeMirror scrolls
/// sideways to follow a cursor past the right edge (typing at the end of a long line) but never
/// back, so after moving to a short line the view stayed scrolled, every line's start hidden.
const scrollBackLeft = EditorView.updateListener.of((u) => {
  if (!u.selectionSet && !u.docChanged) return;
  const view = u.view;
  const scroller = view.scrollDOM;
  if (scroller.scrollLeft === 0) return;
  view.requestMeasure({
    read: () => {
      const at = view.coordsAtPos(view.state.selection.main.head);
      if (!at) return false;
      const x = at.right - scroller.getBoundingClientRect().left + scroller.scrollLeft; // in the unscrolled content
      return x + 24 <= scroller.clientWidth; // in view, with a margin, at the left edge
    },
    write: (fits) => {
      if (fits) scroller.scrollLeft = 0;
    },
  });
});

export class EditorPanel {
  readonly element: HTMLElement;
  private readonly tree: HTMLElement;
  private readonly view: EditorView;
  private readonly status: HTMLElement;
  private readonly banner: HTMLElement;
  private readonly refs: HTMLElement;
  private readonly title: HTMLElement;
  /// completion, diagnostics, hover, definition, references and rename: the language server
  readonly lsp = new LspClient(() => websocketTransport(lspUrl(token)));
  private readonly buffers = new Map<string, Buffer>();
  private files: FileEntry[] = [];
  private current: Buffer | null = null;
  /// The server's diagnostics of the current file's behavior sets (`xabsl compile`'s, per set):
  /// what the status bar counts. The language server only draws them into the text as you type.
  private lastDiagnostics: readonly SetDiagnostic[] = [];
  /// which warnings are hidden, per behavior set (the Lint… dialog)
  private readonly lintFilter = new LintFilter();
  private readonly lintDialog: HTMLDialogElement;
  private countTimer: ReturnType<typeof setTimeout> | null = null;
  private countAsked = 0;

  /// The New option dialog (it writes the file and the include line, then opens the file here).
  private readonly newOptionDialog: NewOptionDialog;

  constructor(private readonly session: Session) {
    this.newOptionDialog = new NewOptionDialog(session, async (path) => {
      await this.refreshFiles();
      await this.open(path, { line: 2, col: 8 });
    });
    this.tree = h("nav.file-tree", { "aria-label": "Behavior files" });
    this.title = h("span.file-title", {}, "No file open");
    this.status = h("div.editor-status", { role: "status", "aria-live": "polite" });
    this.banner = h("div.banner", { hidden: true, role: "alert" });
    this.refs = h("div.references", { hidden: true });
    const host = h("div.editor-host");
    this.view = new EditorView({ parent: host, state: this.makeState("", "") });
    const toolbar = h(
      "div.toolbar",
      {},
      this.title,
      h("button.primary#save", { title: "Save and hot reload (Ctrl+S)", onclick: () => void this.save() }, "Save"),
      h("button", { title: "Go to definition (F12)", onclick: () => this.goToDefinition() }, "Definition"),
      h("button", { title: "Find references (Shift+F12)", onclick: () => void this.references() }, "References"),
      h("button", { title: "Rename everywhere (F2)", onclick: () => void this.rename() }, "Rename"),
      h("button", { title: "Create an option: name, parameters, folder; adds its include line to the agents file", onclick: () => void this.newOption() }, "New option…"),
      h("button#lint-filter", { title: "Which warnings to show for this behavior set (remembered in this browser)", onclick: () => this.showLintDialog() }, "Lint…"),
    );
    this.lintDialog = h("dialog.lint-filter", { "aria-label": "Warnings shown" }) as HTMLDialogElement;
    this.element = h(
      "div.panel.editor-panel",
      {},
      h("div.editor-side", {}, h("div.section-title", {}, "Files"), this.tree),
      h("div.editor-main", {}, toolbar, this.banner, host, this.refs, this.status),
      this.lintDialog,
    );
    this.view.contentDOM.setAttribute("aria-label", "XABSL source");
  }

  private makeState(doc: string, path: string): EditorState {
    return EditorState.create({
      doc,
      extensions: [
        EditorState.lineSeparator.of(lineSeparatorOf(doc)),
        lineNumbers(),
        highlightActiveLineGutter(),
        history(),
        drawSelection(),
        indentOnInput(),
        bracketMatching(),
        closeBrackets(),
        highlightActiveLine(),
        highlightSelectionMatches(),
        scrollBackLeft,
        autocompletion({ activateOnTyping: true }),
        xabsl(),
        syntaxHighlighting(highlight),
        xabslCompletion(this.lsp, () => path || null),
        lspHover(this.lsp, () => path || null),
        lintGutter(),
        xabslLinter(this.lsp, path || null, (result) => this.showCompile(result), 150, (d) => !this.lintFilter.hides(this.setKey(path), d)),
        keymap.of([
          { key: "Mod-s", preventDefault: true, run: () => (void this.save(), true) },
          { key: "F12", run: () => (this.goToDefinition(), true) },
          { key: "Shift-F12", run: () => (void this.references(), true) },
          { key: "F2", run: () => (void this.rename(), true) },
          ...closeBracketsKeymap,
          ...defaultKeymap,
          ...searchKeymap,
          ...historyKeymap,
          ...completionKeymap,
          ...lintKeymap,
          indentWithTab,
        ]),
        EditorView.domEventHandlers({
          mousedown: (ev, view) => {
            if (!(ev.ctrlKey || ev.metaKey)) return false;
            const pos = view.posAtCoords({ x: ev.clientX, y: ev.clientY });
            if (pos === null) return false;
            view.dispatch({ selection: { anchor: pos } });
            this.goToDefinition();
            ev.preventDefault();
            return true;
          },
        }),
        EditorView.updateListener.of((u) => {
          if (u.docChanged) {
            this.statusNote = "";
            this.markDirty();
            this.scheduleCounts();
          }
        }),
      ],
    });
  }

  private isDirty(b: Buffer | null): boolean {
    if (!b) return false;
    const state = b === this.current ? this.view.state : b.state;
    return state.sliceDoc() !== b.saved;
  }

  private markDirty(): void {
    const b = this.current;
    if (!b) return;
    this.title.textContent = `${b.path}${this.isDirty(b) ? " ●" : ""}`;
    for (const el of this.tree.querySelectorAll<HTMLElement>("[data-path]")) {
      const buf = this.buffers.get(el.dataset.path ?? "");
      el.classList.toggle("dirty", this.isDirty(buf ?? null));
    }
  }

  /// Load the file list (on the first hello and when files change).
  async refreshFiles(): Promise<void> {
    try {
      this.files = await listFiles();
    } catch (error) {
      this.tree.replaceChildren(h("div.empty", {}, `Cannot list files: ${(error as Error).message}`));
      return;
    }
    const groups = new Map<string, FileEntry[]>();
    for (const f of this.files) {
      const dir = f.path.includes("/") ? f.path.slice(0, f.path.lastIndexOf("/")) : "";
      if (!groups.has(dir)) groups.set(dir, []);
      groups.get(dir)?.push(f);
    }
    const items: HTMLElement[] = [];
    for (const dir of [...groups.keys()].sort()) {
      items.push(h("div.dir", {}, dir ? `${dir}/` : "/"));
      for (const f of (groups.get(dir) ?? []).sort((a, b) => a.path.localeCompare(b.path))) {
        const name = f.path.slice(dir ? dir.length + 1 : 0);
        const el = h(
          "button.file",
          { "data-path": f.path, title: `${f.path}${f.programs.length ? ` (in ${f.programs.join(", ")})` : " (not included by any agents file)"}`, onclick: () => void this.open(f.path) },
          name,
        );
        if (f.path === this.current?.path) el.classList.add("open");
        items.push(el);
      }
    }
    this.tree.replaceChildren(...items);
    this.markDirty();
  }

  /// Open `path` (keeping other buffers and their undo history), optionally at a span.
  async open(path: string, at?: { line: number; col: number } | { from: number; to: number }): Promise<void> {
    if (this.current) this.current.state = this.view.state;
    let buffer = this.buffers.get(path);
    if (!buffer) {
      let file;
      try {
        file = await readFile(path);
      } catch (error) {
        toast(`Cannot open ${path}: ${(error as Error).message}`, "error");
        return;
      }
      buffer = { path, state: this.makeState(file.text, path), version: file.version, saved: file.text, conflict: null };
      this.buffers.set(path, buffer);
    }
    this.current = buffer;
    this.view.setState(buffer.state);
    this.statusNote = "";
    this.showBanner();
    void this.refreshCounts();
    for (const el of this.tree.querySelectorAll<HTMLElement>("[data-path]")) el.classList.toggle("open", el.dataset.path === path);
    this.markDirty();
    if (at) {
      const doc = this.view.state.doc;
      let from: number;
      let to: number;
      if ("line" in at) {
        const line = doc.line(Math.max(1, Math.min(doc.lines, at.line)));
        from = Math.min(line.to, line.from + Math.max(0, at.col - 1));
        to = from;
      } else {
        from = Math.min(doc.length, at.from);
        to = Math.min(doc.length, at.to);
      }
      this.view.dispatch({ selection: EditorSelection.single(from, to), effects: EditorView.scrollIntoView(from, { y: "center" }) });
    }
    this.view.focus();
  }

  /// Open the file of a span from the description (server paths may differ in prefix).
  openSpan(span: Span): void {
    void (async () => {
      if (!this.files.length) await this.refreshFiles();
      const file = this.files.find((f) => samePath(span.file, f.path))?.path ?? span.file;
      await this.open(file, { line: span.line, col: span.col });
    })();
  }

  /// The diagnostics of `path` worth showing: its own behavior set's (see behaviorsets.ts).
  private own(path: string, diagnostics: readonly ServerDiagnostic[]): ServerDiagnostic[] {
    const programs = this.files.find((f) => f.path === path)?.programs ?? [...this.session.programs.keys()];
    return diagnosticsFor(path, diagnostics as readonly SetDiagnostic[], programs);
  }

  /// The language server's answer: it draws the diagnostics into the text (xabslLinter); the
  /// status bar counts the server's compile (refreshCounts), so only a failure is shown here.
  private showCompile(result: readonly ServerDiagnostic[] | Error): void {
    if (result instanceof Error) {
      this.status.className = "editor-status warn";
      this.status.textContent = `Cannot check: ${result.message}`;
    }
  }

  /// The home behavior set of `path` (the set whose warnings its editor shows).
  private homeOf(path: string): string | null {
    const programs = this.files.find((f) => f.path === path)?.programs ?? [...this.session.programs.keys()];
    return homeProgram(path, programs);
  }

  /// The key the hidden warnings of `path`'s home set are kept under.
  private setKey(path: string): string {
    return LintFilter.setKey(this.session.hello?.session.example ?? "", this.homeOf(path) ?? "");
  }

  /// Count again a moment after typing stops (one compile per pause, not per key).
  private scheduleCounts(): void {
    if (this.countTimer !== null) clearTimeout(this.countTimer);
    this.countTimer = setTimeout(() => {
      this.countTimer = null;
      void this.refreshCounts();
    }, 600);
  }

  /// The diagnostics of the current file's behavior sets from the server's compile, the one
  /// `xabsl compile` runs: of the buffer's text while it has unsaved edits, else of the files
  /// as the last compile found them. So the studio counts what the command line prints.
  async refreshCounts(): Promise<void> {
    const b = this.current;
    if (!b) return;
    const asked = ++this.countAsked;
    let diagnostics: SetDiagnostic[];
    try {
      if (this.isDirty(b)) {
        diagnostics = (await compile(b.path, this.view.state.sliceDoc())).diagnostics as SetDiagnostic[];
      } else {
        const programs = new Set(this.files.find((f) => f.path === b.path)?.programs ?? []);
        const status = await programStatus();
        diagnostics = Object.entries(status)
          .filter(([key]) => !programs.size || programs.has(key))
          .flatMap(([key, p]) => p.diagnostics.map((d) => ({ ...d, program: key })));
      }
    } catch {
      return; // the next save, compile or reload counts again
    }
    if (asked !== this.countAsked || b !== this.current) return;
    this.lastDiagnostics = this.own(b.path, diagnostics);
    this.renderStatus();
  }

  /// The Lint… dialog: per warning code of this behavior set, shown or hidden.
  private showLintDialog(): void {
    const path = this.current?.path;
    if (!path) {
      toast("Open a file of a behavior set first", "info");
      return;
    }
    const set = this.setKey(path);
    const home = this.homeOf(path);
    const counts = new Map<string, number>();
    for (const d of this.lastDiagnostics) if (d.severity !== "error" && (home === null || d.program === undefined || d.program === home)) counts.set(d.code, (counts.get(d.code) ?? 0) + 1);
    for (const code of this.lintFilter.hidden(set).codes) if (!counts.has(code)) counts.set(code, 0);
    const changed = (): void => {
      this.renderStatus();
      this.applySquiggles();
      this.showLintDialog();
    };
    const rows = [...counts.entries()]
      .sort((a, b) => b[1] - a[1] || a[0].localeCompare(b[0]))
      .map(([code, n]) =>
        h(
          "label.lint-code",
          {},
          h("input", {
            type: "checkbox",
            checked: !this.lintFilter.hides(set, { severity: "warning", code }),
            "data-code": code,
            onchange: (ev: Event) => {
              this.lintFilter.setCode(set, code, !(ev.target as HTMLInputElement).checked);
              changed();
            },
          }),
          h("code", {}, code),
          ` ${n}`,
          LINT_CODES.has(code) ? h("span.muted", {}, " · lint: the original compiler does not print it") : null,
        ),
      );
    const hidden = this.lintFilter.hidden(set);
    this.lintDialog.replaceChildren(
      h("div.section-title", {}, `Warnings shown for ${home ?? "this behavior set"}`),
      rows.length ? h("div.lint-codes", {}, ...rows) : h("div.muted", {}, "This behavior set has no warnings."),
      h(
        "div.actions",
        {},
        h("button#lint-original", { title: "Hide every lint warning: leave what the original compiler prints (xabsl compile --no-lint)", disabled: hidden.allLint, onclick: () => (this.lintFilter.setAllLint(set, true), changed()) }, "As the original compiler"),
        h("button#lint-all", { title: "Show every warning", onclick: () => (this.lintFilter.setAllLint(set, false), changed()) }, "Show all"),
        h("button", { onclick: () => this.lintDialog.close() }, "Close"),
      ),
    );
    if (!this.lintDialog.open) this.lintDialog.showModal();
  }

  /// Draw the language server's diagnostics of the current file again, without the hidden ones.
  private applySquiggles(): void {
    const path = this.current?.path;
    if (!path) return;
    const set = this.setKey(path);
    const own = (this.lsp.diagnostics.get(path) ?? []).filter((d) => !this.lintFilter.hides(set, d));
    this.view.dispatch(setDiagnostics(this.view.state, lspToCodeMirror(own, this.view.state.doc)));
  }

  /// What the last save said ("hot reloaded behavior"): kept while the counts are redrawn, until
  /// the next edit.
  private statusNote = "";

  private renderStatus(note?: string): void {
    if (note !== undefined) this.statusNote = note;
    const extra = this.statusNote;
    const path = this.current?.path ?? "";
    const set = this.setKey(path);
    const result = this.lastDiagnostics.filter((d) => !this.lintFilter.hides(set, d));
    const hidden = this.lastDiagnostics.length - result.length;
    const errors = result.filter((d) => d.severity === "error");
    const warnings = result.filter((d) => d.severity === "warning");
    const elsewhere = result.filter((d) => !samePath(d.span?.file ?? d.file, path));
    const items: Array<HTMLElement | string> = [];
    items.push(h("strong", {}, errors.length ? `✗ ${errors.length} error${errors.length > 1 ? "s" : ""}` : "✓ compiles"));
    if (warnings.length) items.push(`, ${warnings.length} warning${warnings.length > 1 ? "s" : ""}`);
    if (hidden) items.push(h("button.link.lint-hidden", { title: "Which warnings are shown (Lint…)", onclick: () => this.showLintDialog() }, ` (${hidden} hidden)`));
    if (extra) items.push(` — ${extra}`);
    for (const d of elsewhere.slice(0, 5)) {
      items.push(
        h(
          "button.link.diag-link",
          { onclick: () => d.span && this.openSpan(d.span) },
          `${d.span?.file ?? d.file}:${d.span?.line ?? "?"}: ${d.message}`,
        ),
      );
    }
    const first = errors.find((d) => samePath(d.span?.file ?? d.file, path));
    if (first) items.push(h("div.first-error", {}, `line ${first.span?.line}: ${first.message}`));
    this.status.className = `editor-status ${errors.length ? "error" : "ok"}`;
    this.status.replaceChildren(...items);
  }

  /// The choice for a buffer with unsaved edits whose file changed on disk (outside the studio or
  /// by another client): keep mine (save it over theirs) or take theirs, with the diff between.
  private showBanner(): void {
    const b = this.current;
    const conflict = b?.conflict;
    if (!b || !conflict) {
      this.banner.hidden = true;
      return;
    }
    this.banner.hidden = false;
    const diff =
      conflict.theirs === undefined
        ? h("div.muted", {}, "Reading the file on disk…")
        : h(
            "details.conflict-diff",
            { open: true },
            h("summary", {}, "What taking theirs changes: − yours, + theirs"),
            h("pre.diff", {}, ...lineDiff(this.view.state.sliceDoc(), conflict.theirs).map((l) => h(`span.${l.kind === "+" ? "add" : l.kind === "-" ? "del" : "same"}`, {}, `${l.kind} ${l.text}\n`))),
          );
    this.banner.replaceChildren(
      h("strong", {}, "Conflict: "),
      `${b.path} changed on disk (outside the studio, or by another client) while you have unsaved edits. Your text is still here, unsaved.`,
      h("button#keep-mine.danger", { title: "Save your text over the file on disk", onclick: () => void this.save(true) }, "Keep mine (save over theirs)"),
      h("button#take-theirs", { title: "Load the file on disk; your unsaved edits are dropped", onclick: () => void this.reloadFromDisk() }, "Take theirs (drop my edits)"),
      diff,
    );
    if (conflict.theirs === undefined) {
      void readFile(b.path).then(
        (file) => {
          if (b.conflict !== conflict) return;
          conflict.theirs = file.text;
          conflict.version = file.version;
          if (b === this.current) this.showBanner();
        },
        () => undefined, // deleted meanwhile: the file event says so
      );
    }
  }

  private async reloadFromDisk(): Promise<void> {
    const b = this.current;
    if (!b) return;
    const file = await readFile(b.path);
    b.version = file.version;
    b.saved = file.text;
    b.conflict = null;
    this.replaceText(b, file.text);
    this.showBanner();
    this.markDirty();
  }

  /// Put a file's new text from disk into its buffer: as an undoable change when its line
  /// separator is the buffer's, else as a fresh state (the separator is fixed per state).
  private replaceText(b: Buffer, text: string): void {
    const state = b === this.current ? this.view.state : b.state;
    if (state.lineBreak === lineSeparatorOf(text)) {
      const tr = state.update({ changes: { from: 0, to: state.doc.length, insert: text } });
      if (b === this.current) this.view.dispatch(tr);
      else b.state = tr.state;
      return;
    }
    b.state = this.makeState(text, b.path);
    if (b === this.current) this.view.setState(b.state);
  }

  /// Save the current file: PUT with If-Match; the server compiles and hot-reloads.
  async save(overwrite = false): Promise<void> {
    const b = this.current;
    if (!b) return;
    // A completion popup left open would go on offering names for text that is saved now.
    closeCompletion(this.view);
    const text = this.view.state.sliceDoc(); // joined with the file's own line separator
    const version = overwrite && b.conflict ? b.conflict.version : b.version;
    try {
      const { status, result, conflict } = await writeFile(b.path, text, version);
      if (conflict) {
        b.conflict = conflict;
        this.showBanner();
        toast(`Not saved: ${b.path} changed on disk. Choose what to keep.`, "error");
        return;
      }
      b.version = result.version ?? b.version;
      b.saved = text;
      this.lsp.saved(b.path);
      b.conflict = null;
      this.showBanner();
      this.markDirty();
      this.lastDiagnostics = this.own(b.path, result.diagnostics ?? []);
      if (status === 422 || !result.ok) {
        this.renderStatus("saved, but it does not compile: the running behavior keeps running");
        toast(`Saved ${b.path}, but it has errors — the old behavior keeps running.`, "error");
      } else {
        const reloaded = result.reloaded?.length ? `hot reloaded ${result.reloaded.join(", ")}` : "saved";
        this.renderStatus(reloaded);
        toast(`Saved ${b.path} — ${reloaded}.`, "ok");
      }
    } catch (error) {
      toast(`Save failed: ${(error as Error).message}`, "error");
    }
  }

  goToDefinition(): void {
    const path = this.current?.path;
    if (!path) return;
    void definitionAt(this.lsp, path, this.view.state, this.view.state.selection.main.head).then(
      (place) => (place ? void this.open(place.path, place) : toast("No definition found here", "info")),
      (error: Error) => toast(`No definition: ${error.message}`, "error"),
    );
  }

  /// The text of `path`: its buffer when open, else the file.
  private async textOf(path: string): Promise<string | null> {
    const open = this.buffers.get(path);
    if (open) return (open === this.current ? this.view.state : open.state).doc.toString();
    try {
      return (await readFile(path)).text;
    } catch {
      return null; // a file deleted meanwhile
    }
  }

  private async references(): Promise<void> {
    const path = this.current?.path;
    if (!path) return;
    const state = this.view.state;
    const word = state.wordAt(state.selection.main.head);
    const name = word ? state.sliceDoc(word.from, word.to) : "";
    const refs = await referencesAt(this.lsp, path, state, state.selection.main.head).catch(() => []);
    const texts = new Map<string, string | null>();
    for (const r of refs) if (!texts.has(r.path)) texts.set(r.path, await this.textOf(r.path));
    this.refs.hidden = false;
    this.refs.replaceChildren(
      h("div.section-title", {}, `${refs.length} reference${refs.length === 1 ? "" : "s"} to ${name}`, h("button.icon", { title: "Close", onclick: () => (this.refs.hidden = true) }, "×")),
      ...refs.map((r) => h("button.ref", { onclick: () => void this.open(r.path, r) }, h("span.ref-loc", {}, `${r.path}:${r.line}`), h("code", {}, (texts.get(r.path) ?? "").split("\n")[r.line - 1]?.trim() ?? ""))),
    );
  }

  /// Rename the name at the cursor in every file of the behavior set (the files stay unsaved).
  private async rename(): Promise<void> {
    const path = this.current?.path;
    if (!path) return;
    const state = this.view.state;
    const head = state.selection.main.head;
    await this.lsp.sync(path, state.doc.toString());
    const prepared = await this.lsp.prepareRename(path, toPosition(state.doc, head)).catch(() => null);
    if (!prepared) {
      toast("Nothing to rename here", "info");
      return;
    }
    const newName = window.prompt(`Rename ${prepared.placeholder} to:`, prepared.placeholder);
    if (!newName || newName === prepared.placeholder) return;
    let edits;
    try {
      edits = await renameAt(this.lsp, path, state, head, newName);
    } catch (error) {
      toast(`Cannot rename: ${(error as Error).message}`, "error");
      return;
    }
    if (!edits.size) {
      toast("Nothing to rename here", "info");
      return;
    }
    for (const [p, changes] of edits) {
      if (!this.buffers.has(p)) {
        await this.open(p);
        await this.open(path);
      }
      const b = this.buffers.get(p);
      if (!b) continue;
      if (b === this.current) this.view.dispatch({ changes: toChanges(this.view.state.doc, changes) });
      else b.state = b.state.update({ changes: toChanges(b.state.doc, changes) }).state;
      void this.lsp.sync(p, (b === this.current ? this.view.state : b.state).doc.toString());
    }
    this.markDirty();
    toast(`Renamed in ${edits.size} file${edits.size === 1 ? "" : "s"}; save them to keep it.`, "ok");
  }

  private async newOption(): Promise<void> {
    await this.newOptionDialog.show();
  }


  /// React to a file written by another client or changed on disk (`by: "disk"`: a checkout,
  /// another editor): a buffer without unsaved edits takes the new text, one with edits asks
  /// which to keep (showBanner).
  fileEvent(event: FileEvent): void {
    void this.refreshFiles();
    const b = this.buffers.get(event.path);
    if (!b || event.version === b.version) return;
    if (event.deleted) {
      toast(`${event.path} was deleted on disk.`, "error");
      return;
    }
    const where = event.by === "disk" ? "on disk" : "by another client";
    if (!this.isDirty(b)) {
      void readFile(b.path).then((file) => {
        b.version = file.version;
        b.saved = file.text;
        b.conflict = null;
        this.replaceText(b, file.text);
        this.markDirty();
        if (b === this.current) this.showBanner();
        toast(`${b.path} changed ${where}: the editor shows the new text.`, "info");
      });
    } else {
      b.conflict = { version: event.version ?? "" };
      if (b === this.current) this.showBanner();
      toast(`${b.path} changed ${where} while you have unsaved edits: keep yours or take theirs.`, "error");
    }
  }

  compileEvent(event: CompileEvent): void {
    void event;
    void this.refreshCounts(); // every set's latest compile, as the status has them
  }

  render(changes: Set<SessionEvent>): void {
    if (changes.has("hello")) {
      if (!this.files.length) void this.refreshFiles();
      if (this.current && !this.isDirty(this.current)) void this.refreshCounts();
    }
  }

  /// The editor view (tests and the keyboard map focus it).
  get editorView(): EditorView {
    return this.view;
  }
}
