/// The timeline: for the buffered history (live ticks plus the server's ring buffer), one row per
/// robot (the team overview: root option and state) and one row per option of the selected robot,
/// coloured by state. Click or drag to scrub: every panel shows that moment. ←/→ step a tick
/// (Shift: ten), Home goes to the oldest, End or L back to live.
import { buildRobotTimeline, buildTeamTimeline, segmentHue, type TimelineRow } from "../timeline";
import type { Session, SessionEvent } from "../session";
import { formatClock, formatMs, h } from "../ui";

const LABEL_W = 150;
const AXIS_H = 18;
const TEAM_ROW = 13;
const OPTION_ROW = 17;
const GAP = 16;

export class TimelinePanel {
  readonly element: HTMLElement;
  private readonly canvas: HTMLCanvasElement;
  private readonly ctx: CanvasRenderingContext2D;
  private readonly scroller: HTMLElement;
  private readonly liveButton: HTMLButtonElement;
  private readonly info: HTMLElement;
  private team: TimelineRow[] = [];
  private rows: TimelineRow[] = [];
  private builtAt = 0;
  private t0 = 0;
  private t1 = 1;
  private width = 300;
  private dirty = true;
  /// Breakpoint hits, marked on the axis (red) at their time.
  private hits: ReadonlyArray<{ t: number; robot: number; description: string }> = [];
  /// Where the running world was forked ("Run from here", panels/fork.ts): marked at its time.
  private fork: number | null = null;
  /// The toolbar, for controls of other modules (panels/fork.ts).
  readonly toolbar: HTMLElement;

  constructor(
    private readonly session: Session,
    private readonly openOption: (id: number) => void,
  ) {
    this.canvas = h("canvas.timeline-canvas", { tabindex: 0, "aria-label": "Timeline: click or drag to go back in time; End returns to live" });
    this.ctx = this.canvas.getContext("2d") as CanvasRenderingContext2D;
    this.liveButton = h("button.live", { title: "Back to live (L or End)", onclick: () => this.session.setCursor(null) }, "● Live");
    this.info = h("span.muted");
    this.scroller = h("div.timeline-scroll", {}, this.canvas);
    this.toolbar = h("div.toolbar", {}, h("strong", {}, "Timeline"), this.liveButton, this.info);
    this.element = h("div.panel.timeline-panel", {}, this.toolbar, this.scroller);
    this.canvas.addEventListener("pointerdown", (ev) => this.pointer(ev));
    this.canvas.addEventListener("keydown", (ev) => this.key(ev));
    new ResizeObserver(() => {
      this.dirty = true;
    }).observe(this.scroller);
  }

  /// Mark breakpoint hits (a red triangle and line at each hit's time).
  markHits(hits: ReadonlyArray<{ t: number; robot: number; description: string }>): void {
    this.hits = hits;
    this.dirty = true;
  }

  /// Mark the fork point (a violet line at its time; null: no fork).
  markFork(t: number | null): void {
    if (t === this.fork) return;
    this.fork = t;
    this.dirty = true;
  }

  private key(ev: KeyboardEvent): void {
    const n = ev.shiftKey ? 10 : 1;
    if (ev.key === "ArrowLeft") this.session.stepCursor(-n);
    else if (ev.key === "ArrowRight") this.session.stepCursor(n);
    else if (ev.key === "Home") this.session.setCursor(this.session.buffer.oldest?.t ?? null);
    else if (ev.key === "End") this.session.setCursor(null);
    else return;
    ev.preventDefault();
  }

  private timeAt(x: number): number {
    return this.t0 + ((x - LABEL_W) / Math.max(1, this.width - LABEL_W - 6)) * (this.t1 - this.t0);
  }

  private pointer(ev: PointerEvent): void {
    const rect = this.canvas.getBoundingClientRect();
    const x = ev.clientX - rect.left;
    const y = ev.clientY - rect.top;
    this.canvas.focus();
    if (x < LABEL_W) {
      this.clickLabel(y);
      return;
    }
    this.session.setCursor(this.timeAt(x));
    this.canvas.setPointerCapture(ev.pointerId);
    const move = (e: PointerEvent): void => this.session.setCursor(this.timeAt(e.clientX - this.canvas.getBoundingClientRect().left));
    const up = (): void => {
      this.canvas.removeEventListener("pointermove", move);
      this.canvas.removeEventListener("pointerup", up);
    };
    this.canvas.addEventListener("pointermove", move);
    this.canvas.addEventListener("pointerup", up);
  }

  private clickLabel(y: number): void {
    let top = AXIS_H + GAP;
    for (const row of this.rows) {
      if (y >= top && y < top + OPTION_ROW) {
        if (row.kind === "option") this.openOption(row.id);
        return;
      }
      top += OPTION_ROW;
    }
    if (!this.rows.length) top += OPTION_ROW;
    top += GAP;
    for (const row of this.team) {
      if (y >= top && y < top + TEAM_ROW) return this.session.selectRobot(row.id);
      top += TEAM_ROW;
    }
  }

  render(changes: Set<SessionEvent>): void {
    const session = this.session;
    this.liveButton.classList.toggle("on", session.isLive);
    this.liveButton.textContent = session.isLive ? "● Live" : "▶ Back to live";
    const now = performance.now();
    const structural = changes.has("hello") || changes.has("history") || changes.has("select");
    if (structural || (changes.has("tick") && session.isLive && now - this.builtAt > 250)) {
      this.builtAt = now;
      const ticks = session.buffer.all;
      this.team = buildTeamTimeline(ticks, session.robots.filter((a) => a.program !== null), (id) => session.indexOf(id));
      this.rows = buildRobotTimeline(ticks, session.selectedRobot, session.indexOf(session.selectedRobot));
      this.t0 = session.buffer.oldest?.t ?? 0;
      this.t1 = Math.max(this.t0 + 1, session.buffer.newest?.t ?? 1);
      this.dirty = true;
    }
    if (changes.has("cursor")) this.dirty = true;
    if (this.dirty && !this.element.closest("[hidden]")) {
      this.dirty = false;
      this.draw();
    }
  }

  private draw(): void {
    const session = this.session;
    const dpr = window.devicePixelRatio || 1;
    const width = Math.max(200, this.scroller.clientWidth);
    const height = AXIS_H + GAP + this.team.length * TEAM_ROW + GAP + Math.max(1, this.rows.length) * OPTION_ROW + 6;
    this.width = width;
    if (this.canvas.width !== Math.round(width * dpr) || this.canvas.height !== Math.round(height * dpr)) {
      this.canvas.width = Math.round(width * dpr);
      this.canvas.height = Math.round(height * dpr);
      this.canvas.style.width = `${width}px`;
      this.canvas.style.height = `${height}px`;
    }
    const ctx = this.ctx;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    const style = getComputedStyle(document.documentElement);
    const fg = style.getPropertyValue("--fg").trim() || "#ddd";
    const muted = style.getPropertyValue("--muted").trim() || "#999";
    const dark = document.documentElement.dataset.theme !== "light";
    ctx.clearRect(0, 0, width, height);
    ctx.font = "11px system-ui, sans-serif";
    ctx.textBaseline = "middle";
    const span = this.t1 - this.t0;
    const xOf = (t: number): number => LABEL_W + ((t - this.t0) / span) * (width - LABEL_W - 6);
    // Axis: a tick every "nice" number of seconds.
    ctx.fillStyle = muted;
    ctx.strokeStyle = dark ? "rgba(255,255,255,0.08)" : "rgba(0,0,0,0.08)";
    const stepS = [0.5, 1, 2, 5, 10, 20, 30, 60].find((s) => (s * 1000 * (width - LABEL_W)) / span > 60) ?? 60;
    for (let s = Math.ceil(this.t0 / 1000 / stepS) * stepS; s * 1000 <= this.t1; s += stepS) {
      const x = xOf(s * 1000);
      ctx.fillText(formatMs(s * 1000), x + 2, AXIS_H / 2);
      ctx.beginPath();
      ctx.moveTo(x, AXIS_H);
      ctx.lineTo(x, height);
      ctx.stroke();
    }
    let top = AXIS_H;
    const drawRow = (row: TimelineRow, y: number, h: number, label: string, indent: number, selected: boolean): void => {
      ctx.fillStyle = selected ? (dark ? "rgba(255,213,74,0.15)" : "rgba(255,193,7,0.2)") : "transparent";
      ctx.fillRect(0, y, width, h);
      ctx.fillStyle = selected ? fg : muted;
      ctx.fillText(label.length > 22 ? `${label.slice(0, 21)}…` : label, 4 + indent, y + h / 2);
      for (const seg of row.segments) {
        const x0 = Math.max(LABEL_W, xOf(seg.t0));
        const x1 = Math.min(width - 6, xOf(seg.t1));
        if (x1 <= x0) continue;
        ctx.fillStyle = `hsl(${segmentHue(seg.key)} 55% ${dark ? 45 : 62}%)`;
        ctx.fillRect(x0, y + 1, Math.max(1, x1 - x0 - 0.5), h - 2);
        if (x1 - x0 > 40 && h >= 14) {
          ctx.fillStyle = dark ? "#fff" : "#111";
          const text = seg.label;
          const max = Math.floor((x1 - x0 - 6) / 6);
          ctx.fillText(text.length > max ? `${text.slice(0, Math.max(1, max - 1))}…` : text, x0 + 3, y + h / 2);
        }
      }
    };
    ctx.fillStyle = fg;
    ctx.fillText(`${session.robotInfo(session.selectedRobot)?.name ?? ""}: options and their states`, 4, top + GAP / 2);
    top += GAP;
    if (!this.rows.length) {
      ctx.fillStyle = muted;
      ctx.fillText(session.buffer.length ? "nothing active in the buffered history" : "waiting for frames…", LABEL_W, top + OPTION_ROW / 2);
    }
    const openOption = session.openOption;
    for (const row of this.rows) {
      drawRow(row, top, OPTION_ROW, row.kind === "behavior" ? `● ${row.label}` : row.label, row.depth * 8, row.kind === "option" && row.id === openOption);
      top += OPTION_ROW;
    }
    if (!this.rows.length) top += OPTION_ROW;
    ctx.fillStyle = fg;
    ctx.fillText("Team (root option/state)", 4, top + GAP / 2);
    top += GAP;
    for (const row of this.team) {
      drawRow(row, top, TEAM_ROW, row.label, 0, row.id === session.selectedRobot);
      top += TEAM_ROW;
    }
    ctx.fillStyle = "#e53935";
    ctx.strokeStyle = "rgba(229,57,53,0.6)";
    for (const hit of this.hits) {
      if (hit.t < this.t0 || hit.t > this.t1) continue;
      const x = xOf(hit.t);
      ctx.beginPath();
      ctx.moveTo(x - 5, 0);
      ctx.lineTo(x + 5, 0);
      ctx.lineTo(x, 8);
      ctx.closePath();
      ctx.fill();
      ctx.beginPath();
      ctx.moveTo(x, 8);
      ctx.lineTo(x, height);
      ctx.stroke();
    }
    this.canvas.dataset.hits = String(this.hits.length);
    if (this.fork !== null && this.fork >= this.t0 && this.fork <= this.t1) {
      const x = xOf(this.fork);
      ctx.fillStyle = ctx.strokeStyle = "#9c6ade";
      ctx.fillText("⑂", x + 3, 7);
      ctx.setLineDash([4, 3]);
      ctx.beginPath();
      ctx.moveTo(x, 0);
      ctx.lineTo(x, height);
      ctx.stroke();
      ctx.setLineDash([]);
    }
    this.canvas.dataset.fork = this.fork === null ? "" : String(this.fork);
    const cursor = session.cursor;
    if (cursor !== null) {
      const x = xOf(cursor);
      ctx.strokeStyle = "#ffd54a";
      ctx.lineWidth = 2;
      ctx.beginPath();
      ctx.moveTo(x, 0);
      ctx.lineTo(x, height);
      ctx.stroke();
      ctx.lineWidth = 1;
    }
    const tick = session.view;
    this.info.textContent = `${formatMs(this.t1 - this.t0)} buffered${tick ? ` · showing t = ${formatClock(tick.t)}` : ""}${session.isLive ? "" : " (scrubbed: every panel shows this moment)"}`;
  }
}
