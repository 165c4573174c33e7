/// The timeline: for the buffered history (live ticks plus the server's ring buffer), one row per
/// robot (the team overview: root option and state) and one row per option of the selected robot,
/// coloured by state. Click or drag to scrub: every panel shows that moment. ←/→ step a tick
/// (Shift: ten), Home goes to the oldest, End or L back to live.
///
/// The history goes across hot reloads and resets (timeline times, `Tick.x`): each new
/// generation is marked on the axis by its reason (reload, reset, fork, ...); clicking a mark
/// shows what changed (panels/changes.ts). The matches of a search (panels/search.ts) are green
/// bands on the axis and on their robot's team row.
import type { DescriptionIndex } from "../description";
import { segmentHue, TimelineBuilder, type TimelineRow } from "../timeline";
import type { Session, SessionEvent } from "../session";
import { formatClock, formatMs, h } from "../ui";
import { ChangesDialog, type Mark } from "./changes";
import type { Match } from "./search";

const LABEL_W = 150;
const AXIS_H = 18;
const TEAM_ROW = 13;
const OPTION_ROW = 17;
const GAP = 16;
/// Colours of generation marks by reason (others: MARK_OTHER).
const MARK_COLORS: Record<string, string> = { reload: "#42a5f5", reset: "#ffa726", fork: "#9c6ade", host_gone: "#e53935", host_back: "#43a047" };
const MARK_OTHER = "#ab47bc";
/// The letter on a mark's flag by reason (others: the reason's first letter).
const MARK_LETTERS: Record<string, string> = { reload: "E", reset: "0", fork: "F", host_gone: "×", host_back: "A" };

export class TimelinePanel {
  readonly element: HTMLElement;
  private readonly canvas: HTMLCanvasElement;
  private readonly ctx: CanvasRenderingContext2D;
  private readonly scroller: HTMLElement;
  private readonly liveButton: HTMLButtonElement;
  private readonly info: HTMLElement;
  /// The rows, kept up to date with the buffer tick by tick (a full build only on structural changes).
  private readonly model = new TimelineBuilder();
  /// Description indexes per generation and robot, until the next structural change.
  private readonly indexes = new Map<number, DescriptionIndex | null>();
  private readonly indexIn = (id: number, gen: number): DescriptionIndex | null => {
    const key = gen * 65536 + id;
    let index = this.indexes.get(key);
    if (index === undefined) this.indexes.set(key, (index = this.session.indexIn(gen, id)));
    return index;
  };
  private team: TimelineRow[] = [];
  private rows: TimelineRow[] = [];
  private builtAt = 0;
  private t0 = 0;
  private t1 = 1;
  private width = 300;
  /// The scroller's client width as the ResizeObserver last saw it (0: not yet, or hidden then).
  private scrollerWidth = 0;
  private dirty = true;
  /// Breakpoint hits, marked on the axis (red) at their time.
  private hits: ReadonlyArray<{ t: number; seq?: number; robot: number; description: string }> = [];
  /// The intervals a search found, drawn as green bands (panels/search.ts).
  private matches: ReadonlyArray<Match> = [];
  /// Where a generation started in the buffered history (timeline time), as drawn; a fork is
  /// one (reason "fork"), so "Run from here" needs no mark of its own.
  private marks: Array<Mark & { x: number }> = [];
  /// The first divergence of two compared recordings (a violet diamond and line at its tick).
  private divergence: { seq: number; t: number; agent: string } | null = null;
  /// The dialog a click on a mark opens (in the page once the first mark is clicked).
  readonly changes = new ChangesDialog();
  /// The toolbar, for controls of other modules (panels/fork.ts).
  readonly toolbar: HTMLElement;

  constructor(
    private readonly session: Session,
    private readonly openOption: (id: number) => void,
  ) {
    this.canvas = h("canvas.timeline-canvas", { tabindex: 0, "aria-label": "Timeline: click or drag to go back in time; End returns to live" });
    this.ctx = this.canvas.getContext("2d") as CanvasRenderingContext2D;
    this.liveButton = h("button.live", { title: "Back to live (L or End)", onclick: () => this.session.setCursor(null) }, "● Live");
    this.info = h("span.muted.timeline-info");
    this.scroller = h("div.timeline-scroll", {}, this.canvas);
    this.toolbar = h("div.toolbar", {}, h("strong", {}, "Timeline"), this.liveButton, this.info);
    this.element = h("div.panel.timeline-panel", {}, this.toolbar, this.scroller);
    this.canvas.addEventListener("pointerdown", (ev) => this.pointer(ev));
    this.canvas.addEventListener("keydown", (ev) => this.key(ev));
    new ResizeObserver(() => {
      // Layout is fresh here: reading the width now spares each draw a forced layout (the
      // draw comes in the next frame, as it did; drawing here could resize the scroller again).
      this.scrollerWidth = this.scroller.clientWidth;
      this.dirty = true;
    }).observe(this.scroller);
  }

  /// Mark where two compared recordings first act differently (the Compare view's; null: none).
  markDivergence(divergence: { seq: number; t: number; agent: string } | null): void {
    this.divergence = divergence;
    this.dirty = true;
  }

  /// Mark breakpoint hits (a red triangle and line at each hit's time).
  markHits(hits: ReadonlyArray<{ t: number; seq?: number; robot: number; description: string }>): void {
    this.hits = hits;
    this.dirty = true;
  }

  /// Mark the intervals of a search (an empty list removes the marks).
  markMatches(matches: ReadonlyArray<Match>): void {
    this.matches = matches;
    this.dirty = true;
  }

  private key(ev: KeyboardEvent): void {
    const n = ev.shiftKey ? 10 : 1;
    if (ev.key === "ArrowLeft") this.session.stepCursor(-n);
    else if (ev.key === "ArrowRight") this.session.stepCursor(n);
    else if (ev.key === "Home") this.session.setCursor(this.session.buffer.oldest?.x ?? null);
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
    if (y < AXIS_H) {
      const mark = this.markAt(x);
      if (mark) {
        this.openMark(mark);
        return;
      }
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

  /// The mark drawn within a few pixels of `x` on the axis.
  private markAt(x: number): Mark | null {
    let best: (Mark & { x: number }) | null = null;
    for (const m of this.marks) {
      const px = this.xOf(m.x);
      if (Math.abs(px - x) <= 7 && (!best || Math.abs(px - x) < Math.abs(this.xOf(best.x) - x))) best = m;
    }
    return best;
  }

  /// Show what the generation of `mark` changed.
  openMark(mark: Mark): void {
    if (!this.changes.element.isConnected) document.body.append(this.changes.element);
    void this.changes.show(mark, formatClock);
  }

  private xOf(t: number): number {
    return LABEL_W + ((t - this.t0) / Math.max(1, this.t1 - this.t0)) * (this.width - LABEL_W - 6);
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
    if (structural) {
      // Descriptions, generations or the robot changed: the model and the cached indexes go.
      this.model.invalidate();
      this.indexes.clear();
    }
    if (structural || (changes.has("tick") && session.isLive && now - this.builtAt > 250)) {
      this.builtAt = now;
      this.model.update(session.buffer.all, {
        robotId: session.selectedRobot,
        agents: session.robots.filter((a) => a.program !== null),
        indexOf: this.indexIn,
      });
      this.team = this.model.team;
      this.rows = this.model.rows;
      this.t0 = session.buffer.oldest?.x ?? 0;
      this.t1 = Math.max(this.t0 + 1, session.buffer.newest?.x ?? 1);
      this.marks = session.buffer.starts().map((tick) => ({ gen: tick.gen, reason: session.generations.get(tick.gen)?.reason ?? "reload", t: tick.t, x: tick.x }));
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
    const width = Math.max(200, this.scrollerWidth || this.scroller.clientWidth);
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
    const teamTop = new Map<number, number>();
    for (const row of this.team) {
      drawRow(row, top, TEAM_ROW, row.label, 0, row.id === session.selectedRobot);
      teamTop.set(row.id, top);
      top += TEAM_ROW;
    }
    // Search matches: a band under the axis, and over the robot's team row.
    let drawnMatches = 0;
    for (const match of this.matches) {
      const from = session.buffer.bySeq(match.first_seq)?.x ?? match.first_t;
      const to = session.buffer.bySeq(match.last_seq)?.x ?? match.last_t;
      if (to < this.t0 || from > this.t1) continue;
      const x0 = Math.max(LABEL_W, xOf(from) - 1);
      const w = Math.max(2, Math.min(width - 6, xOf(to) + 1) - x0);
      ctx.fillStyle = "#43a047";
      ctx.fillRect(x0, AXIS_H - 5, w, 5);
      const y = teamTop.get(match.robot);
      if (y !== undefined) {
        ctx.fillStyle = "rgba(67,160,71,0.55)";
        ctx.fillRect(x0, y, w, TEAM_ROW);
      }
      drawnMatches += 1;
    }
    this.canvas.dataset.matches = String(drawnMatches);
    ctx.fillStyle = "#e53935";
    ctx.strokeStyle = "rgba(229,57,53,0.6)";
    for (const hit of this.hits) {
      const at = (hit.seq !== undefined ? session.buffer.bySeq(hit.seq)?.x : undefined) ?? hit.t;
      if (at < this.t0 || at > this.t1) continue;
      const x = xOf(at);
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
    // The divergence: at its tick where the buffer holds it (a replay of either recording), else its time.
    const parted = this.divergence;
    const partedAt = parted ? (session.buffer.bySeq(parted.seq)?.x ?? parted.t) : null;
    if (parted && partedAt !== null && partedAt >= this.t0 && partedAt <= this.t1) {
      const x = xOf(partedAt);
      ctx.fillStyle = "#ab47bc";
      ctx.strokeStyle = "rgba(171,71,188,0.8)";
      ctx.beginPath();
      ctx.moveTo(x, 0);
      ctx.lineTo(x + 5, 5);
      ctx.lineTo(x, 10);
      ctx.lineTo(x - 5, 5);
      ctx.closePath();
      ctx.fill();
      ctx.beginPath();
      ctx.moveTo(x, 10);
      ctx.lineTo(x, height);
      ctx.stroke();
      this.canvas.dataset.divergence = JSON.stringify({ seq: parted.seq, agent: parted.agent, px: Math.round(x) });
    } else delete this.canvas.dataset.divergence;
    // Generation marks: a flag on the axis and a dashed line, coloured by reason.
    const drawn: Array<{ gen: number; reason: string; px: number }> = [];
    for (const mark of this.marks) {
      const x = xOf(mark.x);
      const color = MARK_COLORS[mark.reason] ?? MARK_OTHER;
      ctx.fillStyle = color;
      ctx.strokeStyle = color;
      ctx.fillRect(x - 5, 1, 10, AXIS_H - 4);
      ctx.fillStyle = "#fff";
      ctx.fillText(MARK_LETTERS[mark.reason] ?? mark.reason.charAt(0).toUpperCase(), x - 3, AXIS_H / 2 - 1);
      ctx.setLineDash([3, 3]);
      ctx.beginPath();
      ctx.moveTo(x, AXIS_H - 3);
      ctx.lineTo(x, height);
      ctx.stroke();
      ctx.setLineDash([]);
      drawn.push({ gen: mark.gen, reason: mark.reason, px: Math.round(x) });
    }
    // For tests and tools: where the marks are (canvas pixels).
    this.canvas.dataset.marks = JSON.stringify(drawn);
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
    const n = this.marks.length;
    const reloads = n ? ` · ${n} reload${n === 1 ? "" : "s"} or reset${n === 1 ? "" : "s"}: click ${n === 1 ? "its" : "a"} mark on the axis to see what changed` : "";
    const info = `${formatMs(this.t1 - this.t0)} buffered${reloads}${tick ? ` · showing t = ${formatClock(tick.t)}` : ""}${session.isLive ? "" : " (scrubbed: every panel shows this moment)"}`;
    if (this.info.textContent !== info) {
      this.info.textContent = info;
      this.info.title = info; // the toolbar is one row: a long text is cut, the whole of it here
    }
  }
}
