/// The behavior editor: a file tree of the behavior folders, CodeMirror with XABSL highlighting,
/// completion from the IR (reconfigured on every hello), diagnostics as you type (compiled on
/// the server, nothing saved), go to definition (F12, Ctrl+click), find references (Shift+F12),
/// save (Ctrl+S) = PUT with If-Match -> hot reload, conflicts shown, never overwritten silently,
/// and a new option (the New option dialog, panels/newoption.ts).
import { autocompletion, closeBrackets, closeBracketsKeymap, completionKeymap } from "@codemirror/autocomplete";
import { defaultKeymap, history, historyKeymap, indentWithTab } from "@codemirror/commands";
import { bracketMatching, HighlightStyle, indentOnInput, syntaxHighlighting } from "@codemirror/language";
import { lintGutter, lintKeymap } from "@codemirror/lint";
import { highlightSelectionMatches, searchKeymap } from "@codemirror/search";
import { Compartment, EditorSelection, EditorState } from "@codemirror/state";
import { drawSelection, EditorView, highlightActiveLine, highlightActiveLineGutter, keymap, lineNumbers } from "@codemirror/view";
import { tags as t } from "@lezer/highlight";
import { compile, type FileEntry, listFiles, readFile, writeFile } from "../api";
import { diagnosticsFor, homeProgram, type SetDiagnostic } from "../behaviorsets";
import type { DescriptionIndex, Span } from "../description";
import type { CompileEvent, FileEvent } from "../protocol";
import type { Session, SessionEvent } from "../session";
import { h, toast } from "../ui";
import { xabslCompletion } from "../xabsl/complete";
import { xabsl } from "../xabsl/language";
import { samePath, type ServerDiagnostic, xabslLinter } from "../xabsl/lint";
import { definitionOf, findReferences, wordAt } from "../xabsl/navigate";
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


interface Buffer {
  path: string;
  state: EditorState;
  version: string;
  saved: string;
  conflict: { version: string } | null;
}

export class EditorPanel {
  readonly element: HTMLElement;
  private readonly tree: HTMLElement;
  private readonly view: EditorView;
  private readonly status: HTMLElement;
  private readonly banner: HTMLElement;
  private readonly refs: HTMLElement;
  private readonly title: HTMLElement;
  private readonly completion = new Compartment();
  private readonly buffers = new Map<string, Buffer>();
  private files: FileEntry[] = [];
  private current: Buffer | null = null;
  private lastDiagnostics: readonly ServerDiagnostic[] = [];
  private completionGen = -2;

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
      h("button", { title: "Create an option: name, parameters, folder; adds its include line to the agents file", onclick: () => void this.newOption() }, "New option…"),
    );
    this.element = h(
      "div.panel.editor-panel",
      {},
      h("div.editor-side", {}, h("div.section-title", {}, "Files"), this.tree),
      h("div.editor-main", {}, toolbar, this.banner, host, this.refs, this.status),
    );
    this.view.contentDOM.setAttribute("aria-label", "XABSL source");
  }

  private index(): DescriptionIndex | null {
    const session = this.session;
    const path = this.current?.path;
    if (path) {
      const entry = this.files.find((f) => f.path === path);
      const home = homeProgram(path, entry?.programs ?? []);
      for (const program of home ? [home, ...(entry?.programs ?? [])] : (entry?.programs ?? [])) {
        const index = session.programs.get(program);
        if (index) return index;
      }
    }
    return session.indexOf(session.selectedRobot) ?? session.programs.values().next().value ?? null;
  }

  private makeState(doc: string, path: string): EditorState {
    return EditorState.create({
      doc,
      extensions: [
        lineNumbers(),
        highlightActiveLineGutter(),
        history(),
        drawSelection(),
        indentOnInput(),
        bracketMatching(),
        closeBrackets(),
        highlightActiveLine(),
        highlightSelectionMatches(),
        autocompletion({ activateOnTyping: true }),
        xabsl(),
        syntaxHighlighting(highlight),
        this.completion.of(xabslCompletion(this.index()?.description ?? null)),
        lintGutter(),
        xabslLinter(
          () => (path ? path : null),
          async (p, text) => this.own(p, (await compile(p, text)).diagnostics),
          (result) => this.showCompile(result),
        ),
        keymap.of([
          { key: "Mod-s", preventDefault: true, run: () => (void this.save(), true) },
          { key: "F12", run: () => (this.goToDefinition(), true) },
          { key: "Shift-F12", run: () => (void this.references(), true) },
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
          if (u.docChanged) this.markDirty();
        }),
      ],
    });
  }

  private isDirty(b: Buffer | null): boolean {
    if (!b) return false;
    const state = b === this.current ? this.view.state : b.state;
    return state.doc.toString() !== b.saved;
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
    this.completionGen = -2;
    this.syncCompletion();
    this.showBanner();
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

  private syncCompletion(): void {
    const gen = this.session.hello?.generation ?? -1;
    if (gen === this.completionGen) return;
    this.completionGen = gen;
    this.view.dispatch({ effects: this.completion.reconfigure(xabslCompletion(this.index()?.description ?? null)) });
  }

  private showCompile(result: readonly ServerDiagnostic[] | Error): void {
    if (result instanceof Error) {
      this.status.className = "editor-status warn";
      this.status.textContent = `Cannot check: ${result.message}`;
      return;
    }
    this.lastDiagnostics = result;
    this.renderStatus();
  }

  private renderStatus(extra?: string): void {
    const result = this.lastDiagnostics;
    const errors = result.filter((d) => d.severity === "error");
    const warnings = result.filter((d) => d.severity === "warning");
    const path = this.current?.path ?? "";
    const elsewhere = result.filter((d) => !samePath(d.span?.file ?? d.file, path));
    const items: Array<HTMLElement | string> = [];
    items.push(h("strong", {}, errors.length ? `✗ ${errors.length} error${errors.length > 1 ? "s" : ""}` : "✓ compiles"));
    if (warnings.length) items.push(`, ${warnings.length} warning${warnings.length > 1 ? "s" : ""}`);
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

  private showBanner(): void {
    const b = this.current;
    if (!b?.conflict) {
      this.banner.hidden = true;
      return;
    }
    this.banner.hidden = false;
    this.banner.replaceChildren(
      h("strong", {}, "Conflict: "),
      `${b.path} was changed on disk by someone else since you opened it. Your text is still here, unsaved.`,
      h("button", { onclick: () => void this.reloadFromDisk() }, "Discard mine, load theirs"),
      h("button.danger", { onclick: () => void this.save(true) }, "Overwrite theirs with mine"),
    );
  }

  private async reloadFromDisk(): Promise<void> {
    const b = this.current;
    if (!b) return;
    const file = await readFile(b.path);
    b.version = file.version;
    b.saved = file.text;
    b.conflict = null;
    this.view.dispatch({ changes: { from: 0, to: this.view.state.doc.length, insert: file.text } });
    this.showBanner();
    this.markDirty();
  }

  /// Save the current file: PUT with If-Match; the server compiles and hot-reloads.
  async save(overwrite = false): Promise<void> {
    const b = this.current;
    if (!b) return;
    const text = this.view.state.doc.toString();
    const version = overwrite && b.conflict ? b.conflict.version : b.version;
    try {
      const { status, result, conflict } = await writeFile(b.path, text, version);
      if (conflict) {
        b.conflict = conflict;
        this.showBanner();
        toast(`Not saved: ${b.path} changed on disk. Choose what to keep.`, "error");
        return;
      }
      b.version = result.version;
      b.saved = text;
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
    const state = this.view.state;
    const text = state.doc.toString();
    const w = wordAt(text, state.selection.main.head);
    if (!w) return;
    const def = definitionOf(w.word, text, this.index());
    if (!def) {
      toast(`No definition found for ${w.word}`, "info");
      return;
    }
    if (def.kind === "local") {
      this.view.dispatch({ selection: EditorSelection.single(def.from, def.to), effects: EditorView.scrollIntoView(def.from, { y: "center" }) });
    } else {
      this.openSpan(def.span);
    }
  }

  private async references(): Promise<void> {
    const state = this.view.state;
    const w = wordAt(state.doc.toString(), state.selection.main.head);
    if (!w) return;
    const texts = new Map<string, string>();
    await Promise.all(
      this.files.map(async (f) => {
        const open = this.buffers.get(f.path);
        if (open) texts.set(f.path, (open === this.current ? this.view.state : open.state).doc.toString());
        else {
          try {
            texts.set(f.path, (await readFile(f.path)).text);
          } catch {
            /* a file deleted meanwhile */
          }
        }
      }),
    );
    const refs = findReferences(w.word, texts);
    this.refs.hidden = false;
    this.refs.replaceChildren(
      h("div.section-title", {}, `${refs.length} reference${refs.length === 1 ? "" : "s"} to ${w.word}`, h("button.icon", { title: "Close", onclick: () => (this.refs.hidden = true) }, "×")),
      ...refs.map((r) => h("button.ref", { onclick: () => void this.open(r.path, { line: r.line, col: r.col }) }, h("span.ref-loc", {}, `${r.path}:${r.line}`), h("code", {}, r.lineText))),
    );
  }

  private async newOption(): Promise<void> {
    await this.newOptionDialog.show();
  }


  /// React to other clients' writes: reload a clean buffer, flag a dirty one.
  fileEvent(event: FileEvent): void {
    void this.refreshFiles();
    const b = this.buffers.get(event.path);
    if (!b || event.version === b.version) return;
    if (event.deleted) {
      toast(`${event.path} was deleted on disk.`, "error");
      return;
    }
    if (!this.isDirty(b)) {
      void readFile(b.path).then((file) => {
        b.version = file.version;
        b.saved = file.text;
        if (b === this.current) this.view.dispatch({ changes: { from: 0, to: this.view.state.doc.length, insert: file.text } });
        else b.state = this.makeState(file.text, b.path);
        this.markDirty();
      });
    } else {
      b.conflict = { version: event.version ?? "" };
      if (b === this.current) this.showBanner();
    }
  }

  compileEvent(event: CompileEvent): void {
    if (!event.ok && this.current) this.lastDiagnostics = this.own(this.current.path, (event.diagnostics as unknown as ServerDiagnostic[]).map((d) => ({ ...d, program: event.program })));
  }

  render(changes: Set<SessionEvent>): void {
    if (changes.has("hello")) {
      if (!this.files.length) void this.refreshFiles();
      this.syncCompletion();
    }
  }

  /// The editor view (tests and the keyboard map focus it).
  get editorView(): EditorView {
    return this.view;
  }
}
