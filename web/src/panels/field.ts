/// The field: the world's static scene drawn once per size, robots and ball drawn per tick on a
/// canvas (team colour, number, heading, role; the selected robot ringed). Click a robot to
/// select it. Millimetres in the world frame, x along the field, y to the left.
///
/// Any world can be drawn without code of its own here: besides soccer's lines, circles, marks
/// and goals, the static and the dynamic scene may carry `walls` (`[x1, y1, x2, y2]`) and
/// `shapes` (engine/host.py): `{shape: "circle", x, y, r}`, `{shape: "rect", x, y, w, h}` (centre
/// and size) or `{shape: "segment", x1, y1, x2, y2}`, each with optional `fill`, `stroke`,
/// `dash`, `label` (text centred on the shape) and `caption` (text below it).
import type { RobotInfo, StaticScene, Tick } from "../protocol";
import type { Session, SessionEvent } from "../session";
import { type LabelBox, type LabelRequest, placeLabels } from "../labels";
import { h } from "../ui";
import { roleOf } from "./roles";

const FALLBACK_COLORS = ["#1f6fd1", "#d1341f", "#2a9d4b", "#b8860b"];

/// One generic shape of a scene (see the header comment).
export interface Shape {
  shape: "circle" | "rect" | "segment";
  x?: number;
  y?: number;
  r?: number;
  w?: number;
  h?: number;
  x1?: number;
  y1?: number;
  x2?: number;
  y2?: number;
  fill?: string;
  stroke?: string;
  dash?: boolean;
  label?: string;
  caption?: string;
}

/// The well-formed shapes of a scene's `shapes` value (anything else is ignored).
export function shapesOf(value: unknown): Shape[] {
  if (!Array.isArray(value)) return [];
  return value.filter(
    (s): s is Shape =>
      typeof s === "object" && s !== null && ["circle", "rect", "segment"].includes((s as Shape).shape),
  );
}

export class FieldPanel {
  readonly element: HTMLElement;
  private readonly canvas: HTMLCanvasElement;
  private readonly ctx: CanvasRenderingContext2D;
  private background: HTMLCanvasElement | null = null;
  /// The robot labels drawn last, in canvas pixels (tests check that they never overlap).
  labelBoxes: LabelBox[] = [];
  private scale = 1;
  private cx = 0;
  private cy = 0;
  private width = 0;
  private height = 0;
  private readonly caption: HTMLElement;

  constructor(private readonly session: Session) {
    this.canvas = h("canvas.field-canvas", { "aria-label": "Field: click a robot to select it", tabindex: 0 });
    this.ctx = this.canvas.getContext("2d") as CanvasRenderingContext2D;
    this.caption = h("div.field-caption");
    this.element = h("div.panel.field-panel", {}, this.canvas, this.caption);
    this.canvas.addEventListener("click", (ev) => this.click(ev));
    new ResizeObserver(() => this.resize()).observe(this.element);
  }

  private resize(): void {
    const rect = this.element.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    this.width = Math.max(50, rect.width);
    this.height = Math.max(50, rect.height);
    this.canvas.width = Math.round(this.width * dpr);
    this.canvas.height = Math.round(this.height * dpr);
    this.canvas.style.width = `${this.width}px`;
    this.canvas.style.height = `${this.height}px`;
    this.ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    this.background = null;
    this.draw();
  }

  /// The world rectangle to show: the soccer field with its border, or a plain `{x: [lo, hi],
  /// y: [lo, hi]}` field of a simpler world.
  private bounds(scene: StaticScene | null): { x0: number; x1: number; y0: number; y1: number } {
    const f = scene?.field as Record<string, unknown> | undefined;
    if (f && Array.isArray(f.x) && Array.isArray(f.y)) {
      const [x0, x1] = f.x as number[];
      const [y0, y1] = f.y as number[];
      const m = 0.05 * Math.max((x1 ?? 0) - (x0 ?? 0), 1);
      return { x0: (x0 ?? 0) - m, x1: (x1 ?? 0) + m, y0: (y0 ?? 0) - m, y1: (y1 ?? 0) + m };
    }
    const length = typeof f?.length === "number" ? f.length : 9000;
    const width = typeof f?.width === "number" ? f.width : 6000;
    const border = typeof f?.border === "number" ? f.border : 700;
    return { x0: -length / 2 - border, x1: length / 2 + border, y0: -width / 2 - border, y1: width / 2 + border };
  }

  private toScreen(x: number, y: number): [number, number] {
    return [this.cx + x * this.scale, this.cy - y * this.scale];
  }

  private drawBackground(scene: StaticScene | null): HTMLCanvasElement {
    const dpr = window.devicePixelRatio || 1;
    const bg = document.createElement("canvas");
    bg.width = this.canvas.width;
    bg.height = this.canvas.height;
    const g = bg.getContext("2d") as CanvasRenderingContext2D;
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    const b = this.bounds(scene);
    const w = b.x1 - b.x0;
    const hh = b.y1 - b.y0;
    this.scale = Math.min(this.width / w, this.height / hh) * 0.98;
    this.cx = this.width / 2 - ((b.x0 + b.x1) / 2) * this.scale;
    this.cy = this.height / 2 + ((b.y0 + b.y1) / 2) * this.scale;
    const style = getComputedStyle(document.documentElement);
    g.fillStyle = style.getPropertyValue("--field-bg").trim() || "#2f7d32";
    const [left, top] = this.toScreen(b.x0, b.y1);
    g.fillRect(left, top, w * this.scale, hh * this.scale);
    g.strokeStyle = "rgba(255,255,255,0.9)";
    g.lineWidth = Math.max(1, ((scene?.field as { line_width?: number } | undefined)?.line_width ?? 50) * this.scale);
    for (const [x1, y1, x2, y2] of (scene?.lines ?? []) as number[][]) {
      const [a, b] = this.toScreen(x1 ?? 0, y1 ?? 0);
      const [c, d] = this.toScreen(x2 ?? 0, y2 ?? 0);
      g.beginPath();
      g.moveTo(a, b);
      g.lineTo(c, d);
      g.stroke();
    }
    for (const [x, y, r] of (scene?.circles ?? []) as number[][]) {
      const [a, b] = this.toScreen(x ?? 0, y ?? 0);
      g.beginPath();
      g.arc(a, b, (r ?? 0) * this.scale, 0, 2 * Math.PI);
      g.stroke();
    }
    g.fillStyle = "rgba(255,255,255,0.9)";
    for (const [x, y] of (scene?.marks ?? []) as number[][]) {
      const [a, b] = this.toScreen(x ?? 0, y ?? 0);
      g.fillRect(a - 2, b - 2, 4, 4);
    }
    for (const goal of scene?.goals ?? []) {
      g.strokeStyle = "rgba(255,255,255,0.55)";
      g.lineWidth = 1.5;
      g.beginPath();
      goal.net.forEach(([x, y], i) => {
        const [a, b] = this.toScreen(x ?? 0, y ?? 0);
        if (i === 0) g.moveTo(a, b);
        else g.lineTo(a, b);
      });
      g.stroke();
      g.fillStyle = "#f5f5f5";
      for (const [x, y, r] of goal.posts) {
        const [a, b] = this.toScreen(x ?? 0, y ?? 0);
        g.beginPath();
        g.arc(a, b, Math.max(2, (r ?? 50) * this.scale), 0, 2 * Math.PI);
        g.fill();
      }
    }
    this.drawShapes(g, shapesOf(scene?.shapes));
    g.strokeStyle = "rgba(0,0,0,0.35)";
    g.lineWidth = 2;
    for (const [x1, y1, x2, y2] of (scene?.walls ?? []) as number[][]) {
      const [a, b] = this.toScreen(x1 ?? 0, y1 ?? 0);
      const [c, d] = this.toScreen(x2 ?? 0, y2 ?? 0);
      g.beginPath();
      g.moveTo(a, b);
      g.lineTo(c, d);
      g.stroke();
    }
    return bg;
  }

  /// Draw generic shapes in world coordinates (see the header comment).
  private drawShapes(g: CanvasRenderingContext2D, shapes: Shape[]): void {
    for (const s of shapes) {
      g.beginPath();
      if (s.shape === "circle") {
        const [a, b] = this.toScreen(s.x ?? 0, s.y ?? 0);
        g.arc(a, b, Math.max(1.5, (s.r ?? 0) * this.scale), 0, 2 * Math.PI);
      } else if (s.shape === "rect") {
        const w = s.w ?? 0;
        const hh = s.h ?? 0;
        const [a, b] = this.toScreen((s.x ?? 0) - w / 2, (s.y ?? 0) + hh / 2);
        g.rect(a, b, w * this.scale, hh * this.scale);
      } else {
        const [a, b] = this.toScreen(s.x1 ?? 0, s.y1 ?? 0);
        const [c, d] = this.toScreen(s.x2 ?? 0, s.y2 ?? 0);
        g.moveTo(a, b);
        g.lineTo(c, d);
      }
      if (s.fill && s.shape !== "segment") {
        g.fillStyle = s.fill;
        g.fill();
      }
      if (s.stroke || s.shape === "segment") {
        g.setLineDash(s.dash ? [6, 4] : []);
        g.strokeStyle = s.stroke ?? "rgba(255,255,255,0.9)";
        g.lineWidth = 1.5;
        g.stroke();
        g.setLineDash([]);
      }
      const text = s.label ?? s.caption;
      if (text) {
        let [a, b] = this.toScreen(s.x ?? s.x1 ?? 0, s.y ?? s.y1 ?? 0);
        if (!s.label) b += Math.max(1.5, (s.r ?? (s.h ?? 0) / 2) * this.scale) + 9;
        g.font = "600 12px system-ui, sans-serif";
        g.textAlign = "center";
        g.textBaseline = "middle";
        g.lineWidth = 3;
        g.strokeStyle = "rgba(0,0,0,0.7)";
        g.strokeText(text, a, b + 0.5);
        g.fillStyle = "#fff";
        g.fillText(text, a, b + 0.5);
      }
    }
  }

  private teamColor(robot: RobotInfo | undefined): string {
    const teams = this.session.scene?.teams ?? [];
    const i = teams.findIndex((t) => t.name === robot?.team);
    return teams[i]?.color ?? FALLBACK_COLORS[Math.max(0, i) % FALLBACK_COLORS.length] ?? "#888";
  }

  render(changes: Set<SessionEvent>): void {
    if (changes.has("hello")) this.background = null;
    this.draw();
  }

  private draw(): void {
    const ctx = this.ctx;
    const session = this.session;
    if (!this.background) this.background = this.drawBackground(session.scene);
    ctx.save();
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.clearRect(0, 0, this.canvas.width, this.canvas.height);
    ctx.drawImage(this.background, 0, 0);
    ctx.restore();
    const tick = session.view;
    if (!tick?.scene) {
      this.caption.textContent = session.hello ? "waiting for the first frame…" : "";
      return;
    }
    this.drawDynamic(tick);
  }

  private drawDynamic(tick: Tick): void {
    const ctx = this.ctx;
    const scene = tick.scene;
    const session = this.session;
    this.drawShapes(ctx, shapesOf(scene?.shapes));
    const radius = Math.max(6, (session.scene?.robot_radius ?? 150) * this.scale);
    const robots = scene?.robots ?? [];
    ctx.font = `600 ${Math.max(9, Math.round(radius * 1.05))}px system-ui, sans-serif`;
    ctx.textAlign = "center";
    ctx.textBaseline = "middle";
    const labels: Array<LabelRequest & { fault: boolean }> = [];
    const labelSize = Math.max(9, Math.round(radius * 0.8));
    robots.forEach(([x, y, heading], i) => {
      const robot = session.robots[i];
      const state = tick.robots.find((a) => a.id === (robot?.id ?? i));
      const [sx, sy] = this.toScreen(x, y);
      const selected = robot?.id === session.selectedRobot;
      if (selected) {
        ctx.beginPath();
        ctx.arc(sx, sy, radius + 5, 0, 2 * Math.PI);
        ctx.strokeStyle = "#ffd54a";
        ctx.lineWidth = 3;
        ctx.stroke();
      }
      ctx.beginPath();
      ctx.arc(sx, sy, radius, 0, 2 * Math.PI);
      ctx.fillStyle = this.teamColor(robot);
      ctx.fill();
      ctx.lineWidth = 1.5;
      ctx.strokeStyle = state?.fault ? "#ff2d2d" : "rgba(0,0,0,0.6)";
      ctx.stroke();
      const a = (heading * Math.PI) / 180;
      ctx.beginPath();
      ctx.moveTo(sx, sy);
      ctx.lineTo(sx + Math.cos(a) * radius * 1.6, sy - Math.sin(a) * radius * 1.6);
      ctx.strokeStyle = "#fff";
      ctx.lineWidth = 2;
      ctx.stroke();
      ctx.fillStyle = "#fff";
      ctx.fillText(String(robot?.number ?? i + 1), sx, sy + 0.5);
      const role = robot ? roleOf(session, robot.id, state ?? null) : null;
      const tag = [role, state?.forced ? "forced" : null, state?.fault ? "FAULT" : null].filter((s) => s).join(" · ");
      if (tag) {
        ctx.font = `500 ${labelSize}px system-ui, sans-serif`;
        labels.push({ cx: sx, cy: sy, radius: radius + 2, w: ctx.measureText(tag).width, h: labelSize, text: tag, fault: !!state?.fault });
        ctx.font = `600 ${Math.max(9, Math.round(radius * 1.05))}px system-ui, sans-serif`;
      }
    });
    // Labels last, where they overlap neither another label nor a robot (labels.ts).
    ctx.font = `500 ${labelSize}px system-ui, sans-serif`;
    ctx.textAlign = "left";
    ctx.textBaseline = "top";
    const boxes = placeLabels(labels);
    this.labelBoxes = [];
    boxes.forEach((box, i) => {
      if (!box) return;
      ctx.fillStyle = labels[i]?.fault ? "#ffb3b3" : "rgba(255,255,255,0.92)";
      ctx.fillText(box.text, box.x, box.y);
      this.labelBoxes.push(box);
    });
    if (scene?.ball) {
      const [bx, by] = this.toScreen(scene.ball[0], scene.ball[1]);
      ctx.beginPath();
      ctx.arc(bx, by, Math.max(4, (session.scene?.ball_radius ?? 50) * this.scale), 0, 2 * Math.PI);
      ctx.fillStyle = "#ff8c1a";
      ctx.fill();
      ctx.strokeStyle = "#222";
      ctx.lineWidth = 1;
      ctx.stroke();
    }
    this.caption.textContent = "";
  }

  /// The id of the robot nearest to a canvas point, within reach.
  robotAt(px: number, py: number): number | null {
    const robots = this.session.view?.scene?.robots ?? [];
    const radius = Math.max(6, (this.session.scene?.robot_radius ?? 150) * this.scale);
    let best: number | null = null;
    let bestD = (radius * 2) ** 2;
    robots.forEach(([x, y], i) => {
      const [sx, sy] = this.toScreen(x, y);
      const d = (sx - px) ** 2 + (sy - py) ** 2;
      if (d < bestD) {
        bestD = d;
        best = this.session.robots[i]?.id ?? i;
      }
    });
    return best;
  }

  private click(ev: MouseEvent): void {
    const rect = this.canvas.getBoundingClientRect();
    const id = this.robotAt(ev.clientX - rect.left, ev.clientY - rect.top);
    if (id !== null) this.session.selectRobot(id);
  }
}
