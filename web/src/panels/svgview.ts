/// A pan-and-zoom viewport for a server-rendered graphviz SVG, with highlighting by CSS class on
/// element ids. The SVG is laid out once by the server; ticks only toggle classes (`setClasses`)
/// and never touch geometry.
import { h, parseSvg } from "../ui";

export class SvgView {
  readonly element: HTMLElement;
  svg: SVGSVGElement | null = null;
  private readonly stage: HTMLElement;
  private x = 0;
  private y = 0;
  private zoom = 1;
  private width = 0;
  private height = 0;
  private readonly ids = new Map<string, Element>();
  /// class name -> ids currently carrying it.
  private readonly marked = new Map<string, Set<string>>();
  /// Whether the picture is at Fit (then a resize fits it again; else it keeps its centre).
  private fitted = true;
  /// The automatic placement to redo after a resize while `fitted` (Fit, or Fit then the
  /// readable zoom around the active option of `focusIfTiny`).
  private refit: () => void = () => this.fit();
  private viewW = 0;
  private viewH = 0;
  onClick: ((id: string, ev: MouseEvent) => void) | null = null;
  /// Smallest on-screen size (px) of the text matching `legibleText` that Fit allows (0: none):
  /// a picture too large to be read whole is shown at that size, centred on `focus()`.
  minTextPx = 0;
  legibleText = "g.node text";
  focus: (() => string | null) | null = null;

  constructor(label: string) {
    this.stage = h("div.svg-stage");
    this.element = h("div.svg-view", { tabindex: 0, "aria-label": label }, this.stage);
    this.element.addEventListener("wheel", (ev) => this.wheel(ev), { passive: false });
    this.element.addEventListener("pointerdown", (ev) => this.drag(ev));
    this.element.addEventListener("click", (ev) => {
      const hit = ev.target as Element;
      // a node or an edge, or a cluster by its label (its inside is where one pans)
      const target = hit.closest("g.node[id], g.edge[id]") ?? (hit.tagName === "text" ? hit.closest("g.cluster[id]") : null);
      if (target && this.onClick && !this.element.classList.contains("panned")) this.onClick(target.id, ev);
    });
    this.element.addEventListener("keydown", (ev) => {
      const step = 60;
      const moves: Record<string, [number, number]> = { ArrowLeft: [step, 0], ArrowRight: [-step, 0], ArrowUp: [0, step], ArrowDown: [0, -step] };
      const m = moves[ev.key];
      if (m) {
        ev.preventDefault();
        this.x += m[0];
        this.y += m[1];
        this.fitted = false;
        this.apply();
      } else if (ev.key === "+" || ev.key === "=") this.zoomBy(1.25);
      else if (ev.key === "-") this.zoomBy(0.8);
      else if (ev.key === "f") this.fit();
    });
    new ResizeObserver(() => this.resized()).observe(this.element);
  }

  /// The viewport changed size (window, splitter, a tab shown again).
  private resized(): void {
    const rect = this.element.getBoundingClientRect();
    if (!rect.width || !rect.height) return; // hidden: handled when shown again
    const dw = rect.width - this.viewW;
    const dh = rect.height - this.viewH;
    const first = !this.viewW;
    this.viewW = rect.width;
    this.viewH = rect.height;
    if (!this.svg || (!dw && !dh)) return;
    // Not `first` alone: a centerOn made at the real size before this first report stands.
    if (this.fitted || (first && this.pendingCentre)) this.refit();
    else {
      this.x += dw / 2;
      this.y += dh / 2;
      this.apply();
    }
  }

  /// Show a new SVG (text from the server); returns false when it cannot be read.
  show(text: string): boolean {
    const svg = parseSvg(text);
    if (!svg) return false;
    this.svg = svg;
    this.ids.clear();
    this.marked.clear();
    for (const el of svg.querySelectorAll("[id]")) this.ids.set(el.id, el);
    const w = svg.viewBox?.baseVal?.width || parseFloat(svg.getAttribute("width") ?? "0") || 400;
    const hh = svg.viewBox?.baseVal?.height || parseFloat(svg.getAttribute("height") ?? "0") || 300;
    this.width = w;
    this.height = hh;
    svg.setAttribute("width", String(w));
    svg.setAttribute("height", String(hh));
    // Graphviz puts a <title> in every group: browsers show them as tooltips, which is welcome.
    this.stage.replaceChildren(svg);
    if (this.minimap) {
      if (this.minimap.url) URL.revokeObjectURL(this.minimap.url);
      this.minimap.url = URL.createObjectURL(new Blob([text], { type: "image/svg+xml" }));
      this.minimap.image.src = this.minimap.url;
    }
    this.fit();
    return true;
  }

  clear(message = ""): void {
    this.svg = null;
    this.ids.clear();
    this.marked.clear();
    this.stage.replaceChildren(h("div.empty", {}, message));
    if (this.minimap) this.minimap.box.hidden = true;
    this.x = 0;
    this.y = 0;
    this.zoom = 1;
    this.apply();
  }

  has(id: string): boolean {
    return this.ids.has(id);
  }

  elementById(id: string): Element | undefined {
    return this.ids.get(id);
  }

  allIds(): IterableIterator<string> {
    return this.ids.keys();
  }

  /// Make exactly `ids` carry class `name` (diffing against the previous call).
  setClasses(name: string, ids: Iterable<string>): void {
    const next = new Set<string>();
    for (const id of ids) if (this.ids.has(id)) next.add(id);
    const prev = this.marked.get(name) ?? new Set<string>();
    for (const id of prev) if (!next.has(id)) this.ids.get(id)?.classList.remove(name);
    for (const id of next) if (!prev.has(id)) this.ids.get(id)?.classList.add(name);
    this.marked.set(name, next);
  }

  private apply(): void {
    this.stage.style.transform = `translate(${this.x}px, ${this.y}px) scale(${this.zoom})`;
    if (this.minimap) this.drawMinimap();
  }

  /// A minimap in the corner: the whole picture small, the part in view framed; a click or a
  /// drag on it moves the view there. Shown while the picture is larger than the view. The
  /// picture is an <img> of the server's SVG text, so it costs no DOM and no work on a tick.
  enableMinimap(): void {
    if (this.minimap) return;
    const frame = h("div.minimap-view");
    const image = h("img", { alt: "", draggable: false });
    const box = h("div.minimap", { title: "Minimap: click or drag to move the view", hidden: true }, image, frame);
    this.minimap = { box, image, frame, url: "" };
    this.element.append(box);
    box.addEventListener("pointerdown", (ev) => {
      ev.stopPropagation();
      ev.preventDefault();
      const move = (e: PointerEvent): void => this.minimapTo(e);
      move(ev);
      box.setPointerCapture(ev.pointerId);
      box.addEventListener("pointermove", move);
      box.addEventListener("pointerup", () => box.removeEventListener("pointermove", move), { once: true });
    });
  }

  private minimap: { box: HTMLElement; image: HTMLImageElement; frame: HTMLElement; url: string } | null = null;

  /// The minimap's scale: picture pixels to minimap pixels.
  private minimapScale(): number {
    return Math.min(MINIMAP_W / (this.width || 1), MINIMAP_H / (this.height || 1));
  }

  private drawMinimap(): void {
    const m = this.minimap;
    if (!m) return;
    const view = this.element.getBoundingClientRect();
    const w = this.width * this.zoom;
    const hh = this.height * this.zoom;
    const show = this.svg !== null && view.width > 0 && (w > view.width + 1 || hh > view.height + 1);
    if (m.box.hidden !== !show) m.box.hidden = !show;
    if (!show) return;
    const s = this.minimapScale();
    m.box.style.width = `${this.width * s}px`;
    m.box.style.height = `${this.height * s}px`;
    const k = s / this.zoom; // screen px -> minimap px
    const left = Math.max(0, -this.x * k);
    const top = Math.max(0, -this.y * k);
    m.frame.style.left = `${left}px`;
    m.frame.style.top = `${top}px`;
    m.frame.style.width = `${Math.max(4, Math.min(this.width * s, (view.width - this.x) * k) - left)}px`;
    m.frame.style.height = `${Math.max(4, Math.min(this.height * s, (view.height - this.y) * k) - top)}px`;
  }

  private minimapTo(ev: PointerEvent): void {
    const m = this.minimap;
    if (!m) return;
    const r = m.box.getBoundingClientRect();
    const s = this.minimapScale();
    const ux = (ev.clientX - r.left) / s;
    const uy = (ev.clientY - r.top) / s;
    const view = this.element.getBoundingClientRect();
    this.fitted = false;
    this.x = view.width / 2 - ux * this.zoom;
    this.y = view.height / 2 - uy * this.zoom;
    this.apply();
  }

  /// Whether the minimap is shown (tests read it).
  get minimapShown(): boolean {
    return this.minimap !== null && !this.minimap.box.hidden;
  }

  /// Fit the picture into the view; `overview`: the whole of it, however small its text gets.
  fit(overview = false): void {
    const rect = this.element.getBoundingClientRect();
    if (!this.width || !rect.width) {
      this.fitPending = true;
      requestAnimationFrame(() => this.element.isConnected && this.width && this.element.getBoundingClientRect().width && this.fit(overview));
      return;
    }
    this.fitPending = false;
    this.fitted = true;
    this.refit = () => this.fit(overview);
    const applied = this.zoom; // the stage is still drawn at this zoom
    this.zoom = Math.min(2, Math.min(rect.width / this.width, rect.height / this.height) * 0.95);
    this.x = (rect.width - this.width * this.zoom) / 2;
    this.y = (rect.height - this.height * this.zoom) / 2;
    const legible = overview ? 0 : this.legibleZoom();
    if (this.zoom < legible) {
      this.zoom = legible;
      const id = this.focus?.() ?? null;
      const target = id ? this.unscaledCentre(id, applied) : null;
      const [ux, uy] = target ?? [this.width / 2, this.height / 2];
      this.x = place(this.width * this.zoom, rect.width, ux * this.zoom);
      this.y = place(this.height * this.zoom, rect.height, uy * this.zoom);
    }
    this.apply();
    const centre = this.pendingCentre;
    this.pendingCentre = null;
    centre?.();
  }

  /// A fit waits for the view to have a size (a tab just shown): centring waits for it too.
  private fitPending = false;
  private pendingCentre: (() => void) | null = null;

  /// The zoom at which the smallest legible-class text is `minTextPx` on screen (0: no floor).
  private legibleZoom(): number {
    if (!this.minTextPx || !this.svg) return 0;
    let size = Infinity;
    for (const t of this.svg.querySelectorAll(this.legibleText)) {
      const px = parseFloat(t.getAttribute("font-size") ?? "");
      if (px > 0) size = Math.min(size, px);
    }
    return Number.isFinite(size) ? this.minTextPx / size : 0;
  }

  /// The centre of element `id` in unscaled picture pixels.
  private unscaledCentre(id: string, zoom: number): [number, number] | null {
    const el = this.ids.get(id);
    if (!el) return null;
    const box = el.getBoundingClientRect();
    const stageBox = this.stage.getBoundingClientRect();
    if (!box.width && !box.height) return null;
    return [(box.left + box.width / 2 - stageBox.left) / zoom, (box.top + box.height / 2 - stageBox.top) / zoom];
  }

  /// While the placement is automatic (Fit, not panned since): centre the box around elements
  /// `ids` at the same zoom (a machine follows its active state and the transition that led
  /// there); a picture that fits stays centred as a whole.
  follow(ids: readonly string[]): void {
    if (!this.fitted || !this.svg) return;
    const boxes = ids.map((id) => this.ids.get(id)?.getBoundingClientRect()).filter((b): b is DOMRect => !!b && (b.width > 0 || b.height > 0));
    if (!boxes.length) return;
    const view = this.element.getBoundingClientRect();
    const stageBox = this.stage.getBoundingClientRect();
    const left = Math.min(...boxes.map((b) => b.left));
    const right = Math.max(...boxes.map((b) => b.right));
    const top = Math.min(...boxes.map((b) => b.top));
    const bottom = Math.max(...boxes.map((b) => b.bottom));
    const ux = ((left + right) / 2 - stageBox.left) / this.zoom;
    const uy = ((top + bottom) / 2 - stageBox.top) / this.zoom;
    this.x = place(this.width * this.zoom, view.width, ux * this.zoom);
    this.y = place(this.height * this.zoom, view.height, uy * this.zoom);
    this.apply();
  }

  /// The current zoom (tests and the option view read it).
  get scale(): number {
    return this.zoom;
  }

  zoomBy(factor: number, cx?: number, cy?: number): void {
    const rect = this.element.getBoundingClientRect();
    const px = cx ?? rect.width / 2;
    const py = cy ?? rect.height / 2;
    const zoom = Math.max(0.05, Math.min(8, this.zoom * factor));
    this.fitted = false;
    this.x = px - ((px - this.x) * zoom) / this.zoom;
    this.y = py - ((py - this.y) * zoom) / this.zoom;
    this.zoom = zoom;
    this.apply();
  }

  /// After `fit`: when the whole graph is too small to read, centre `id` at a readable zoom.
  focusIfTiny(id: string | null): void {
    if (!id || this.zoom >= 0.55) return;
    requestAnimationFrame(() => {
      this.centerOn(id);
      // still an automatic placement: a resize does it again
      this.fitted = true;
      this.refit = () => {
        this.fit();
        this.focusIfTiny(id);
      };
    });
  }

  /// Centre the element `id` in the view (zooming in to a readable size if needed and `zoomIn`).
  centerOn(id: string, zoomIn = true): void {
    const el = this.ids.get(id) as SVGGraphicsElement | undefined;
    if (!el || !this.svg) return;
    const rect = this.element.getBoundingClientRect();
    if (!rect.width || this.fitPending) {
      this.pendingCentre = () => this.centerOn(id, zoomIn);
      return;
    }
    const box = el.getBoundingClientRect();
    const stageBox = this.stage.getBoundingClientRect();
    // Element centre in unscaled SVG pixels.
    const ux = (box.left + box.width / 2 - stageBox.left) / this.zoom;
    const uy = (box.top + box.height / 2 - stageBox.top) / this.zoom;
    if (zoomIn && this.zoom < 0.8) this.zoom = 1;
    this.fitted = false;
    this.x = rect.width / 2 - ux * this.zoom;
    this.y = rect.height / 2 - uy * this.zoom;
    this.apply();
  }

  private wheel(ev: WheelEvent): void {
    ev.preventDefault();
    const rect = this.element.getBoundingClientRect();
    this.zoomBy(Math.exp(-ev.deltaY * 0.0015), ev.clientX - rect.left, ev.clientY - rect.top);
  }

  private drag(ev: PointerEvent): void {
    if (ev.button !== 0) return;
    const sx = ev.clientX;
    const sy = ev.clientY;
    const x0 = this.x;
    const y0 = this.y;
    let moved = false;
    this.element.classList.remove("panned");
    const move = (e: PointerEvent): void => {
      const dx = e.clientX - sx;
      const dy = e.clientY - sy;
      if (!moved && Math.abs(dx) + Math.abs(dy) > 4) {
        moved = true;
        this.element.setPointerCapture(ev.pointerId);
        this.element.classList.add("panned", "panning");
      }
      if (moved) {
        this.x = x0 + dx;
        this.y = y0 + dy;
        this.fitted = false;
        this.apply();
      }
    };
    const up = (): void => {
      this.element.classList.remove("panning");
      this.element.removeEventListener("pointermove", move);
      this.element.removeEventListener("pointerup", up);
      // "panned" stays set through the click that follows a drag, then clears.
      setTimeout(() => this.element.classList.remove("panned"), 0);
    };
    this.element.addEventListener("pointermove", move);
    this.element.addEventListener("pointerup", up);
  }
}

/// The minimap's largest size (CSS px).
const MINIMAP_W = 200;
const MINIMAP_H = 150;

/// The offset that shows a picture `size` long in a view `view` long with point `at` of it in the
/// middle: centred when it fits, else as close to `at` as its edges allow (no empty margin).
export function place(size: number, view: number, at: number): number {
  if (size <= view) return (view - size) / 2;
  return Math.min(0, Math.max(view - size, view / 2 - at));
}
