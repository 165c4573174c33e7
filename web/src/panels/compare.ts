/// The Compare view: two versions of a behavior set side by side, compared as programs (not text).
/// Opened from the "Compare…" button, or from a reload mark's changes dialog (panels/changes.ts)
/// for the two generations around it. The old version is a git revision (`git:HEAD`), a folder or
/// agents file of the example, or the behavior a recording ran (`recording:NAME`: a fork's
/// original); the new one is the running behavior (or another of those). The server
/// (`GET api/compare`, `GET api/compare/generations/{n}`) answers the changes, each with the
/// file:line of both sides, and the option graph and every changed state machine with the
/// changes marked; given a recording of each version, the option graph's nodes are coloured by
/// the change of their time share (blue: more time, rose: less; docs/compare.md).
import { apiJson } from "../api";
import { formatClock, h } from "../ui";
import { SvgView } from "./svgview";

export interface Where {
  file: string;
  line: number;
  col: number;
}

export interface Change {
  kind: string;
  change: "added" | "removed" | "renamed" | "changed";
  name: string;
  option: string | null;
  state: string | null;
  path: string[] | null;
  details: Array<{ field: string; old: string | null; new: string | null }>;
  old: Where | null;
  new: Where | null;
}

export interface DiffDocument {
  format: string;
  old: { spec?: string; title?: string; commit?: string | null };
  new: { spec?: string; title?: string; commit?: string | null };
  counts: Record<string, number>;
  changes: Change[];
}

export interface Share {
  a: number;
  b: number;
  change: number;
  significant: boolean;
  only_in: "a" | "b" | null;
}

export interface Comparison {
  program: string;
  diff: DiffDocument;
  svg: { option_graph: string; state_machines: Record<string, string> } | null;
  note: string | null;
  shares?: Record<string, Share> | null;
}

const SIGN: Record<string, string> = { added: "+", removed: "−", changed: "~", renamed: "→" };

/// Where a change is: `option/state`, the option, or the program-level part's name.
export function changePlace(c: Change): string {
  if (c.option === null) return c.name;
  return c.state === null ? c.option : `${c.option}/${c.state}`;
}

/// What changed, in one line: the transition's path and target, or each field old → new.
export function changeSummary(c: Change): string {
  const parts: string[] = [];
  if (c.kind === "transition" && c.path) {
    const target = c.details.find((d) => d.field === "target");
    const to = target ? (c.change === "removed" ? target.old : target.new) : null;
    parts.push(`[${c.path.join(" && ") || "always"}]${to && c.change !== "changed" ? ` → ${to}` : ""}`);
  } else if (!["option", "state", "condition"].includes(c.kind)) parts.push(c.name);
  for (const d of c.details) {
    if (c.kind === "transition" && d.field === "target" && c.change !== "changed") continue;
    if (d.old !== null && d.new !== null) parts.push(`${d.field}: ${d.old} → ${d.new}`);
    else if (d.new !== null) parts.push(`${d.field}: ${d.new}`);
    else if (d.old !== null) parts.push(`${d.field} was: ${d.old}`);
  }
  return parts.join("; ");
}

/// `file:line` of a side (empty when the part is not there).
export function place(w: Where | null): string {
  return w ? `${w.file}:${w.line}` : "";
}

/// The query of `GET api/compare` (the recordings only as a pair).
export function compareQuery(program: string, old: string, next: string, recording = "", against = ""): string {
  const q = new URLSearchParams({ program, old, new: next || "running" });
  if (recording && against) {
    q.set("recording", recording);
    q.set("against", against);
  }
  return `compare?${q.toString()}`;
}

/// The options whose state machine the view can show, in the order their changes come.
export function changedOptions(comparison: Comparison): string[] {
  const drawn = comparison.svg?.state_machines ?? {};
  const seen: string[] = [];
  for (const c of comparison.diff.changes) if (c.option && c.option in drawn && !seen.includes(c.option)) seen.push(c.option);
  return seen;
}

/// One robot's first divergence of two recordings (`GET api/compare/diverge`, `xabsl diverge --json`).
export interface Divergence {
  agent: string;
  seq: number;
  t: number;
  path_a: string[];
  path_b: string[];
  option: string | null;
  why_a: { decided_in: string; target: string; stay: boolean } | null;
  why_b: { decided_in: string; target: string; stay: boolean } | null;
}

interface DivergenceReport {
  a: string;
  b: string;
  earliest: Divergence | null;
  divergences: Record<string, Divergence | null>;
}

/// A decision as one phrase: `far → near`, `far stays`.
function decided(why: Divergence["why_a"]): string {
  return why ? (why.stay ? `${why.decided_in} stays` : `${why.decided_in} → ${why.target}`) : "?";
}

export class CompareView {
  /// Where the two recordings first act differently (null: they do not, or none were chosen): the timeline marks it.
  onDivergence: (divergence: Divergence | null) => void = () => undefined;
  private readonly divergence: HTMLElement;
  readonly button: HTMLButtonElement;
  readonly element: HTMLDialogElement;
  private readonly programSelect: HTMLSelectElement;
  private readonly oldInput: HTMLInputElement;
  private readonly newInput: HTMLInputElement;
  private readonly recordingSelect: HTMLSelectElement;
  private readonly againstSelect: HTMLSelectElement;
  private readonly status: HTMLElement;
  private readonly list: HTMLElement;
  private readonly machineTitle: HTMLElement;
  readonly graph = new SvgView("Option graph, changes marked");
  readonly machine = new SvgView("State machine, changes marked");
  private shown: Comparison[] = [];
  private asked = 0;

  constructor(private readonly programs: () => string[]) {
    this.programSelect = h("select.compare-program", { "aria-label": "behavior set" });
    this.oldInput = h("input.compare-old", { type: "text", value: "git:HEAD", size: 28, "aria-label": "old version", list: "compare-specs" });
    this.newInput = h("input.compare-new", { type: "text", value: "running", size: 16, "aria-label": "new version", list: "compare-specs" });
    this.recordingSelect = h("select.compare-recording", { "aria-label": "recording of the new version" });
    this.againstSelect = h("select.compare-against", { "aria-label": "recording of the old version" });
    this.status = h("p.muted.compare-status");
    this.divergence = h("div.compare-diverge");
    this.list = h("div.compare-list");
    this.machineTitle = h("h3.compare-machine-title");
    const form = h(
      "form.compare-form",
      { onsubmit: (ev: Event) => { ev.preventDefault(); void this.run(); } },
      h("label", {}, "Behavior set ", this.programSelect),
      h("label", {}, "Old ", this.oldInput),
      h("label", {}, "New ", this.newInput),
      h("label", { title: "Colour the option graph by the change of time share between two recordings" }, "Time share: new ", this.recordingSelect, " old ", this.againstSelect),
      h("button.primary.compare-run", { type: "submit" }, "Compare"),
      h("datalist#compare-specs", {}, ...["running", "git:HEAD", "git:HEAD~1"].map((v) => h("option", { value: v }))),
    );
    this.element = h(
      "dialog.compare",
      { "aria-label": "Compare versions" },
      h("h2", {}, "Compare versions"),
      form,
      this.status,
      this.divergence,
      h(
        "div.compare-body",
        {},
        this.list,
        h("div.compare-pictures", {}, h("div.compare-graph", {}, this.graph.element), this.machineTitle, h("div.compare-machine", {}, this.machine.element)),
      ),
      h("form", { method: "dialog" }, h("div.dialog-buttons", {}, h("button", {}, "Close"))),
    );
    this.button = h("button#compare", { title: "Compare the running behavior with a git revision, a folder or a recording's", onclick: () => void this.open() }, "Compare…");
    this.graph.onClick = (id) => this.clickGraph(id);
  }

  private attach(): void {
    const keys = this.programs();
    const chosen = this.programSelect.value;
    if (this.programSelect.options.length !== keys.length || [...this.programSelect.options].some((o, i) => o.value !== keys[i])) {
      this.programSelect.replaceChildren(...keys.map((k) => h("option", { value: k }, k)));
      if (keys.includes(chosen)) this.programSelect.value = chosen;
    }
    if (!this.element.isConnected) document.body.append(this.element);
    if (!this.element.open) this.element.showModal();
  }

  /// Open the form (the first behavior set chosen) with the library's recordings to pick from.
  async open(): Promise<void> {
    this.attach();
    try {
      const listing = await apiJson<{ recordings: Array<{ name: string; error?: string | null }> }>("GET", "recordings");
      const names = listing.recordings.filter((r) => !r.error).map((r) => r.name);
      for (const select of [this.recordingSelect, this.againstSelect]) {
        const was = select.value;
        select.replaceChildren(h("option", { value: "" }, "—"), ...names.map((n) => h("option", { value: n }, n)));
        if (names.includes(was)) select.value = was;
      }
      const datalist = this.element.querySelector("#compare-specs");
      datalist?.replaceChildren(...["running", "git:HEAD", "git:HEAD~1", ...names.map((n) => `recording:${n}`)].map((v) => h("option", { value: v })));
    } catch {
      /* no library: the time-share colouring is not offered */
    }
  }

  private async run(): Promise<void> {
    const asked = ++this.asked;
    this.status.textContent = "comparing…";
    try {
      const answer = await apiJson<Comparison>(
        "GET",
        compareQuery(this.programSelect.value, this.oldInput.value.trim(), this.newInput.value.trim(), this.recordingSelect.value, this.againstSelect.value),
      );
      if (asked === this.asked) this.render([answer]);
    } catch (e) {
      if (asked === this.asked) this.status.textContent = `Compare: ${(e as Error).message}`;
    }
    if (asked === this.asked) await this.diverge(asked);
  }

  /// Where the two recordings chosen first act differently, per robot; the earliest is marked on the timeline.
  private async diverge(asked: number): Promise<void> {
    const recording = this.recordingSelect.value;
    const against = this.againstSelect.value;
    this.divergence.replaceChildren();
    if (!recording || !against) {
      this.onDivergence(null);
      return;
    }
    try {
      const q = new URLSearchParams({ recording, against });
      const report = await apiJson<DivergenceReport>("GET", `compare/diverge?${q.toString()}`);
      if (asked !== this.asked) return;
      const first = report.earliest;
      const rows = Object.values(report.divergences)
        .filter((d): d is Divergence => d !== null)
        .sort((x, y) => x.seq - y.seq)
        .map((d) => h("li", {}, `${d.agent}: tick ${d.seq} (${formatClock(d.t)}), ${d.option ?? "?"}: ${report.a} ${decided(d.why_a)} · ${report.b} ${decided(d.why_b)}`));
      this.divergence.replaceChildren(
        h("strong", {}, first ? `First divergence: ${first.agent} at ${formatClock(first.t)} (tick ${first.seq})` : `${report.a} and ${report.b} act alike in every tick they share`),
        h("ol.compare-diverge-list", {}, ...rows),
      );
      this.onDivergence(first);
    } catch (e) {
      if (asked === this.asked) this.divergence.textContent = `Divergence: ${(e as Error).message}`;
      this.onDivergence(null);
    }
  }

  /// The structural view of generation `n` against `n - 1` (a reload mark of the timeline).
  async showGeneration(n: number): Promise<void> {
    const asked = ++this.asked;
    this.attach(); // the form keeps its versions: the status line names the two generations
    this.status.textContent = "comparing…";
    try {
      const answer = await apiJson<{ programs: Comparison[] }>("GET", `compare/generations/${n}`);
      if (asked === this.asked) this.render(answer.programs);
    } catch (e) {
      if (asked === this.asked) this.status.textContent = `No structural view: ${(e as Error).message}`;
    }
  }

  private render(comparisons: Comparison[]): void {
    this.shown = comparisons;
    const total = comparisons.reduce((n, c) => n + c.diff.changes.length, 0);
    const first = comparisons[0];
    if (!first) {
      this.status.textContent = "No behavior set changed.";
      this.list.replaceChildren();
      this.graph.clear("");
      this.machine.clear("");
      return;
    }
    const notes = comparisons.map((c) => c.note).filter(Boolean);
    this.status.textContent =
      `OLD ${first.diff.old.spec ?? ""}  ·  NEW ${first.diff.new.spec ?? ""}: ${total} change${total === 1 ? "" : "s"}` +
      (first.shares ? " · option graph coloured by the change of time share (blue more, rose less)" : "") +
      (notes.length ? ` · ${notes.join("; ")}` : "");
    this.list.replaceChildren(
      ...comparisons.map((c) =>
        h(
          "section.compare-program-changes",
          { "data-program": c.program },
          h("h3", {}, c.program),
          c.diff.changes.length
            ? h(
                "table.compare-changes",
                {},
                h("thead", {}, h("tr", {}, ...["", "kind", "where", "what", "old", "new"].map((t) => h("th", {}, t)))),
                h(
                  "tbody",
                  {},
                  ...c.diff.changes.map((change) =>
                    h(
                      `tr.change-${change.change}`,
                      { "data-option": change.option ?? "", onclick: () => change.option && this.showMachine(c, change.option) },
                      h("td.sign", { title: change.change }, SIGN[change.change] ?? "?"),
                      h("td", {}, change.kind),
                      h("td", {}, changePlace(change)),
                      h("td", {}, changeSummary(change)),
                      h("td.where", {}, place(change.old)),
                      h("td.where", {}, place(change.new)),
                    ),
                  ),
                ),
              )
            : h("p.muted", {}, "The two versions are the same behavior."),
        ),
      ),
    );
    if (first.svg) this.graph.show(first.svg.option_graph);
    else this.graph.clear(first.note ?? "no drawing");
    const option = changedOptions(first)[0];
    if (option) this.showMachine(first, option);
    else {
      this.machineTitle.textContent = "";
      this.machine.clear("no state machine changed");
    }
  }

  private showMachine(comparison: Comparison, option: string): void {
    const svg = comparison.svg?.state_machines[option];
    this.machineTitle.textContent = svg ? `option ${option}` : `option ${option} (not drawn: removed, or only renamed)`;
    if (svg) this.machine.show(svg);
    else this.machine.clear("");
  }

  /// A click on an option of the graph shows its state machine when it changed.
  private clickGraph(id: string): void {
    const comparison = this.shown[0];
    const node = this.graph.elementById(id);
    const name = node?.querySelector("title")?.textContent?.replace(/^o:/, "");
    if (comparison && name && comparison.svg?.state_machines[name]) this.showMachine(comparison, name);
  }
}
