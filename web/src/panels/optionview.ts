/// The option view: the state machine of one option (server SVG) with the active state and the
/// transition that fired last highlighted, and "why": the decision leaf of this tick with the
/// conditions on its path, their branch, and their values re-evaluated by the server (`explain`).
import { graphSvg } from "../api";
import type { Connection } from "../connection";
import { type DescriptionIndex, leafPath, type Option, rangeText } from "../description";
import type { Explanation, OptionNode } from "../protocol";
import type { Session, SessionEvent } from "../session";
import { lastTransitionBefore, transitionsOf } from "../transitions";
import { formatMs, formatValue, h, setText, toggleClass } from "../ui";
import { SvgView } from "./svgview";

export class OptionView {
  readonly element: HTMLElement;
  private readonly view = new SvgView("State machine: drag to pan, wheel to zoom");
  private readonly title: HTMLElement;
  private readonly picker: HTMLSelectElement;
  private readonly info: HTMLElement;
  private readonly why: HTMLElement;
  private readonly doc: HTMLElement;
  private key = "";
  private loading = "";
  private explainKey = "";
  private explainAt = 0;
  private explanation: Explanation | null = null;
  private explaining = false;
  private lastWhy = "";
  private readonly transitions: HTMLElement;
  /// The active state last brought into view.
  private followed = "";
  private transitionsKey = "";
  private transitionItems = new Map<string, HTMLElement>();
  /// The last transition at the scrubbed moment: [cursor|agent|option] -> result.
  private pastKey = "";
  private past: { from: number; to: number; leaf: number; t: number } | null = null;

  constructor(
    private readonly session: Session,
    private readonly connection: Connection,
    private readonly actions: { edit(option: Option): void; test(option: Option): void },
  ) {
    this.title = h("strong.option-title");
    this.picker = h("select", { "aria-label": "Option", title: "Open another option" });
    this.picker.addEventListener("change", () => {
      const v = this.picker.value;
      this.session.openOptionById(v === "" ? null : Number(v));
    });
    this.doc = h("div.option-doc.muted");
    this.info = h("div.option-info");
    this.why = h("div.why", { "aria-live": "polite" });
    this.transitions = h("div.transitions");
    const toolbar = h(
      "div.toolbar",
      {},
      this.title,
      this.picker,
      h("button", { title: "Show the source of this option (E)", onclick: () => this.current() && this.actions.edit(this.current() as Option) }, "Edit source"),
      h("button", { title: "Run this option on the selected robot", onclick: () => this.current() && this.actions.test(this.current() as Option) }, "Test…"),
      h("button", { title: "Ask the engine again why (W)", onclick: () => this.explain(true) }, "Why?"),
      h("button", { title: "Fit: the whole machine, or at a legible size around the active state", onclick: () => this.view.fit() }, "Fit"),
      h("button", { title: "The whole machine, however small", onclick: () => this.view.fit(true) }, "Overview"),
    );
    const side = h("div.option-side", {}, this.doc, this.info, this.why, this.transitions);
    // At Fit state names stay legible (12 px on screen); a large machine is then centred on the
    // active state (or the initial one) and panned by hand, Overview shows all of it.
    this.view.minTextPx = 12;
    this.view.legibleText = 'g.node[id^="state_"] text';
    this.view.focus = () => {
      const option = this.current();
      if (!option) return null;
      const node = this.node(option);
      const initial = option.states.find((st) => st.name === option.initial_state);
      return node ? `state_${node.state}` : initial ? `state_${initial.id}` : null;
    };
    this.element = h("div.panel.option-panel", {}, toolbar, h("div.option-body", {}, this.view.element, side));
    this.view.onClick = (id) => {
      const m = /^state_(\d+)$/.exec(id);
      const option = this.current();
      if (m && option) {
        const state = option.states[Number(m[1])];
        if (state?.span) this.actions.edit({ ...option, span: state.span });
      }
    };
  }

  /// The option shown: the one opened, else the root option of the selected robot.
  current(): Option | null {
    const session = this.session;
    const index = session.indexOf(session.selectedRobot);
    if (!index) return null;
    if (session.openOption !== null) return index.optionById.get(session.openOption) ?? null;
    const root = session.robotInView()?.path.find((n) => n.kind === "option") as OptionNode | undefined;
    return root ? (index.optionById.get(root.option) ?? null) : (index.optionByName.get(index.description.agents[0]?.root ?? "") ?? null);
  }

  private node(option: Option): OptionNode | null {
    const robot = this.session.robotInView();
    return (robot?.path.find((n) => n.kind === "option" && n.option === option.id) as OptionNode | undefined) ?? null;
  }

  render(changes: Set<SessionEvent>): void {
    const session = this.session;
    const index = session.indexOf(session.selectedRobot);
    const option = this.current();
    const program = session.programOf(session.selectedRobot);
    if (changes.has("hello") || changes.has("select") || this.picker.options.length === 0) this.fillPicker(index);
    const wanted = session.openOption === null ? "" : String(session.openOption);
    if (this.picker.value !== wanted) this.picker.value = wanted;
    const k = option && program ? `${program}|${option.id}|${session.hello?.generation ?? 0}` : "";
    if (k !== this.key && k !== this.loading) {
      this.explanation = null;
      if (!option || !program) {
        this.key = k;
        this.view.clear(session.hello ? "No option to show." : "Connecting…");
      } else {
        this.loading = k;
        graphSvg(program, option.id)
          .then((svg) => {
            if (this.loading !== k) return;
            this.loading = "";
            this.key = k;
            if (!this.view.show(svg)) this.view.clear("The server sent an unreadable state machine.");
            this.highlight(option);
          })
          .catch((error: Error) => {
            if (this.loading !== k) return;
            this.loading = "";
            this.key = k;
            this.view.clear(`No state machine: ${error.message}`);
          });
      }
    }
    setText(this.title, option ? option.name : "Option");
    setText(this.doc, option?.doc ?? "");
    if (option) {
      this.renderTransitions(option, k);
      this.highlight(option);
      this.renderInfo(option, index);
      this.renderWhy(option, index);
      this.explain(false);
    }
  }

  private fillPicker(index: DescriptionIndex | null): void {
    const options = [...(index?.description.options ?? [])].sort((a, b) => a.name.localeCompare(b.name));
    this.picker.replaceChildren(h("option", { value: "" }, "(follow the root option)"), ...options.map((o) => h("option", { value: o.id }, o.name)));
  }

  /// The last transition of `option` at the moment in view: seen live, or found in the history.
  private lastTransition(option: Option): { from: number; to: number; leaf: number; t: number } | null {
    const session = this.session;
    if (session.isLive) return session.transitions.get(session.selectedRobot)?.get(option.id) ?? null;
    const key = `${session.cursor}|${session.selectedRobot}|${option.id}|${session.buffer.length}`;
    if (key !== this.pastKey) {
      this.pastKey = key;
      const ticks = session.buffer.all;
      this.past = lastTransitionBefore(ticks, session.buffer.indexAt(session.cursor ?? 0), session.selectedRobot, option.id);
    }
    return this.past;
  }

  private highlight(option: Option): void {
    const node = this.node(option);
    this.view.setClasses("active", node ? [`state_${node.state}`] : []);
    const active = node ? `state_${node.state}` : "";
    if (active && active !== this.followed) this.view.keepInView(active);
    this.followed = active;
    const last = this.lastTransition(option);
    const fired = last ? `leaf_${last.from}_${last.leaf}` : null;
    this.view.setClasses("fired", fired ? [fired] : []);
    this.view.setClasses("previous", last ? [`state_${last.from}`] : []);
    for (const [id, item] of this.transitionItems) toggleClass(item, "fired", id === fired);
  }

  /// Every transition of the option with its whole condition (the edges' labels are short).
  private renderTransitions(option: Option, key: string): void {
    if (key === this.transitionsKey) return;
    this.transitionsKey = key;
    this.transitionItems = new Map();
    const name = (id: number): string => option.states.find((st) => st.id === id)?.name ?? String(id);
    const items = transitionsOf(option).map((t) => {
      const id = `leaf_${t.from}_${t.leaf}`;
      const item = h(
        "li",
        { "data-edge": id, onmouseenter: () => this.view.setClasses("hovered", [id]), onmouseleave: () => this.view.setClasses("hovered", []) },
        h("span.edge-states", {}, `${name(t.from)} → ${name(t.to)}`),
        h("code", {}, t.condition),
      );
      this.transitionItems.set(id, item);
      return item;
    });
    this.transitions.replaceChildren(
      h("div.section-title", {}, `Transitions (${items.length})`),
      items.length ? h("ol.transition-list", {}, ...items) : h("div.muted", {}, "No transitions: the option stays in its state."),
    );
  }

  private renderInfo(option: Option, index: DescriptionIndex | null): void {
    const node = this.node(option);
    const lines: string[] = [];
    if (!node) lines.push(`Not active on ${this.session.robotInfo(this.session.selectedRobot)?.name ?? "this robot"} ${this.session.isLive ? "now" : "at this moment"}.`);
    else {
      const state = option.states[node.state];
      lines.push(`state ${state?.name ?? node.state} for ${formatMs(node.stateTime)} · option active ${formatMs(node.optionTime)}`);
      option.params.forEach((p, i) => lines.push(`@${p.short_name} = ${formatValue(node.params[i], p.type, p.enum, index)} ${rangeText(null, p.unit)}`.trim()));
    }
    const last = this.lastTransition(option);
    if (last) {
      const t = this.session.view?.t ?? last.t;
      lines.push(`last transition ${option.states[last.from]?.name} → ${option.states[last.to]?.name}, ${formatMs(Math.max(0, t - last.t))} ago`);
    }
    const text = lines.join("\n");
    if (this.info.textContent !== text) this.info.textContent = text;
  }

  /// Why the decision of this tick took its leaf: the chain of conditions from the description
  /// (branch taken), with the server's values when an explanation for this leaf is at hand.
  private renderWhy(option: Option, index: DescriptionIndex | null): void {
    const node = this.node(option);
    if (!node || node.leaf < 0) {
      if (this.lastWhy !== "none") {
        this.lastWhy = "none";
        this.why.replaceChildren(h("div.muted", {}, node ? "This option has not decided yet." : ""));
      }
      return;
    }
    const decided = option.states[node.decidedIn];
    const target = option.states[node.state];
    const sameTick = !this.session.replay || (this.explanation as { seq?: number } | null)?.seq === this.session.view?.seq;
    const ex = this.explanation && sameTick && this.explanation.option === option.id && this.explanation.leaf === node.leaf && this.explanation.decided_in === node.decidedIn ? this.explanation : null;
    const key = `${option.id}|${node.decidedIn}|${node.leaf}|${node.state}|${ex ? JSON.stringify(ex.conditions) : ""}`;
    if (key === this.lastWhy) return;
    this.lastWhy = key;
    const path = decided ? leafPath(decided.decision, node.leaf) : null;
    const rows = (path ?? []).map(({ node: ifNode, taken }, i) => {
      const live = ex?.conditions[i];
      const value = live ? formatValue(typeof live.value === "string" ? null : live.value) : "";
      return h(
        "li",
        { class: taken ? "cond taken" : "cond not-taken", title: ifNode.doc ?? "" },
        h("span.branch", {}, taken ? "if" : "else of"),
        h("code", {}, ifNode.if),
        live ? h("span.value", { class: `value ${String(live.value)}` }, value) : null,
        live ? operandsOf(live) : null,
        ifNode.doc ? h("div.cond-doc.muted", {}, ifNode.doc) : null,
      );
    });
    const stays = node.decidedIn === node.state;
    this.why.replaceChildren(
      h("div.why-head", {}, h("strong", {}, "Decision of this tick: "), `${decided?.name ?? node.decidedIn} `, h("span.arrow", {}, stays ? "stays" : `→ ${target?.name ?? node.state}`), h("span.muted", {}, ` (leaf ${node.leaf})`)),
      rows.length ? h("ol.conditions", {}, ...rows) : h("div.muted", {}, "No condition: the decision always takes this leaf."),
      h("div.muted.small", {}, ex ? (this.session.replay ? "Values computed from the recording at this tick." : "Values re-evaluated by the engine just now.") : this.session.isLive || this.session.replay ? "Asking the engine for values…" : "Scrubbed back: values are shown only for the live tick."),
    );
    void index;
  }

  /// Ask the server to explain the current decision (when the leaf changes, else once a second).
  private explain(force: boolean): void {
    const session = this.session;
    const option = this.current();
    // A replay explains any tick (from the recording); a live session only the newest.
    const seq = session.replay ? session.view?.seq : undefined;
    if (!option || (!session.isLive && seq === undefined) || this.explaining || this.element.closest("[hidden]")) return;
    const node = this.node(option);
    if (!node || node.leaf < 0) return;
    const key = `${session.selectedRobot}|${option.id}|${node.decidedIn}|${node.leaf}|${seq ?? ""}`;
    const now = performance.now();
    if (!force && key === this.explainKey && now - this.explainAt < 1000) return;
    this.explainKey = key;
    this.explainAt = now;
    this.explaining = true;
    this.connection
      .command("explain", { robot: session.selectedRobot, option: option.id, ...(seq === undefined ? {} : { seq }) })
      .then((ex) => {
        this.explanation = ex;
      })
      .catch(() => {
        this.explanation = null;
      })
      .finally(() => {
        this.explaining = false;
        this.lastWhy = "";
        // A paused replay sends no frame that would redraw the panel: show the answer now.
        const shown = this.current();
        if (session.replay && shown) this.renderWhy(shown, session.indexOf(session.selectedRobot));
      });
  }
}

interface Operand {
  text: string;
  value: unknown;
}

/// The operand values of a condition's comparisons (a replay's explanation carries them).
function operandsOf(condition: object): HTMLElement | null {
  const operands = (condition as { operands?: Array<{ left: Operand; right: Operand }> }).operands;
  if (!operands?.length) return null;
  const shown = (o: Operand): string => `${o.text} = ${o.value === null || o.value === undefined ? "?" : typeof o.value === "number" ? formatValue(o.value) : String(o.value)}`;
  return h("div.operands.muted.small", {}, operands.map((c) => `${shown(c.left)}, ${shown(c.right)}`).join(" · "));
}
