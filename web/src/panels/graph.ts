/// The option graph of the selected robot (server SVG) with the live activation path: active
/// options, basic behaviors and the calls between them carry the class `active`; nothing is laid
/// out on a tick. Search (/) marks matching options, Enter opens the first; J jumps to the
/// deepest active option; a click on an option opens it in the option view.
import { graphSvg } from "../api";
import { pathParents } from "../protocol";
import type { Session, SessionEvent } from "../session";
import { h } from "../ui";
import { exportMenu, type PictureTarget } from "./exportmenu";
import { SvgView } from "./svgview";

export class GraphPanel {
  readonly element: HTMLElement;
  readonly search: HTMLInputElement;
  private readonly view = new SvgView("Option graph: drag to pan, wheel to zoom");
  private readonly status: HTMLElement;
  /// says when the graph is the one below a forced root rather than the agent's
  private readonly rootNote: HTMLElement;
  private key = "";
  private loading = "";
  private deepest: string | null = null;
  private lastShape = "";

  constructor(
    private readonly session: Session,
    private readonly openOption: (id: number) => void,
    private readonly openBehavior: (id: number) => void,
  ) {
    this.search = h("input.search", { type: "search", placeholder: "Find option…  (/)", "aria-label": "Find option" });
    this.search.addEventListener("input", () => this.mark());
    this.search.addEventListener("keydown", (ev) => {
      if (ev.key === "Enter") {
        const first = this.matches()[0];
        if (first) {
          this.view.centerOn(first);
          this.openOption(Number(first.slice("option_".length)));
        }
      } else if (ev.key === "Escape") {
        this.search.value = "";
        this.mark();
        this.view.element.focus();
      }
    });
    this.status = h("span.muted");
    this.rootNote = h("span.graph-root");
    const toolbar = h(
      "div.toolbar",
      {},
      this.search,
      h("button", { title: "Jump to the active option (J)", onclick: () => this.jump() }, "Jump to active"),
      h("button", { title: "Fit (F)", onclick: () => this.view.fit() }, "Fit"),
      h("button", { title: "Zoom in (+)", onclick: () => this.view.zoomBy(1.25) }, "+"),
      h("button", { title: "Zoom out (−)", onclick: () => this.view.zoomBy(0.8) }, "−"),
      exportMenu(() => this.pictureTarget(), "the option graph"),
      this.status,
      this.rootNote,
    );
    this.element = h("div.panel.graph-panel", {}, toolbar, this.view.element);
    this.view.onClick = (id) => {
      if (id.startsWith("option_")) this.openOption(Number(id.slice(7)));
      else if (id.startsWith("behavior_")) this.openBehavior(Number(id.slice(9)));
    };
  }

  private matches(): string[] {
    const q = this.search.value.trim().toLowerCase();
    if (!q) return [];
    const index = this.session.indexOf(this.session.selectedRobot);
    const out: string[] = [];
    for (const o of index?.description.options ?? []) if (o.name.toLowerCase().includes(q) && this.view.has(`option_${o.id}`)) out.push(`option_${o.id}`);
    return out;
  }

  private mark(): void {
    const m = this.matches();
    this.view.setClasses("match", m);
    this.view.element.classList.toggle("searching", this.search.value.trim() !== "");
    this.status.textContent = this.search.value.trim() ? `${m.length} match${m.length === 1 ? "" : "es"}` : "";
  }

  /// Called after a new graph is shown (the coverage overlay of panels/coverage.ts re-applies).
  onShown: () => void = () => {};

  /// Make exactly `ids` carry class `name` (an overlay such as coverage), with hover texts by id.
  overlay(name: string, ids: Iterable<string>, titles: Map<string, string>): void {
    this.view.setClasses(name, ids);
    for (const [id, text] of titles) {
      const el = this.view.elementById(id);
      if (!el) continue;
      let title = el.querySelector(":scope > title");
      if (!title) el.prepend((title = document.createElementNS("http://www.w3.org/2000/svg", "title")));
      title.textContent = text;
    }
  }

  /// Centre the deepest active option.
  jump(): void {
    if (this.deepest) this.view.centerOn(this.deepest);
  }

  /// The XABSL agent whose option graph to show: the one whose root the robot runs; while an
  /// option is forced as the robot's root, the graph below that option.
  private graphKey(): { program: string; agent: string | undefined; root?: string } | null {
    const session = this.session;
    const program = session.programOf(session.selectedRobot);
    const index = session.indexOf(session.selectedRobot);
    if (!program || !index) return null;
    const robot = session.robotInView();
    const forced = robot?.forced;
    if (forced && forced[0] === 0) {
      const name = index.optionById.get(forced[1])?.name;
      if (name) return { program, agent: undefined, root: name };
    }
    const root = robot?.path[0];
    const rootName = root?.kind === "option" ? index.optionById.get(root.option)?.name : undefined;
    const agents = index.description.agents;
    const agent = agents.find((a) => a.root === rootName) ?? agents[0];
    return { program, agent: agent?.name };
  }

  /// The picture of the graph shown (Export): the agent's graph or the one below the forced root.
  private pictureTarget(): PictureTarget | null {
    const key = this.graphKey();
    if (!key) return null;
    const seq = this.session.view?.seq;
    const robot = this.session.robotInView();
    return {
      path: `picture/${encodeURIComponent(key.program)}`,
      params: key.root ? { root: key.root } : { agent: key.agent },
      tick: robot?.path.length && seq !== undefined ? { robot: this.session.selectedRobot, seq } : undefined,
    };
  }

  render(changes: Set<SessionEvent>): void {
    const key = this.graphKey();
    const k = key ? `${key.program}|${key.agent ?? ""}|${key.root ?? ""}|${this.session.hello?.generation ?? 0}` : "";
    if (k !== this.key && k !== this.loading) {
      if (!key) {
        this.key = k;
        this.view.clear(this.session.hello ? "This robot has no XABSL behavior." : "Connecting…");
      } else {
        this.loading = k;
        this.rootNote.textContent = key.root ? `forced root: ${key.root}` : "";
        graphSvg(key.program, undefined, key.agent, key.root)
          .then((svg) => {
            if (this.loading !== k) return;
            this.loading = "";
            this.key = k;
            this.lastShape = "";
            if (!this.view.show(svg)) this.view.clear("The server sent an unreadable graph.");
            this.mark();
            this.highlight(true);
            this.onShown();
            this.view.focusIfTiny(this.deepest);
          })
          .catch((error: Error) => {
            if (this.loading !== k) return;
            this.loading = "";
            this.key = k;
            this.view.clear(`No option graph: ${error.message}`);
          });
      }
    }
    this.highlight(changes.has("select") || changes.has("cursor"));
  }

  private highlight(force: boolean): void {
    const robot = this.session.robotInView();
    const path = robot?.path ?? [];
    const shape = robot?.shape ?? "";
    if (!force && shape === this.lastShape) return;
    this.lastShape = shape;
    const ids: string[] = [];
    const parents = pathParents(path);
    let deepest: string | null = null;
    let deepestDepth = -1;
    // The graph is the current generation's: a tick before a reload is shown by option names.
    const to = this.session.currentIds(this.session.selectedRobot);
    const optionOf = (n: { option: number }): number => to.option(n.option);
    path.forEach((n, i) => {
      const id = n.kind === "option" ? `option_${optionOf(n)}` : `behavior_${to.behavior(n.behavior)}`;
      ids.push(id);
      if (n.kind === "option" && n.depth > deepestDepth) {
        deepest = id;
        deepestDepth = n.depth;
      }
      const parent = path[parents[i] ?? -1];
      if (parent?.kind === "option") ids.push(`call_${optionOf(parent)}_${n.kind === "option" ? `o${optionOf(n)}` : `b${to.behavior(n.behavior)}`}`);
    });
    this.deepest = deepest;
    this.view.setClasses("active", ids);
    const root = path[0];
    this.view.setClasses("root", root ? [root.kind === "option" ? `option_${optionOf(root)}` : `behavior_${to.behavior(root.behavior)}`] : []);
  }
}
