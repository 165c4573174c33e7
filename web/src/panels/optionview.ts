/// The option view: the state machine of one option (server SVG) with the active state and the
/// transition that fired last highlighted, and "why": the decision leaf of this tick with the
/// conditions on its path, their branch, and the values the decision read then (`explain`; `?`:
/// a value the decision did not read, e.g. an operand after `&&` decided), and "why not": for a
/// state the decision did not go to (picked in the pane, or "Why not …?" on a state's context
/// menu), every route there with the condition that blocked it, from the same values
/// (`explain` with `why_not`).
import { graphSvg } from "../api";
import type { Connection } from "../connection";
import { type DescriptionIndex, leafPath, type Option, rangeText } from "../description";
import type { Explanation, OptionNode } from "../protocol";
import type { Session, SessionEvent } from "../session";
import { lastTransitionBefore, transitionsOf } from "../transitions";
import { formatClock, formatMs, formatValue, h, setText, toggleClass } from "../ui";
import { BreakpointsPanel } from "./breakpoints";
import { exportMenu, type PictureTarget } from "./exportmenu";
import { SvgView } from "./svgview";

type Why = Explanation;
type WhyCondition = Explanation["conditions"][number];
type WhyTree = Record<string, unknown>;
type WhyNotAnswer = NonNullable<Explanation["why_not"]>;
type Comparison = NonNullable<WhyCondition["comparisons"]>[number];

/// A comparison's value as its row shows it, after the operands.
function comparisonValue(k: Comparison): string {
  return ` = ${k.value === null ? "?" : String(k.value)}`;
}

/// Set an element's whole class attribute, only when it differs (a write is style work).
function setClass(el: Element, name: string): void {
  if (el.className !== name) el.className = name;
}

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
  /// The why pane in three parts, each replaced only when what it shows changes. A team's root
  /// can change its decision several times a second, each change followed by the answer with
  /// its values; rebuilding the whole pane for each cost style, layout and paint that the
  /// draw's script time (stats.renderMs) does not show, and frames were missed.
  /// The decision and its conditions (the values go into the rows when the answer comes):
  private readonly whyDecision = h("div.why-decision");
  private whyRows: HTMLElement[] = [];
  private decisionShown: { option: Option; key: string } | null = null;
  /// The answer whose values the rows show (undefined: rows just built, none yet).
  private valuesShown: Explanation | null | undefined = undefined;
  /// "Why not": one picker for the pane's life, never moved. A `<select>` created anew (or moved)
  /// is a form control added to the page, which Chromium then processes in its browser process
  /// too: with a new picker per decision that was more CPU than the page's own script.
  private readonly whyNotPicker: HTMLSelectElement;
  private readonly whyNotResult = h("div.why-not-result");
  private readonly whyNotBox: HTMLElement;
  private pickerFor: { option: Option; state: number } | null = null;
  private whyNotShown: { option: Option; key: string } | null = null;
  /// The decision tree, the last transition and where the values come from (with each answer).
  private readonly whyMore = h("div.why-more");
  private moreShown: { option: Option; ex: Explanation | null; known: string } | null = null;
  /// "Why not": the state asked about, and the answer with the decision it is for.
  private whyNotState: number | null = null;
  private whyNot: { key: string; answer: WhyNotAnswer } | null = null;
  private whyNotError = "";
  private whyNotAsking = "";
  private readonly transitions: HTMLElement;
  /// The active state last brought into view.
  private followed = "";
  private transitionsKey = "";
  private transitionItems = new Map<string, HTMLElement>();
  /// The last transition at the scrubbed moment: [cursor|agent|option] -> result.
  private pastKey = "";
  private past: { from: number; to: number; leaf: number; t: number } | null = null;
  /// Breakpoints of the selected robot's behavior set (shown beside the machine).
  readonly breakpoints: BreakpointsPanel;
  private readonly menu: HTMLElement;
  /// The state Find asked to show, until its machine is on screen.
  private revealing: number | null = null;

  constructor(
    private readonly session: Session,
    private readonly connection: Connection,
    private readonly actions: { edit(option: Option): void; test(option: Option): void; find(option: Option, state: string): void },
  ) {
    this.title = h("strong.option-title");
    this.picker = h("select", { "aria-label": "Option", title: "Open another option" });
    this.picker.addEventListener("change", () => {
      const v = this.picker.value;
      this.session.openOptionById(v === "" ? null : Number(v));
    });
    this.doc = h("div.option-doc.muted");
    this.info = h("div.option-info");
    this.whyNotPicker = h("select.why-not-picker", { "aria-label": "Why not this state", title: "Why did the decision not go to this state?" });
    this.whyNotPicker.addEventListener("change", () => this.askWhyNot(this.whyNotPicker.value === "" ? null : Number(this.whyNotPicker.value)));
    this.whyNotBox = h("div.why-not", { hidden: true }, this.whyNotPicker, this.whyNotResult);
    this.why = h("div.why", { "aria-live": "polite" }, this.whyDecision, this.whyNotBox, this.whyMore);
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
      exportMenu(() => this.pictureTarget(), "this state machine"),
    );
    this.breakpoints = new BreakpointsPanel(session, connection, () => this.current());
    const side = h("div.option-side", {}, this.doc, this.info, this.why, this.breakpoints.element, this.transitions);
    // The state context: right-click a state for "break on enter / leave", or to find every tick in it.
    this.menu = h("div.context-menu", { role: "menu", hidden: true });
    document.addEventListener("pointerdown", (ev) => {
      if (!this.menu.contains(ev.target as Node)) this.menu.hidden = true;
    });
    this.view.element.addEventListener("contextmenu", (ev) => {
      const node = (ev.target as Element).closest('g[id^="state_"]');
      const option = this.current();
      const state = node && option ? option.states[Number(node.id.slice(6))] : undefined;
      if (!state) return;
      ev.preventDefault();
      const item = (label: string, kind: "enter_state" | "leave_state"): HTMLElement =>
        h("button", { role: "menuitem", onclick: () => { this.menu.hidden = true; void this.breakpoints.add(kind, state.name); } }, label);
      const find = h(
        "button.find-state",
        { role: "menuitem", title: "Mark on the timeline every tick where this option is in this state (a query)", onclick: () => { this.menu.hidden = true; this.actions.find(option as Option, state.name); } },
        `Every tick in ${state.name}`,
      );
      const whyNot = h("button", { role: "menuitem", onclick: () => { this.menu.hidden = true; this.askWhyNot(state.id); } }, `Why not ${state.name}?`);
      this.menu.replaceChildren(item(`Break on enter ${state.name}`, "enter_state"), item(`Break on leave ${state.name}`, "leave_state"), whyNot, find);
      this.menu.style.left = `${ev.clientX}px`;
      this.menu.style.top = `${ev.clientY}px`;
      this.menu.hidden = false;
    });
    document.body.append(this.menu);
    // At Fit state names stay legible (12 px on screen); a large machine is then centred on the
    // active state (or the initial one) and panned by hand, Overview shows all of it.
    this.view.minTextPx = 12;
    this.view.enableMinimap();
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
  /// The picture of the state machine shown (Export).
  private pictureTarget(): PictureTarget | null {
    const session = this.session;
    const option = this.current();
    const program = session.programOf(session.selectedRobot);
    if (!option || !program) return null;
    const seq = session.view?.seq;
    const robot = session.robotInView();
    return {
      path: `picture/${encodeURIComponent(program)}/${encodeURIComponent(option.name)}`,
      params: {},
      tick: robot?.path.length && seq !== undefined ? { robot: session.selectedRobot, seq } : undefined,
    };
  }

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
      // a state id of another option (or generation) would ask about the wrong state
      this.whyNotState = null;
      this.whyNot = null;
      this.whyNotError = "";
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
            this.followed = "";
            this.highlight(option);
            this.revealNow();
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
    this.breakpoints.sync();
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

  /// Centre state `state` of the option shown (or about to be) and mark it (class `found`):
  /// where Find jumps to a state.
  reveal(state: number): void {
    this.revealing = state;
    if (this.key && !this.loading) this.revealNow();
  }

  private revealNow(): void {
    if (this.revealing === null) return;
    const id = `state_${this.revealing}`;
    if (!this.view.has(id)) return;
    this.revealing = null;
    this.view.setClasses("found", [id]);
    this.view.centerOn(id);
  }

  private highlight(option: Option): void {
    const node = this.node(option);
    this.view.setClasses("active", node ? [`state_${node.state}`] : []);
    const active = node ? `state_${node.state}` : "";
    const last = this.lastTransition(option);
    const fired = last ? `leaf_${last.from}_${last.leaf}` : null;
    // A new active state (or the machine just shown): centre it with the transition that led
    // there, while the placement is automatic (Fit, or Fit around the active state).
    if (active && active !== this.followed) this.view.follow(fired && last?.to === node?.state ? [active, fired] : [active]);
    this.followed = active;
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

  /// Why the decision of the tick in view took its leaf: the chain of conditions (branch taken)
  /// with their values and each comparison's operand values (`ball.distance (412.3) < 500`), the
  /// decision tree with the path taken, and the last transition up to this tick with its values.
  /// Live: the engine re-evaluates now; scrubbed back: the server evaluates the recorded values of
  /// that tick (`explain` with `seq`).
  private renderWhy(option: Option, index: DescriptionIndex | null): void {
    const node = this.node(option);
    if (!node || node.leaf < 0) {
      const text = node ? "This option has not decided yet." : "";
      if (this.lastWhy !== `none|${text}`) {
        this.lastWhy = `none|${text}`;
        this.whyDecision.replaceChildren(h("div.muted", {}, text));
        this.whyRows = [];
        this.decisionShown = null;
        this.whyNotBox.hidden = true;
        this.whyMore.replaceChildren();
        this.moreShown = null;
      }
      return;
    }
    const decided = option.states[node.decidedIn];
    const target = option.states[node.state];
    const seq = this.session.isLive ? null : (this.session.view?.seq ?? null);
    const e = this.explanation;
    const ex = e && e.option === option.id && e.leaf === node.leaf && e.decided_in === node.decidedIn && (seq === null ? !e.recorded : e.seq === seq) ? e : null;
    // The server's last transition comes with its values; where it has none (a replay keeps no
    // explain history), the transition the info line names from the buffered ticks is shown
    // without values rather than contradicted by "no transition".
    const known = ex && !ex.last_transition ? this.lastTransition(option) : null;
    const decisionKey = this.decisionKey(option, node, seq);
    const whyNot = this.whyNot && this.whyNot.key === `${decisionKey}|${this.whyNotState}` ? this.whyNot.answer : null;
    // Another tick or decision in view: ask again about the same state, once per decision.
    const asked = this.whyNotState;
    if (asked !== null && !whyNot && this.whyNotAsking !== `${decisionKey}|${asked}`) queueMicrotask(() => this.askWhyNot(asked));
    const knownKey = known ? `${known.from}>${known.to}@${known.t}` : "";
    const key = `${option.id}|${node.decidedIn}|${node.leaf}|${node.state}|${seq}|${ex ? JSON.stringify([ex.conditions, ex.last_transition?.seq]) : ""}|${knownKey}|${this.whyNotState}|${whyNot ? "answer" : this.whyNotError}`;
    if (key === this.lastWhy) return;
    this.lastWhy = key;
    const name = (id: number): string => option.states[id]?.name ?? String(id);
    // The decision and its conditions: once per decision (the answer only brings values).
    const decision = `${node.decidedIn}|${node.leaf}|${node.state}`;
    if (this.decisionShown?.option !== option || this.decisionShown.key !== decision) {
      this.decisionShown = { option, key: decision };
      const path = decided ? leafPath(decided.decision, node.leaf) : null;
      this.whyRows = (path ?? []).map(({ node: ifNode, taken }) => this.conditionRow(ifNode.if, taken, undefined, ifNode.doc));
      this.valuesShown = undefined;
      const stays = node.decidedIn === node.state;
      this.whyDecision.replaceChildren(
        h("div.why-head", {}, h("strong", {}, "Decision of this tick: "), `${decided?.name ?? node.decidedIn} `, h("span.arrow", {}, stays ? "stays" : `→ ${target?.name ?? node.state}`), h("span.muted", {}, ` (leaf ${node.leaf})`)),
        this.whyRows.length ? h("ol.conditions", {}, ...this.whyRows) : h("div.muted", {}, "No condition: the decision always takes this leaf."),
      );
    }
    if (this.valuesShown !== ex) {
      this.valuesShown = ex;
      this.whyRows.forEach((row, i) => this.showValues(row, ex?.conditions[i]));
    }
    this.whyNotBox.hidden = false;
    this.renderWhyNot(option, node, whyNot);
    // The tree, the last transition and where the values come from: once per answer.
    if (this.moreShown?.option !== option || this.moreShown.ex !== ex || this.moreShown.known !== knownKey) {
      this.moreShown = { option, ex, known: knownKey };
      const last = ex?.last_transition ?? null;
      const parts: Array<Node | null> = [
        ex?.tree && "if" in ex.tree ? h("details.why-tree", { open: true }, h("summary", {}, "Decision tree, path taken"), this.treeView(ex.tree as WhyTree, name)) : null,
        last
          ? h(
              "div.last-transition",
              {},
              h("strong", {}, "Last transition: "),
              `${last.decided_in_name} → ${last.target_name} at ${formatClock(last.t)} (leaf ${last.leaf})`,
              h("ol.conditions", {}, ...last.conditions.map((c) => this.conditionRow(c.text || c.source, c.branch, c, null))),
            )
          : known
            ? h(
                "div.last-transition",
                {},
                h("strong", {}, "Last transition: "),
                `${name(known.from)} → ${name(known.to)} at ${formatClock(known.t)} (leaf ${known.leaf})`,
                h("div.muted.small", {}, "Its condition values are not available here."),
              )
            : ex
              ? h("div.muted.small", {}, "No transition of this option in the buffered history up to this tick.")
              : null,
        h("div.muted.small", {}, ex ? (ex.recorded ? `Values recorded at t = ${formatClock(ex.t ?? 0)}: what the decision read then.` : "Values the decision read in the last tick.") : "Asking the server for values…"),
      ];
      this.whyMore.replaceChildren(...parts.filter((p): p is Node => p !== null));
    }
    void index;
  }

  private decisionKey(option: Option, node: OptionNode, seq: number | null): string {
    return `${this.session.selectedRobot}|${option.id}|${node.decidedIn}|${node.leaf}|${seq}`;
  }

  /// "Why not STATE": the picker offers the states the decision did not go to (its options change
  /// with the option and the state only), and for the one picked each route there (the
  /// conditions it needs, their values, the one that blocked it: ✗).
  private renderWhyNot(option: Option, node: OptionNode, answer: WhyNotAnswer | null): void {
    const picker = this.whyNotPicker;
    if (this.pickerFor?.option !== option || this.pickerFor.state !== node.state) {
      this.pickerFor = { option, state: node.state };
      picker.replaceChildren(h("option", { value: "" }, "Why not…"), ...option.states.filter((st) => st.id !== node.state).map((st) => h("option", { value: st.id }, st.name)));
    }
    const chosen = this.whyNotState !== null && this.whyNotState !== node.state ? String(this.whyNotState) : "";
    if (picker.value !== chosen) picker.value = chosen;
    const key = `${node.decidedIn}|${this.whyNotState}|${this.whyNotError}|${answer ? JSON.stringify(answer) : ""}`;
    if (this.whyNotShown?.option === option && this.whyNotShown.key === key) return;
    this.whyNotShown = { option, key };
    const asked = this.whyNotState !== null ? option.states[this.whyNotState] : undefined;
    const parts: Node[] = [];
    if (asked && this.whyNotError) parts.push(h("div.muted.small", {}, `Why not ${asked.name}: ${this.whyNotError}`));
    else if (asked && !answer) parts.push(h("div.muted.small", {}, `Asking why not ${asked.name}…`));
    else if (asked && answer) {
      const routes = answer.routes.map((route) => {
        const rows = route.conditions.map((c, i) => {
          const row = this.conditionRow(c.text || c.source, c.branch, c, null);
          row.querySelector(".branch")?.replaceChildren(c.branch ? "needs" : "needs not");
          if (i === route.blocked_at) row.classList.add("blocker");
          return row;
        });
        const blocker = route.blocked_at === null ? null : route.conditions[route.blocked_at];
        const head = blocker
          ? `blocked by ${blocker.text || blocker.source} (${blocker.value === null ? "?" : String(blocker.value)})`
          : route.parts_at === null
            ? "the route taken"
            : "nothing known blocks it (values the decision did not read: ?)";
        return h("li.why-not-route", {}, h("div", {}, `leaf ${route.leaf} (${route.stay ? "stay" : `goto ${answer.target_name}`}): `, h("strong", {}, head)), h("ol.conditions", {}, ...rows));
      });
      parts.push(
        h(
          "div.why-not-answer",
          {},
          h("strong", {}, `Why not ${answer.target_name}: `),
          answer.went
            ? `the decision did go to ${answer.target_name}.`
            : routes.length
              ? `${routes.length} route${routes.length > 1 ? "s lead" : " leads"} there from ${option.states[node.decidedIn]?.name ?? node.decidedIn}.`
              : `no transition of ${option.states[node.decidedIn]?.name ?? node.decidedIn} leads to ${answer.target_name}.`,
          routes.length ? h("ol.why-not-routes", {}, ...routes) : null,
        ),
      );
    }
    this.whyNotResult.replaceChildren(...parts);
  }

  /// Ask why the decision in view did not go to state `state` (null: forget the question).
  private askWhyNot(state: number | null): void {
    const session = this.session;
    const option = this.current();
    this.whyNotState = state;
    this.whyNot = null;
    this.whyNotError = "";
    this.lastWhy = "";
    const node = option ? this.node(option) : null;
    if (!option || !node || node.leaf < 0 || state === null) {
      if (option) this.renderWhy(option, session.indexOf(session.selectedRobot));
      return;
    }
    const seq = session.isLive ? null : (session.view?.seq ?? null);
    const key = `${this.decisionKey(option, node, seq)}|${state}`;
    this.whyNotAsking = key;
    const args = seq === null ? { robot: session.selectedRobot, option: option.id, why_not: state } : { robot: session.selectedRobot, option: option.id, seq, why_not: state };
    this.renderWhy(option, session.indexOf(session.selectedRobot));
    this.connection
      .command("explain", args)
      .then((ex: Why) => {
        if (ex.why_not) this.whyNot = { key, answer: ex.why_not };
      })
      .catch((error: Error) => {
        this.whyNotError = error.message;
      })
      .finally(() => {
        this.lastWhy = "";
        const shown = this.current();
        if (shown) this.renderWhy(shown, session.indexOf(session.selectedRobot));
      });
  }

  private conditionRow(text: string, taken: boolean, values: WhyCondition | undefined, doc: string | null): HTMLElement {
    const row = h(
      "li",
      { class: taken ? "cond taken" : "cond not-taken", title: doc ?? "" },
      h("span.branch", {}, taken ? "if" : "else of"),
      h("code", {}, text),
      doc ? h("div.cond-doc.muted", {}, doc) : null,
    );
    if (values) this.showValues(row, values);
    return row;
  }

  /// Put a condition's values into its row, after its text (none: take them out). A row that
  /// shows values already keeps its elements and only gets the texts and classes that differ:
  /// a live decision is asked again every second, and rows taken out and put back each time
  /// were layout work for the whole pane (and everything below it) even when nothing changed.
  private showValues(row: HTMLElement, values: WhyCondition | undefined): void {
    const shown = [...row.children].filter((child) => child.classList.contains("value") || child.classList.contains("comparisons"));
    if (!values) {
      for (const child of shown) child.remove();
      return;
    }
    const value = values.value === null ? "?" : formatValue(typeof values.value === "string" ? null : values.value);
    const comparisons = values.comparisons ?? [];
    const [badge, list] = shown;
    if (badge?.classList.contains("value") && shown.length === (comparisons.length ? 2 : 1) && this.updateComparisons(list, comparisons)) {
      setClass(badge, `value ${String(values.value)}`);
      setText(badge, value);
      return;
    }
    for (const child of shown) child.remove();
    row.children[1]?.after(
      h("span.value", { class: `value ${String(values.value)}` }, value),
      ...(comparisons.length ? [h("ul.comparisons", {}, ...comparisons.map((k) => h("li", { class: `comparison ${String(k.value)}` }, h("code", {}, k.shown), h("span.muted", {}, comparisonValue(k)))))] : []),
    );
  }

  /// Update the comparisons list `list` of a row in place to `comparisons` when it lists the same
  /// operands (only values differ); false: it does not, the row's values are drawn anew.
  private updateComparisons(list: Element | undefined, comparisons: Comparison[]): boolean {
    if (!comparisons.length) return list === undefined;
    const items = list?.classList.contains("comparisons") ? [...list.children] : [];
    if (items.length !== comparisons.length || items.some((item, i) => item.children[0]?.textContent !== comparisons[i]?.shown)) return false;
    items.forEach((item, i) => {
      const k = comparisons[i] as Comparison;
      setClass(item, `comparison ${String(k.value)}`);
      const muted = item.children[1];
      if (muted) setText(muted, comparisonValue(k));
    });
    return true;
  }

  /// The decision tree as nested boxes: conditions with their values, the taken path marked.
  private treeView(tree: WhyTree, name: (id: number) => string): HTMLElement {
    void name;
    if (!("if" in tree)) {
      const target = tree.stay ? "stay" : `goto ${String(tree.target)}`;
      return h("div", { class: tree.taken ? "tree-leaf taken" : "tree-leaf" }, `${target} (leaf ${String(tree.leaf)})`);
    }
    const value = tree.value === null || tree.value === undefined ? "" : ` = ${String(tree.value)}`;
    return h(
      "div",
      { class: tree.taken ? "tree-if taken" : "tree-if" },
      h("div.tree-cond", {}, h("code", {}, String(tree.if)), h("span.muted", {}, value)),
      h("div", { class: tree.branch === true ? "tree-branch taken" : "tree-branch" }, h("span.tree-label", {}, "then"), this.treeView(tree.then as WhyTree, name)),
      h("div", { class: tree.branch === false ? "tree-branch taken" : "tree-branch" }, h("span.tree-label", {}, "else"), this.treeView(tree.else as WhyTree, name)),
    );
  }

  /// Ask the server to explain the decision in view (live: when the leaf changes, else once a
  /// second; scrubbed: once per tick, from the recorded values).
  private explain(force: boolean): void {
    const session = this.session;
    const option = this.current();
    if (!option || this.explaining || this.element.closest("[hidden]")) return;
    const node = this.node(option);
    if (!node || node.leaf < 0) return;
    const seq = session.isLive ? null : (session.view?.seq ?? null);
    const key = `${session.selectedRobot}|${option.id}|${node.decidedIn}|${node.leaf}|${seq}`;
    const now = performance.now();
    if (!force && key === this.explainKey && (seq !== null || now - this.explainAt < 1000)) return;
    this.explainKey = key;
    this.explainAt = now;
    this.explaining = true;
    const args = seq === null ? { robot: session.selectedRobot, option: option.id } : { robot: session.selectedRobot, option: option.id, seq };
    this.connection
      .command("explain", args)
      .then((ex: Why) => {
        this.explanation = ex;
      })
      .catch(() => {
        this.explanation = null;
      })
      .finally(() => {
        this.explaining = false;
        this.lastWhy = "";
        // A paused session (a replay, a breakpoint hit, the pause key) sends no frame that would
        // redraw the panel: show the answer now, and ask for the decision in view if it
        // changed while this answer was on its way. A running one redraws on its next frame
        // anyway, so drawing here too costs one render per answer.
        const shown = this.current();
        if (shown && !this.element.closest("[hidden]")) {
          this.renderWhy(shown, session.indexOf(session.selectedRobot));
          this.explain(false);
        }
      });
  }
}
