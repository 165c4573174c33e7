/// The option graph of the selected robot (server SVG) with the live activation path: active
/// options, basic behaviors and the calls between them carry the class `active`, and with "Fade"
/// on everything else is faded; nothing is laid out on a tick.
///
/// A graph of more than `OVERVIEW_ABOVE` options opens grouped by source folder with every group
/// collapsed (the overview); a click on a group expands it, a click on an expanded folder's frame
/// collapses it again (the server lays each combination out once: engine/emit/groups.py).
/// Find (/) lists options and states by name across all options (find.ts): Enter jumps to the
/// first (an option: centred and marked here, its folder expanded if needed; a state: opened in
/// the option view), ↑/↓ choose, Shift+Enter opens an option in the option view. J jumps to the
/// deepest active option; a click on an option opens it in the option view.
import { graphGroups, graphSvg } from "../api";
import { type Found, find } from "../find";
import { GroupMap, OVERVIEW_ABOVE, type OptionGroup } from "../graphgroups";
import { pathParents } from "../protocol";
import type { Session, SessionEvent } from "../session";
import { h, toggleClass } from "../ui";
import { exportMenu, type PictureTarget } from "./exportmenu";
import { SvgView } from "./svgview";

/// Results shown under the search box.
const LISTED = 12;

export class GraphPanel {
  readonly element: HTMLElement;
  readonly search: HTMLInputElement;
  private readonly view = new SvgView("Option graph: drag to pan, wheel to zoom");
  private readonly status: HTMLElement;
  private readonly results: HTMLElement;
  private readonly groupButtons: HTMLElement;
  private readonly fadeBox: HTMLInputElement;
  /// says when the graph is the one below a forced root rather than the agent's
  private readonly rootNote: HTMLElement;
  private key = "";
  private loading = "";
  private deepest: string | null = null;
  private lastShape = "";
  /// Groups of the graph shown (null: the plain graph).
  private groups: GroupMap | null = null;
  /// Collapsed group keys by graph (program|agent|root), kept across reloads; absent: not grouped.
  private readonly collapsedBy = new Map<string, Set<string>>();
  /// Graphs shown before (the overview is opened by itself only the first time).
  private readonly opened = new Set<string>();
  private found: Found[] = [];
  private chosen = 0;
  /// What to centre and mark once the graph being loaded is shown.
  private pending: string | null = null;

  constructor(
    private readonly session: Session,
    private readonly openOption: (id: number) => void,
    private readonly openBehavior: (id: number) => void,
    private readonly openState: (option: number, state: number) => void = (option) => openOption(option),
  ) {
    this.search = h("input.search", { type: "search", placeholder: "Find option or state…  (/)", "aria-label": "Find option or state" });
    this.results = h("ol.find-results", { role: "listbox", hidden: true });
    this.search.addEventListener("input", () => {
      this.chosen = 0;
      this.mark();
    });
    this.search.addEventListener("keydown", (ev) => {
      if (ev.key === "Enter") {
        const target = this.found[this.chosen];
        if (target) this.go(target, ev.shiftKey);
      } else if (ev.key === "ArrowDown" || ev.key === "ArrowUp") {
        ev.preventDefault();
        const n = Math.min(this.found.length, LISTED);
        if (n) this.chosen = (this.chosen + (ev.key === "ArrowDown" ? 1 : n - 1)) % n;
        this.listResults();
      } else if (ev.key === "Escape") {
        this.search.value = "";
        this.mark();
        this.view.element.focus();
      }
    });
    this.search.addEventListener("blur", () => setTimeout(() => (this.results.hidden = true), 150));
    this.search.addEventListener("focus", () => this.listResults());
    this.status = h("span.muted");
    this.rootNote = h("span.graph-root");
    this.fadeBox = h("input", { type: "checkbox", checked: true, onchange: () => this.highlight(true) });
    this.groupButtons = h(
      "span.group-buttons",
      {},
      h("button", { title: "Group by folder, every folder collapsed", onclick: () => this.setCollapsed(new Set(this.groups?.groups.map((g) => g.key) ?? ["*"])) }, "Overview"),
      h("button", { title: "Every folder expanded (still framed by folder)", onclick: () => this.setCollapsed(new Set()) }, "Expand all"),
    );
    const toolbar = h(
      "div.toolbar",
      {},
      h("span.find-box", {}, this.search, this.results),
      h("button", { title: "Jump to the active option (J)", onclick: () => this.jump() }, "Jump to active"),
      h("button", { title: "Fit (F)", onclick: () => this.view.fit() }, "Fit"),
      h("button", { title: "Zoom in (+)", onclick: () => this.view.zoomBy(1.25) }, "+"),
      h("button", { title: "Zoom out (−)", onclick: () => this.view.zoomBy(0.8) }, "−"),
      this.groupButtons,
      h("label.fade-toggle", { title: "Fade what the selected robot does not run" }, this.fadeBox, " Fade"),
      exportMenu(() => this.pictureTarget(), "the option graph"),
      this.status,
      this.rootNote,
    );
    this.view.enableMinimap();
    this.element = h("div.panel.graph-panel", {}, toolbar, this.view.element);
    this.view.onClick = (id) => {
      if (id.startsWith("option_")) this.openOption(Number(id.slice(7)));
      else if (id.startsWith("behavior_")) this.openBehavior(Number(id.slice(9)));
      else if (id.startsWith("group_")) this.expand(Number(id.slice(6)));
      else if (id.startsWith("cluster_")) this.collapse(Number(id.slice(8)));
    };
  }

  private index() {
    return this.session.indexOf(this.session.selectedRobot);
  }

  /// The drawn element of option `id` (its collapsed group's node when it is in one).
  private optionNode(id: number): string {
    return this.groups ? this.groups.nodeId("option", id) : `option_${id}`;
  }

  private mark(): void {
    const q = this.search.value.trim();
    this.found = find(this.index()?.description.options ?? [], q, 500);
    const marked = new Set<string>();
    for (const f of this.found) marked.add(this.optionNode(f.option));
    this.view.setClasses("match", marked);
    this.view.element.classList.toggle("searching", q !== "");
    const options = this.found.filter((f) => f.kind === "option").length;
    const states = this.found.length - options;
    this.status.textContent = q ? `${options} option${options === 1 ? "" : "s"}, ${states} state${states === 1 ? "" : "s"}` : "";
    this.listResults();
  }

  private listResults(): void {
    const shown = this.found.slice(0, LISTED);
    this.results.hidden = shown.length === 0 || document.activeElement !== this.search;
    this.results.replaceChildren(
      ...shown.map((f, i) =>
        h(
          "li",
          {
            role: "option",
            class: i === this.chosen ? "chosen" : "",
            "data-kind": f.kind,
            // pointerdown, not click: the search box's blur would hide the list first
            onpointerdown: (ev: Event) => {
              ev.preventDefault();
              this.go(f, (ev as PointerEvent).shiftKey);
            },
          },
          h("span.found-kind", {}, f.kind),
          h("span.found-name", {}, f.name),
          f.kind === "state" ? h("span.muted", {}, ` in ${f.optionName}`) : null,
        ),
      ),
    );
  }

  /// Jump to a search result: an option is centred and marked in the graph (its folder expanded
  /// when collapsed; `open`: opened in the option view too), a state opened in the option view.
  private go(target: Found, open: boolean): void {
    this.results.hidden = true;
    if (target.kind === "state" && target.state !== undefined) {
      this.openState(target.option, target.state);
      return;
    }
    if (open) {
      this.openOption(target.option);
      return;
    }
    const id = `option_${target.option}`;
    const groups = this.groups;
    const n = groups?.groupOf("option", target.option);
    if (groups && n !== undefined && groups.isCollapsed(n)) {
      this.pending = id;
      this.expand(n);
    } else this.reveal(id);
  }

  /// Centre element `id` and mark it (class `found`) until the next search.
  private reveal(id: string): void {
    this.view.setClasses("found", [id]);
    this.view.centerOn(id);
  }

  private graphBase(): string {
    const key = this.graphKey();
    return key ? `${key.program}|${key.agent ?? ""}|${key.root ?? ""}` : "";
  }

  private setCollapsed(collapsed: Set<string>): void {
    const base = this.graphBase();
    if (!base) return;
    this.collapsedBy.set(base, collapsed);
    this.render(new Set());
  }

  private expand(n: number): void {
    const key = this.groups?.groups[n]?.key;
    const collapsed = this.collapsedBy.get(this.graphBase());
    if (key === undefined || !collapsed) return;
    this.pending ??= `cluster_${n}`;
    this.setCollapsed(new Set([...collapsed].filter((k) => k !== key)));
  }

  private collapse(n: number): void {
    const key = this.groups?.groups[n]?.key;
    const collapsed = this.collapsedBy.get(this.graphBase());
    if (key === undefined || !collapsed) return;
    this.pending = `group_${n}`;
    this.setCollapsed(new Set([...collapsed, key]));
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

  /// Centre the deepest active option (its folder's node while that is collapsed).
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

  /// The groups and the SVG of graph `key` as the user has it grouped (opening an overview for a
  /// graph of many options the first time it is shown).
  private async fetchGraph(key: { program: string; agent: string | undefined; root?: string }, base: string): Promise<{ svg: string; groups: GroupMap | null }> {
    let collapsed = this.collapsedBy.get(base);
    if (!collapsed && !this.opened.has(base)) {
      this.opened.add(base);
      const options = this.index()?.description.options.length ?? 0;
      if (options > OVERVIEW_ABOVE) this.collapsedBy.set(base, (collapsed = new Set(["*"])));
    }
    if (!collapsed) return { svg: await graphSvg(key.program, undefined, key.agent, key.root), groups: null };
    const list: OptionGroup[] = await graphGroups(key.program, key.agent, key.root);
    if (collapsed.has("*")) {
      collapsed = new Set(list.map((g) => g.key));
      this.collapsedBy.set(base, collapsed);
    }
    const groups = new GroupMap(list, collapsed);
    return { svg: await graphSvg(key.program, undefined, key.agent, key.root, groups.query()), groups };
  }

  render(changes: Set<SessionEvent>): void {
    const key = this.graphKey();
    const base = this.graphBase();
    const grouping = [...(this.collapsedBy.get(base) ?? ["-"])].sort().join("|");
    const k = key ? `${base}|${this.session.hello?.generation ?? 0}|${grouping}` : "";
    if (k !== this.key && k !== this.loading) {
      if (!key) {
        this.key = k;
        this.view.clear(this.session.hello ? "This robot has no XABSL behavior." : "Connecting…");
      } else {
        this.loading = k;
        this.rootNote.textContent = key.root ? `forced root: ${key.root}` : "";
        this.fetchGraph(key, base)
          .then(({ svg, groups }) => {
            if (this.loading !== k) return;
            this.loading = "";
            // the first fetch may have decided the grouping: the key says what is shown
            this.key = `${base}|${this.session.hello?.generation ?? 0}|${[...(this.collapsedBy.get(base) ?? ["-"])].sort().join("|")}`;
            this.groups = groups;
            this.lastShape = "";
            // grouped: Fit keeps labels legible (9 px), around what was asked for or the active option
            this.view.minTextPx = groups ? 9 : 0;
            this.view.focus = () => this.pending ?? this.deepest;
            this.groupButtons.hidden = groups === null && (this.index()?.description.options.length ?? 0) <= OVERVIEW_ABOVE;
            if (!this.view.show(svg)) this.view.clear("The server sent an unreadable graph.");
            this.mark();
            this.highlight(true);
            this.onShown();
            const pending = this.pending;
            this.pending = null;
            if (pending && this.view.has(pending)) {
              if (pending.startsWith("option_")) this.reveal(pending);
              else this.view.centerOn(pending, false);
            } else this.view.focusIfTiny(this.deepest);
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
    const groups = this.groups;
    const nodeOf = (n: (typeof path)[number]): [kind: "option" | "behavior", id: number] => (n.kind === "option" ? ["option", to.option(n.option)] : ["behavior", to.behavior(n.behavior)]);
    path.forEach((n, i) => {
      const [kind, id] = nodeOf(n);
      const element = groups ? groups.nodeId(kind, id) : `${kind}_${id}`;
      ids.push(element);
      if (n.kind === "option" && n.depth > deepestDepth) {
        deepest = element;
        deepestDepth = n.depth;
      }
      const parent = path[parents[i] ?? -1];
      if (parent?.kind !== "option") return;
      const caller = to.option(parent.option);
      const call = groups ? groups.callId(caller, kind, id) : `call_${caller}_${kind === "option" ? "o" : "b"}${id}`;
      if (call) ids.push(call);
    });
    this.deepest = deepest;
    this.view.setClasses("active", ids);
    toggleClass(this.view.element, "fade", this.fadeBox.checked && ids.length > 0);
    const root = path[0];
    if (root) {
      const [kind, id] = nodeOf(root);
      this.view.setClasses("root", [groups ? groups.nodeId(kind, id) : `${kind}_${id}`]);
    } else this.view.setClasses("root", []);
  }
}
