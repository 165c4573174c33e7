/// The changes dialog: what a new generation (a hot reload, a reset, a fork) changed, opened
/// from its mark in the timeline. Per behavior file the unified diff of its text before and
/// after (the server keeps the sources of recent generations, `GET /api/generations/{n}/diff`).
import { type GenerationDiff, generationDiff } from "../api";
import { h } from "../ui";

/// What the dialog says about one mark: its generation, why it started and when.
export interface Mark {
  gen: number;
  reason: string;
  /// Behavior time of its first tick (ms).
  t: number;
}

export class ChangesDialog {
  readonly element: HTMLDialogElement;
  private readonly title: HTMLElement;
  private readonly body: HTMLElement;
  private asked = 0;
  /// Opens the structural view of a generation (panels/compare.ts) beside the text diff; null: none.
  onStructure: ((gen: number) => void) | null = null;

  constructor(private readonly fetchDiff: (n: number) => Promise<GenerationDiff> = generationDiff) {
    this.title = h("h2");
    this.body = h("div.changes-body");
    this.element = h(
      "dialog.changes",
      { "aria-label": "What changed" },
      this.title,
      this.body,
      h("form", { method: "dialog" }, h("div.dialog-buttons", {}, h("button.primary", {}, "Close"))),
    );
  }

  /// Open the dialog for `mark` and fill it when the server answers.
  async show(mark: Mark, clock: (ms: number) => string): Promise<void> {
    const asked = ++this.asked;
    this.title.textContent = `${label(mark.reason)} at t = ${clock(mark.t)} (generation ${mark.gen})`;
    this.body.replaceChildren(h("p.muted", {}, "loading…"));
    if (!this.element.open) this.element.showModal();
    let diff: GenerationDiff;
    try {
      diff = await this.fetchDiff(mark.gen);
    } catch (error) {
      if (asked === this.asked) this.body.replaceChildren(h("p.muted", {}, `No changes to show: ${(error as Error).message}`));
      return;
    }
    if (asked !== this.asked) return;
    if (!diff.files.length) {
      this.body.replaceChildren(h("p.muted", {}, "No behavior file changed."));
      return;
    }
    const structure = this.onStructure;
    this.body.replaceChildren(
      h(
        "p",
        {},
        `${diff.files.length} file${diff.files.length === 1 ? "" : "s"} changed since generation ${diff.previous}:`,
        ...(structure ? [" ", h("button.structure", { title: "What changed in the options, states and transitions, drawn", onclick: () => structure(mark.gen) }, "Structural view…")] : []),
      ),
      ...diff.files.map((f) =>
        h(
          "section.changed-file",
          { "data-path": f.path },
          h("h3", {}, h("code", {}, f.path), ` ${f.change}`, h("span.muted", {}, ` · ${f.program}`)),
          h("pre.diff", {}, ...f.diff.split("\n").map((line) => h(`span.${lineKind(line)}`, {}, `${line}\n`))),
        ),
      ),
    );
  }
}

function label(reason: string): string {
  if (reason === "reload") return "Hot reload";
  if (reason === "reset") return "Reset";
  if (reason === "host_gone") return "A host went away";
  if (reason === "host_back") return "A host attached again";
  return reason.charAt(0).toUpperCase() + reason.slice(1);
}

function lineKind(line: string): string {
  if (line.startsWith("+++") || line.startsWith("---")) return "head";
  if (line.startsWith("@@")) return "hunk";
  if (line.startsWith("+")) return "add";
  if (line.startsWith("-")) return "del";
  return "same";
}
