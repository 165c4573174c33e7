/// The facts panel: each derived fact's truth over the buffered time beside the simulator's ground
/// truth (upper band: derived, lower band: truth; red where they differ, hatched while tentative),
/// and "why" for every change: the fact event's cause (the rule, its phase, the signals — which
/// activations and sensor conditions held — the facts it needed, the dwell or confirmation time).
/// Click the chart or an event to go to that moment.
import "./world.css";
import type { Connection } from "../connection";
import type { Session, SessionEvent } from "../session";
import type { Tick } from "../protocol";
import { formatMs, h, setText } from "../ui";
import { type DDScene, worldCommand } from "./world";

export interface FactEvent {
  i: number;
  t: number;
  fact: string;
  value: boolean;
  cause: Record<string, unknown>;
}

const LABEL_W = 120;
const ROW = 18;

/// "why" in words for one event's cause.
export function explainCause(e: FactEvent): string {
  const c = e.cause;
  const parts: string[] = [];
  const phase = String(c.phase ?? "");
  const verb: Record<string, string> = {
    set: "set",
    confirmed: "confirmed",
    tentative: "tentatively seen (waits for confirmation)",
    retracted: "retracted before confirmation",
    cleared: "cleared",
    implied: "cleared as implied",
    exclusive: "cleared (exclusive with another fact)",
    forced: "set by hand",
  };
  parts.push(`${e.value ? "+" : "−"}${e.fact}: ${verb[phase] ?? phase}`);
  if (c.rule !== undefined && phase !== "forced") parts.push(`by rule ${String(c.rule)}`);
  if (c.by !== undefined) parts.push(`because ${String(c.by)} became true`);
  const signals = c.signals as Record<string, number> | undefined;
  if (signals && Object.keys(signals).length) parts.push(`while ${Object.entries(signals).map(([k, v]) => `${k}=${typeof v === "number" ? v.toFixed(2) : String(v)}`).join(", ")}`);
  const facts = c.facts as string[] | undefined;
  if (facts?.length) parts.push(`given ${facts.join(", ")}`);
  if (typeof c.held === "number") parts.push(`held ${c.held.toFixed(2)} s`);
  return parts.join(" · ");
}

export class FactsPanel {
  readonly element: HTMLElement;
  private readonly canvas: HTMLCanvasElement;
  private readonly ctx: CanvasRenderingContext2D;
  private readonly list: HTMLElement;
  private readonly why: HTMLElement;
  private readonly agreement: HTMLElement;
  private events: FactEvent[] = [];
  private total = 0;
  private fetching = false;
  private selectedFact: string | null = null;
  private selectedEvent: FactEvent | null = null;
  private t0 = 0;
  private t1 = 1;
  private lastDraw = 0;
  private listKey = "";
  private generation = -1;

  constructor(
    private readonly session: Session,
    private readonly connection: Connection,
  ) {
    this.canvas = h("canvas.facts-canvas", { "aria-label": "Derived facts against ground truth over time; click to go to that moment" });
    this.ctx = this.canvas.getContext("2d") as CanvasRenderingContext2D;
    this.list = h("ol.fact-events", { "aria-label": "Fact events" });
    this.why = h("div.fact-why", { "aria-live": "polite" });
    this.agreement = h("span.muted");
    this.element = h(
      "div.panel.facts-panel",
      {},
      h("div.toolbar", {}, h("strong", {}, "Facts"), h("span.muted", {}, "upper: derived · lower: truth · red: differ"), this.agreement),
      h("div.facts-body", {}, h("div.facts-chart", {}, this.canvas), this.why, h("div.dd-title", {}, "changes (click one for why)"), this.list),
    );
    this.canvas.addEventListener("click", (ev) => this.click(ev));
  }

  render(changes: Set<SessionEvent>): void {
    const gen = this.session.hello?.generation ?? -1;
    if (changes.has("hello") && gen !== this.generation) {
      this.generation = gen;
      this.events = [];
      this.total = 0;
      this.listKey = "";
    }
    if (this.element.closest("[hidden]")) return;
    const live = this.session.live?.scene as DDScene | null | undefined;
    if (live?.fact_events !== undefined && live.fact_events > this.total) void this.fetch();
    const now = performance.now();
    if (changes.has("cursor") || changes.has("hello") || changes.has("history") || now - this.lastDraw > 100) {
      this.lastDraw = now;
      this.drawChart();
      this.drawList();
    }
  }

  private async fetch(): Promise<void> {
    if (this.fetching) return;
    this.fetching = true;
    try {
      const result = await worldCommand<{ total: number; events: FactEvent[] }>(this.connection, "fact_events", { since: this.total });
      this.events.push(...result.events.filter((e) => e.i >= this.total));
      this.total = result.total;
      this.listKey = "";
    } catch {
      /* retried with the next frame */
    } finally {
      this.fetching = false;
    }
  }

  private facts(): string[] {
    const f = this.session.scene?.facts;
    return Array.isArray(f) ? (f as string[]) : [];
  }

  private ticks(): Tick[] {
    return this.session.buffer.all as Tick[];
  }

  private click(ev: MouseEvent): void {
    const rect = this.canvas.getBoundingClientRect();
    const x = ev.clientX - rect.left;
    const y = ev.clientY - rect.top;
    const facts = this.facts();
    const row = Math.floor(y / ROW);
    if (x < LABEL_W) {
      const fact = facts[row] ?? null;
      this.selectedFact = fact === this.selectedFact ? null : fact;
      this.listKey = "";
      this.drawList();
      return;
    }
    const t = this.t0 + ((x - LABEL_W) / Math.max(1, rect.width - LABEL_W - 4)) * (this.t1 - this.t0);
    this.session.setCursor(Math.round(t));
  }

  private drawChart(): void {
    const facts = this.facts();
    const ticks = this.ticks();
    const width = Math.max(200, this.canvas.parentElement?.clientWidth ?? 400);
    const height = Math.max(ROW, facts.length * ROW);
    const dpr = window.devicePixelRatio || 1;
    if (this.canvas.width !== Math.round(width * dpr) || this.canvas.height !== Math.round(height * dpr)) {
      this.canvas.width = Math.round(width * dpr);
      this.canvas.height = Math.round(height * dpr);
      this.canvas.style.width = `${width}px`;
      this.canvas.style.height = `${height}px`;
    }
    const ctx = this.ctx;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, width, height);
    const style = getComputedStyle(document.documentElement);
    const fg = style.getPropertyValue("--fg").trim() || "#ddd";
    const muted = style.getPropertyValue("--grid").trim() || "rgba(128,128,128,0.2)";
    ctx.font = "11px ui-monospace, monospace";
    if (!ticks.length) return;
    this.t0 = (ticks[0] as Tick).x;
    this.t1 = Math.max(this.t0 + 1, (ticks[ticks.length - 1] as Tick).x);
    const plotW = width - LABEL_W - 4;
    const xOf = (t: number): number => LABEL_W + ((t - this.t0) / (this.t1 - this.t0)) * plotW;
    let agree = 0;
    let total = 0;
    facts.forEach((fact, row) => {
      const y = row * ROW;
      ctx.fillStyle = fact === this.selectedFact ? "#ffd54a" : fg;
      ctx.fillText(fact, 4, y + 12);
      ctx.fillStyle = muted;
      ctx.fillRect(LABEL_W, y + 2, plotW, ROW - 4);
    });
    for (let i = 0; i < ticks.length; i++) {
      const tick = ticks[i] as Tick;
      const scene = tick.scene as DDScene | null;
      if (!scene?.facts || !scene.truth) continue;
      const x0 = xOf(tick.x);
      const x1 = i + 1 < ticks.length ? xOf((ticks[i + 1] as Tick).x) : x0 + 1;
      const derived = new Set(scene.facts);
      const truth = new Set(scene.truth);
      const tentative = new Set(scene.tentative ?? []);
      facts.forEach((fact, row) => {
        const y = row * ROW;
        const d = derived.has(fact);
        const g = truth.has(fact);
        total++;
        if (d === g) agree++;
        const differ = d !== g;
        if (d) {
          ctx.fillStyle = differ ? "#e5533d" : "#4fa3ff";
          ctx.fillRect(x0, y + 2, Math.max(1, x1 - x0), 7);
        } else if (tentative.has(fact)) {
          ctx.fillStyle = "rgba(79,163,255,0.35)";
          ctx.fillRect(x0, y + 2, Math.max(1, x1 - x0), 7);
        }
        if (g) {
          ctx.fillStyle = differ ? "#e5533d" : "#81c784";
          ctx.fillRect(x0, y + 10, Math.max(1, x1 - x0), 6);
        }
      });
    }
    // Fact events as ticks on their row; the cursor as a line.
    const row = new Map(facts.map((f, i) => [f, i]));
    ctx.fillStyle = fg;
    for (const e of this.events) {
      const r = row.get(e.fact);
      if (r === undefined || e.t < this.t0) continue;
      ctx.fillRect(xOf(e.t) - 0.5, r * ROW + 1, 1.5, ROW - 2);
    }
    const cursor = this.session.cursor;
    if (cursor !== null) {
      ctx.strokeStyle = "#ffd54a";
      ctx.lineWidth = 2;
      ctx.beginPath();
      ctx.moveTo(xOf(cursor), 0);
      ctx.lineTo(xOf(cursor), height);
      ctx.stroke();
    }
    setText(this.agreement, total ? `derived = truth on ${((100 * agree) / total).toFixed(1)}% of fact-ticks shown` : "");
  }

  private drawList(): void {
    const shown = this.events.filter((e) => this.selectedFact === null || e.fact === this.selectedFact).slice(-200).reverse();
    const key = `${this.events.length}|${this.selectedFact}|${this.selectedEvent?.i}`;
    if (key === this.listKey) return;
    this.listKey = key;
    this.list.replaceChildren(
      ...shown.map((e) =>
        h(
          "li.fact-event",
          { class: `fact-event${e === this.selectedEvent ? " selected" : ""}`, "data-fact": e.fact, "data-phase": String(e.cause.phase ?? "") },
          h(
            "button.link",
            {
              title: "Why, and go to this moment",
              onclick: () => {
                this.selectedEvent = e;
                this.session.seekTick(e.t);
                this.listKey = "";
                this.drawList();
              },
            },
            `${formatMs(e.t)} ${e.value ? "+" : "−"}${e.fact}`,
          ),
          h("span.muted", {}, ` ${String(e.cause.phase ?? "")}`),
        ),
      ),
    );
    const sel = this.selectedEvent;
    this.why.replaceChildren(
      sel ? h("div", {}, h("strong", {}, "why: "), h("span.fact-why-text", {}, explainCause(sel))) : h("span.muted", {}, this.events.length ? "click a change to see why it happened" : "no fact changed yet"),
    );
  }
}
