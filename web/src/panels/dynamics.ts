/// The Dual Dynamics panel: every behavior's activation α(t); for one selected behavior the terms
/// of each tick's Δα (relaxation to the target, the plan's operator-coupling bias, noise) and the
/// parts of its drive u (sensors, self-excitation, the other behaviors, bias); the switch
/// variables s_OP(t); the fused actuator commands with each behavior's share α·λ·(m* − m).
/// Click a plot to go to that moment (as on the timeline); the bars show the tick in view.
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { cursorHook, timeAxes } from "./timeplot";
import "./world.css";
import type { Session, SessionEvent } from "../session";
import type { Tick } from "../protocol";
import { h, setText } from "../ui";
import type { Connection } from "../connection";
import { ModelEditor } from "./modeleditor";
import { commandsOf, type DDScene, type DDStatic, ddOf, SERIES } from "./world";

interface Chart {
  host: HTMLElement;
  plot: uPlot | null;
  key: string;
  /// Plot height in px (the legend goes below it, so the host grows with it).
  height: number;
}

const TERM_LABELS: Record<string, string> = {
  relax: "target λ(T−α)",
  plan: "plan bias Σ s·c·(Z−α)",
  noise: "noise",
};
const DRIVE_LABELS: Record<string, string> = { sensors: "sensors", self: "self-excitation", others: "inhibition / excitation by others", bias: "bias" };

/// Index of the largest activation (0 without data).
function dominant(alpha: number[] | undefined): number {
  let best = 0;
  (alpha ?? []).forEach((a, i) => {
    if (a > (alpha?.[best] ?? 0)) best = i;
  });
  return best;
}

export class DynamicsPanel {
  readonly element: HTMLElement;
  private readonly behavior: HTMLSelectElement;
  private readonly windowSelect: HTMLSelectElement;
  private readonly alpha: Chart;
  private readonly terms: Chart;
  private readonly switches: Chart;
  private readonly drive: HTMLElement;
  private readonly fusion: HTMLElement;
  private readonly termsTitle: HTMLElement;
  private dd: DDStatic | null = null;
  private lastDraw = 0;
  private readonly model: ModelEditor;
  private generation = -1;

  constructor(
    private readonly session: Session,
    connection: Connection,
  ) {
    this.model = new ModelEditor(connection);
    this.behavior = h("select", { "aria-label": "Behavior whose Δα terms are shown", title: "Behavior whose Δα terms are shown" });
    this.behavior.addEventListener("change", () => this.draw(true));
    this.windowSelect = h("select", { "aria-label": "Seconds shown" }, ...[10, 20, 30, 60].map((s) => h("option", { value: s }, `${s} s`)));
    this.windowSelect.value = "20";
    this.windowSelect.addEventListener("change", () => this.draw(true));
    const chart = (cls: string, height: number): Chart => ({ host: h("div.dd-chart", { class: `dd-chart ${cls}` }), plot: null, key: "", height });
    this.alpha = chart("dd-alpha", 150);
    this.terms = chart("dd-terms", 130);
    this.switches = chart("dd-switches", 110);
    this.drive = h("div.dd-drive");
    this.fusion = h("div.dd-fusion");
    this.termsTitle = h("span", {}, "Δα");
    this.element = h(
      "div.panel.dynamics-panel",
      {},
      h("div.toolbar", {}, h("strong", {}, "Dual Dynamics"), h("span.muted", {}, "terms of"), this.behavior, this.windowSelect, h("span.muted", {}, "click a plot to go to that moment")),
      h(
        "div.dd-body",
        {},
        h("div.dd-section", {}, h("div.dd-title", {}, "activation α(t)"), this.alpha.host),
        h("div.dd-section", {}, h("div.dd-title", {}, this.termsTitle), this.terms.host, this.drive),
        h("div.dd-section", {}, h("div.dd-title", {}, "switch variables s_OP(t)"), this.switches.host),
        h("div.dd-section", {}, h("div.dd-title", {}, "actuator fusion: each behavior's share α·λ·(m* − m) (1/s)"), this.fusion),
        this.model.element,
      ),
    );
    new ResizeObserver(() => this.resize()).observe(this.element);
  }

  render(changes: Set<SessionEvent>): void {
    const gen = this.session.hello?.generation ?? -1;
    if (changes.has("hello") && gen !== this.generation) {
      this.generation = gen;
      // A reload or reset: the model editor keeps unsaved text only within one generation.
      this.model.setCommands(commandsOf(this.session.scene));
      this.dd = ddOf(this.session.scene);
      const names = this.dd?.behaviors ?? [];
      const keep = this.behavior.value;
      this.behavior.replaceChildren(h("option", { value: "" }, "the dominant behavior"), ...names.map((b) => h("option", { value: b }, b)));
      this.behavior.value = names.includes(keep) ? keep : "";
      this.alpha.key = this.terms.key = this.switches.key = "";
    }
    this.draw(changes.has("hello") || changes.has("cursor") || changes.has("history"));
  }

  private resize(): void {
    for (const c of [this.alpha, this.terms, this.switches]) {
      const r = c.host.getBoundingClientRect();
      if (c.plot && r.width > 0) c.plot.setSize({ width: r.width, height: c.height });
    }
  }

  private ticks(): Tick[] {
    const newest = this.session.buffer.newest;
    const span = Number(this.windowSelect.value) * 1000;
    return newest ? this.session.buffer.range(newest.x - span, newest.x) : [];
  }

  private draw(force: boolean): void {
    if (this.element.closest("[hidden]") || !this.dd) return;
    const now = performance.now();
    if (!force && now - this.lastDraw < 66) return;
    this.lastDraw = now;
    const dd = this.dd;
    const ticks = this.ticks();
    const xs = ticks.map((t) => t.x / 1000);
    const scenes = ticks.map((t) => t.scene as DDScene | null);
    // α of every behavior.
    this.chart(
      this.alpha,
      dd.behaviors,
      [xs, ...dd.behaviors.map((_, i) => scenes.map((s) => s?.alpha?.[i] ?? null))],
      { min: 0, max: 1 },
    );
    // Δα terms of the selected behavior.
    const b = this.behavior.value ? Math.max(0, dd.behaviors.indexOf(this.behavior.value)) : dominant((this.session.view?.scene as DDScene | null | undefined)?.alpha);
    const termNames = ["relax", "plan", "noise"];
    setText(this.termsTitle, `Δα of ${dd.behaviors[b] ?? ""} per tick, by term`);
    this.chart(
      this.terms,
      [...termNames.map((k) => TERM_LABELS[k] ?? k), "Δα"],
      [
        xs,
        ...termNames.map((k) => scenes.map((s) => s?.terms?.[k]?.[b] ?? null)),
        scenes.map((s) => (s?.terms ? termNames.reduce((acc, k) => acc + (s.terms?.[k]?.[b] ?? 0), 0) : null)),
      ],
    );
    // s_OP of every operator seen in the window.
    const ops = [...new Set(scenes.flatMap((s) => Object.keys(s?.s ?? {})))].sort();
    this.chart(this.switches, ops, [xs, ...ops.map((op) => scenes.map((s) => s?.s?.[op] ?? 0))], { min: 0, max: 1 });
    this.drawTick(b);
  }

  /// The drive decomposition and the fusion bars of the tick in view.
  private drawTick(b: number): void {
    const dd = this.dd as DDStatic;
    const scene = this.session.view?.scene as DDScene | null | undefined;
    const terms = scene?.terms;
    if (!terms) {
      this.drive.replaceChildren(h("span.muted", {}, "no Dual Dynamics data in this tick"));
      this.fusion.replaceChildren();
      return;
    }
    const f = (v: number | undefined): string => (v === undefined ? "–" : v.toFixed(3));
    const alpha = scene?.alpha?.[b];
    const theta = dd.theta[b];
    this.drive.replaceChildren(
      h(
        "div.dd-drive-row",
        { "data-behavior": dd.behaviors[b] ?? "" },
        h("span", {}, `α = ${f(alpha)}`),
        h("span", {}, `u = ${f(terms.u?.[b])}`),
        ...Object.entries(DRIVE_LABELS).map(([k, label]) => h("span.dd-part", { "data-term": k }, `${label} ${f(terms[k]?.[b])}`)),
        h("span", {}, `→ T = S(k(u − θ=${f(theta)})) = ${f(terms.T?.[b])}`),
        ...["relax", "plan", "noise"].map((k) => h("span.dd-part", { "data-term": k }, `${TERM_LABELS[k]} ${f(terms[k]?.[b])}`)),
      ),
    );
    const rows: HTMLElement[] = [];
    for (const [act, fu] of Object.entries(scene?.fusion ?? {})) {
      const total = fu.shares.reduce((a, v) => a + Math.abs(v), 0) + Math.abs(fu.decay) || 1;
      const bar = h("div.dd-bar");
      fu.shares.forEach((v, i) => {
        if (Math.abs(v) < 1e-4) return;
        bar.append(
          h("span.dd-share", {
            style: `width:${(100 * Math.abs(v)) / total}%;background:${SERIES[i % SERIES.length]};opacity:${v < 0 ? 0.55 : 1}`,
            title: `${dd.behaviors[i]}: ${v.toFixed(3)}`,
          }),
        );
      });
      if (Math.abs(fu.decay) > 1e-4) bar.append(h("span.dd-share.decay", { style: `width:${(100 * Math.abs(fu.decay)) / total}%`, title: `decay: ${fu.decay.toFixed(3)}` }));
      rows.push(h("div.dd-fusion-row", { "data-actuator": act }, h("span.dd-act", {}, act), h("span.dd-val", {}, fu.value.toFixed(3)), bar));
    }
    rows.push(
      h("div.dd-legend", {}, ...dd.behaviors.map((name, i) => h("span", {}, h("span.swatch", { style: `background:${SERIES[i % SERIES.length]}` }), name)), h("span", {}, h("span.swatch.decay"), "decay")),
    );
    this.fusion.replaceChildren(...rows);
  }

  private chart(c: Chart, labels: string[], data: (number | null)[][], range?: { min: number; max: number }): void {
    const key = `${document.documentElement.dataset.theme}|${labels.join(",")}`;
    if (key !== c.key || !c.plot) {
      c.key = key;
      c.plot?.destroy();
      c.host.replaceChildren();
      const rect = c.host.getBoundingClientRect();
      const opts: uPlot.Options = {
        width: Math.max(100, rect.width),
        height: c.height,
        legend: { show: true, live: false },
        cursor: { drag: { x: false, y: false } },
        scales: { x: { time: false }, y: range ? { range: [range.min, range.max] } : {} },
        axes: timeAxes(0, 48),
        series: [{}, ...labels.map((label, i) => ({ label, stroke: SERIES[i % SERIES.length] as string, width: 1.4, points: { show: false } }))],
        hooks: { draw: [cursorHook(this.session)] },
      };
      const plot = new uPlot(opts, data as uPlot.AlignedData, c.host);
      plot.over.addEventListener("click", (ev) => {
        const t = plot.posToVal(ev.offsetX, "x");
        if (Number.isFinite(t)) this.session.setCursor(Math.round(t * 1000));
      });
      c.plot = plot;
      return;
    }
    c.plot.setData(data as uPlot.AlignedData);
  }
}
