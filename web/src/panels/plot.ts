/// Plots of pinned symbols over the last N seconds of buffered ticks (uPlot), several series,
/// with the timeline cursor drawn as a vertical line. Enum and boolean values plot as their
/// numbers (element index, 0/1). Redrawn at most ~15 times a second. The x axis is timeline
/// time, across hot reloads and resets; a pin names a symbol by its id in the current
/// generation, and ticks of earlier generations are read by that symbol's name in theirs.
import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { cursorHook, timeAxes } from "./timeplot";
import type { Session, SessionEvent } from "../session";
import { h } from "../ui";

export interface Pin {
  robot: number;
  kind: "input" | "output";
  id: number;
}

const COLORS = ["#4fc3f7", "#ffb74d", "#81c784", "#e57373", "#ba68c8", "#fff176", "#4db6ac", "#f06292"];
const KEY = "xabsl-studio.pins.v1";

export class PlotPanel {
  readonly element: HTMLElement;
  private readonly host: HTMLElement;
  private readonly legend: HTMLElement;
  private readonly seconds: HTMLSelectElement;
  private plot: uPlot | null = null;
  private pins: Pin[] = [];
  private plotKey = "";
  private lastDraw = 0;
  /// Symbol ids of pins in earlier generations (`idIn`).
  private readonly ids = new Map<string, number | null>();

  constructor(private readonly session: Session) {
    this.host = h("div.plot-host");
    this.legend = h("div.plot-legend");
    this.seconds = h("select", { "aria-label": "Plot window", title: "Seconds shown" }, ...[10, 20, 30, 60, 120].map((s) => h("option", { value: s }, `${s} s`)));
    this.seconds.value = "20";
    this.seconds.addEventListener("change", () => this.draw(true));
    this.element = h("div.panel.plot-panel", {}, h("div.toolbar", {}, h("strong", {}, "Plot"), this.seconds, this.legend), this.host);
    try {
      const saved = JSON.parse(localStorage.getItem(KEY) ?? "[]") as Pin[];
      if (Array.isArray(saved)) this.pins = saved.filter((p) => typeof p.robot === "number" && typeof p.id === "number");
    } catch {
      this.pins = [];
    }
    new ResizeObserver(() => this.resize()).observe(this.host);
  }

  has(robot: number, kind: Pin["kind"], id: number): boolean {
    return this.pins.some((p) => p.robot === robot && p.kind === kind && p.id === id);
  }

  toggle(robot: number, kind: Pin["kind"], id: number): void {
    if (this.has(robot, kind, id)) this.pins = this.pins.filter((p) => !(p.robot === robot && p.kind === kind && p.id === id));
    else this.pins.push({ robot, kind, id });
    try {
      localStorage.setItem(KEY, JSON.stringify(this.pins));
    } catch {
      /* not remembered */
    }
    this.draw(true);
  }

  private label(p: Pin): string {
    const s = this.session;
    const index = s.hello ? s.indexIn(s.hello.generation, p.robot) : s.indexOf(p.robot); // pins hold current ids
    const list = p.kind === "input" ? index?.description.inputs : index?.description.outputs;
    const name = list?.find((x) => x.id === p.id)?.name ?? `${p.kind} ${p.id}`;
    return `${s.robotInfo(p.robot)?.name ?? p.robot}: ${name}`;
  }

  private resize(): void {
    const rect = this.host.getBoundingClientRect();
    if (this.plot && rect.width > 0 && rect.height > 0) this.plot.setSize({ width: rect.width, height: rect.height });
  }

  render(changes: Set<SessionEvent>): void {
    const force = changes.has("hello") || changes.has("cursor") || changes.has("history");
    this.draw(force);
  }

  private build(): void {
    this.plot?.destroy();
    this.plot = null;
    const rect = this.host.getBoundingClientRect();
    this.legend.replaceChildren(
      ...this.pins.map((p, i) =>
        h(
          "button.legend-item",
          { title: "Unpin", onclick: () => this.toggle(p.robot, p.kind, p.id) },
          h("span.swatch", { style: `background:${COLORS[i % COLORS.length]}` }),
          this.label(p),
          " ×",
        ),
      ),
    );
    if (!this.pins.length) {
      this.host.replaceChildren(h("div.empty", {}, "Pin symbols with “plot” in the Symbols panel to plot them here."));
      return;
    }
    this.host.replaceChildren();
    const opts: uPlot.Options = {
      width: Math.max(100, rect.width),
      height: Math.max(60, rect.height),
      legend: { show: false },
      cursor: { drag: { x: false, y: false } },
      scales: { x: { time: false } },
      axes: timeAxes(1, 56),
      series: [{}, ...this.pins.map((p, i) => ({ label: this.label(p), stroke: COLORS[i % COLORS.length] as string, width: 1.5, points: { show: false } }))],
      hooks: { draw: [cursorHook(this.session)] },
    };
    this.plot = new uPlot(opts, this.data(), this.host);
  }

  private data(): uPlot.AlignedData {
    const newest = this.session.buffer.newest;
    const window = Number(this.seconds.value) * 1000;
    const ticks = newest ? this.session.buffer.range(newest.x - window, newest.x) : [];
    const xs = ticks.map((t) => t.x / 1000);
    const series = this.pins.map((p) =>
      ticks.map((t) => {
        const robot = t.robots.find((a) => a.id === p.robot);
        const id = this.idIn(t.gen, p);
        if (id === null) return null;
        const v = (p.kind === "input" ? robot?.inputs : robot?.outputs)?.[id];
        return v === undefined ? null : typeof v === "boolean" ? (v ? 1 : 0) : v;
      }),
    );
    return [xs, ...series] as uPlot.AlignedData;
  }

  /// The id of pin `p`'s symbol in generation `gen` (by name; null: it has none there).
  private idIn(gen: number, p: Pin): number | null {
    const current = this.session.hello?.generation;
    if (gen === current || current === undefined) return p.id;
    const key = `${gen}|${current}|${p.robot}|${p.kind}|${p.id}`;
    let id = this.ids.get(key);
    if (id === undefined) {
      const list = (index: ReturnType<Session["indexIn"]>) => (p.kind === "input" ? index?.description.inputs : index?.description.outputs);
      const name = list(this.session.indexIn(current, p.robot))?.find((x) => x.id === p.id)?.name;
      id = name === undefined ? null : (list(this.session.indexIn(gen, p.robot))?.find((x) => x.name === name)?.id ?? null);
      if (this.ids.size > 1000) this.ids.clear();
      this.ids.set(key, id);
    }
    return id;
  }

  private draw(force: boolean): void {
    if (this.element.closest("[hidden]")) return;
    const now = performance.now();
    const key = `${this.session.hello?.generation}|${document.documentElement.dataset.theme}|${JSON.stringify(this.pins)}`;
    if (key !== this.plotKey) {
      this.plotKey = key;
      this.build();
      this.lastDraw = now;
      return;
    }
    if (!force && now - this.lastDraw < 66) return;
    this.lastDraw = now;
    this.plot?.setData(this.data());
  }

  /// What the plot shows now: x (timeline seconds) and one array of values per pin (tests, tools).
  points(): { x: number[]; series: Array<Array<number | null>> } {
    const data = this.plot?.data;
    if (!data) return { x: [], series: [] };
    return { x: Array.from(data[0] as ArrayLike<number>), series: data.slice(1).map((s) => Array.from(s as ArrayLike<number | null>)) };
  }
}
