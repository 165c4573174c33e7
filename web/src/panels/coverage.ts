/// Coverage and oscillations of the live session (GET /api/profile, counted in the server from
/// its ring buffer: every tick, where the browser only sees the frames its rate lets through).
/// Shows the selected robot's coverage figures, dims never-active options and never-taken calls
/// in the option graph (counts on hover), and lists oscillations: a click moves the timeline
/// cursor to the tick the option or state was left. Refreshes on demand and every few seconds
/// while the tab is open.
import { token } from "../api";
import type { Session, SessionEvent } from "../session";
import { h } from "../ui";
import type { Option } from "../description";
import type { GraphPanel } from "./graph";

interface Duration { share: number; activations: number; mean_ms: number; longest_ms: number }
interface OptionProfile extends Duration {
  states: Record<string, Duration>;
  transitions: Array<{ from: string; to: string; leaf: number; count: number }>;
}
interface Ratio { reached: number; total: number; percent: number }
interface AgentProfile {
  program: string;
  ticks: number;
  options: Record<string, OptionProfile>;
  coverage: { options: Ratio & { never: string[] }; states: Ratio & { never: string[] }; transitions: Ratio; leaves: Ratio };
}
export interface Oscillation {
  agent: string; kind: string; option: string; state: string | null; via: string[];
  left_seq: number; reentered_seq: number; left_t: number; reentered_t: number; away_ms: number;
}
export interface Profile { ticks: number; agents: Record<string, AgentProfile>; oscillations: Oscillation[] }

const STYLE = `
.graph-panel svg .never, .option-panel svg .never { opacity: 0.35; }
.graph-panel svg .never polygon, .graph-panel svg .never path,
.option-panel svg .never polygon, .option-panel svg .never path, .option-panel svg .never ellipse { stroke-dasharray: 4 3; }
.coverage-panel { display: flex; flex-direction: column; gap: 6px; padding: 6px; overflow: auto; }
.coverage-panel .figures span { margin-right: 12px; }
.coverage-panel ol { margin: 0; padding-left: 20px; }
.coverage-panel li button { all: unset; cursor: pointer; text-decoration: underline dotted; }
`;

export async function fetchProfile(robot: string | null, oscillationMs = 1000): Promise<Profile> {
  const query = new URLSearchParams({ oscillation_ms: String(oscillationMs) });
  if (robot) query.set("robot", robot);
  const response = await fetch(`api/profile?${query}`, { headers: token ? { Authorization: `Bearer ${token}` } : {} });
  if (!response.ok) throw new Error(`${response.status}: ${await response.text()}`);
  return (await response.json()) as Profile;
}

export class CoveragePanel {
  readonly element: HTMLElement;
  private readonly figures = h("div.figures.muted", {}, "Press Refresh to count the session's ticks.");
  private readonly list = h("ol", { "aria-label": "Oscillations" });
  private readonly overlay: HTMLInputElement = h("input", { type: "checkbox", checked: true, "aria-label": "Dim never-active options in the option graph" });
  private readonly threshold: HTMLInputElement = h("input", { type: "number", min: "1", step: "100", value: "1000", "aria-label": "Oscillation threshold (ms)", style: "width: 6em" });
  private profile: Profile | null = null;
  private robot: string | null = null;
  private last = 0;
  private busy = false;
  private overlaid: { svg: Element | null; profile: Profile | null; checked: boolean } = { svg: null, profile: null, checked: true };

  /// `shownOption`: the option the state-machine view (panels/optionview.ts) shows, and its element.
  constructor(
    private readonly session: Session,
    private readonly graph: GraphPanel,
    private readonly shownOption: () => { option: Option | null; element: HTMLElement },
  ) {
    document.head.append(h("style", {}, STYLE));
    this.overlay.addEventListener("change", () => this.applyOverlay());
    this.threshold.addEventListener("change", () => void this.refresh());
    this.graph.onShown = () => this.applyOverlay();
    const toolbar = h(
      "div.toolbar",
      {},
      h("button", { title: "Count the ticks in the server's buffer", onclick: () => void this.refresh() }, "Refresh"),
      h("label", { title: "An option or state re-entered within this many ms is an oscillation" }, "within ", this.threshold, " ms"),
      h("label", {}, this.overlay, " dim never-active in graph"),
    );
    this.element = h("div.panel.coverage-panel", {}, toolbar, this.figures, h("strong", {}, "Oscillations"), this.list);
  }

  /// The selected robot's name (its profile is what the panel shows).
  private robotName(): string | null {
    return this.session.robots.find((r) => r.id === this.session.selectedRobot)?.name ?? null;
  }

  async refresh(): Promise<void> {
    if (this.busy) return;
    this.busy = true;
    this.last = performance.now();
    const robot = this.robotName();
    try {
      const ms = Number(this.threshold.value);
      this.profile = await fetchProfile(robot, Number.isFinite(ms) && ms > 0 ? ms : 1000);
      this.robot = robot;
      this.show();
    } catch (error) {
      this.figures.textContent = `No profile: ${(error as Error).message}`;
    } finally {
      this.busy = false;
    }
  }

  private show(): void {
    const agent = this.robot ? this.profile?.agents[this.robot] : undefined;
    if (!this.profile || !agent) {
      this.figures.textContent = "This robot has no XABSL behavior.";
      this.list.replaceChildren();
      this.applyOverlay();
      return;
    }
    const c = agent.coverage;
    this.figures.replaceChildren(
      h("div", {}, `${this.robot}: ${this.profile.ticks} ticks counted`),
      ...(["options", "states", "transitions", "leaves"] as const).map((part) =>
        h("span", { title: part === "options" ? `never active: ${c.options.never.join(", ")}` : part === "states" ? `never entered: ${c.states.never.join(", ")}` : "" }, `${part} ${c[part].reached}/${c[part].total} (${c[part].percent.toFixed(0)} %)`),
      ),
    );
    const items = this.profile.oscillations.filter((o) => o.agent === this.robot).slice(0, 300);
    this.list.replaceChildren(
      ...items.map((o) =>
        h(
          "li",
          {},
          h(
            "button",
            { title: `left at tick ${o.left_seq}, back at ${o.reentered_seq}`, onclick: () => this.session.seekTick(o.left_t, o.left_seq) },
            `${o.option}${o.state ? `.${o.state}` : ""}${o.via.length ? ` via ${o.via.join(" → ")}` : ""}: away ${o.away_ms.toFixed(0)} ms at ${(o.left_t / 1000).toFixed(1)} s`,
          ),
        ),
      ),
    );
    if (!items.length) this.list.append(h("li.muted", {}, "none"));
    this.applyOverlay();
  }

  /// Dim the selected robot's never-active options in the option graph; counts on hover.
  private applyOverlay(): void {
    const agent = this.robot ? this.profile?.agents[this.robot] : undefined;
    const index = this.session.indexOf(this.session.selectedRobot);
    if (!agent || !index || !this.overlay.checked || this.robot !== this.robotName()) {
      this.graph.overlay("never", [], new Map());
      return;
    }
    const never: string[] = [];
    const titles = new Map<string, string>();
    for (const option of index.description.options) {
      const id = `option_${option.id}`;
      const p = agent.options[option.name];
      if (!p) {
        never.push(id);
        titles.set(id, `${option.name}: never active`);
      } else {
        titles.set(id, `${option.name}: ${(100 * p.share).toFixed(1)} % of the time, ${p.activations} activations, mean ${p.mean_ms.toFixed(0)} ms`);
        for (const call of option.calls) {
          if (call.type === "option" && !agent.options[call.name]) never.push(`call_${option.id}_o${index.optionByName.get(call.name)?.id ?? -1}`);
        }
      }
    }
    this.graph.overlay("never", never, titles);
  }

  /// Dim never-entered states and never-taken transitions in the state-machine view; counts on
  /// hover. The view draws its SVG itself; this marks it again whenever a new one is shown.
  private overlayStateMachine(): void {
    const { option, element } = this.shownOption();
    const svg = element.querySelector("svg");
    const checked = this.overlay.checked && this.robot === this.robotName();
    const o = this.overlaid;
    if (svg === o.svg && this.profile === o.profile && checked === o.checked) return;
    this.overlaid = { svg, profile: this.profile, checked };
    if (!svg || !option) return;
    for (const el of svg.querySelectorAll(".never")) el.classList.remove("never");
    const agent = this.robot ? this.profile?.agents[this.robot] : undefined;
    if (!agent || !checked) return;
    const p = agent.options[option.name];
    const title = (el: Element, text: string): void => {
      let t = el.querySelector(":scope > title");
      if (!t) el.prepend((t = document.createElementNS("http://www.w3.org/2000/svg", "title")));
      t.textContent = text;
    };
    for (const state of option.states) {
      const el = svg.querySelector(`[id="state_${state.id}"]`);
      if (!el) continue;
      const d = p?.states[state.name];
      el.classList.toggle("never", !d);
      title(el, d ? `${state.name}: ${(100 * d.share).toFixed(1)} % of the time, ${d.activations} activations, mean ${d.mean_ms.toFixed(0)} ms` : `${state.name}: never active`);
    }
    const ids = new Map(option.states.map((st) => [st.name, st.id]));
    for (const t of option.transitions) {
      if (t.stay || t.to === t.from) continue;
      const el = svg.querySelector(`[id="leaf_${ids.get(t.from) ?? -1}_${t.leaf}"]`);
      if (!el) continue;
      const n = p?.transitions.filter((x) => x.from === t.from && x.leaf === t.leaf).reduce((a, x) => a + x.count, 0) ?? 0;
      el.classList.toggle("never", n === 0);
      title(el, `${t.from} → ${t.to} (leaf ${t.leaf}): ${n === 0 ? "never taken" : `taken ${n} times`}`);
    }
  }

  render(changes: Set<SessionEvent>): void {
    this.overlayStateMachine();
    if (changes.has("select") && this.robotName() !== this.robot) void this.refresh();
    else if (performance.now() - this.last > 5000 && this.session.isLive) void this.refresh();
  }
}
