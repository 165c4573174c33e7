/// The workspace layout: resizable regions (drag a splitter, or focus it and use the arrow keys),
/// tab groups, and the theme, all remembered in localStorage.
import { h } from "./ui";

const KEY = "xabsl-studio.layout.v1";

export interface LayoutState {
  sizes: Record<string, number>;
  tabs: Record<string, string>;
  theme: "dark" | "light";
}

const DEFAULTS: LayoutState = {
  sizes: { left: 420, right: 380, bottom: 270, plot: 420, field: 320 },
  tabs: {},
  theme: "dark",
};

export function loadLayout(storage: Pick<Storage, "getItem"> | undefined = globalThis.localStorage): LayoutState {
  try {
    const raw = storage?.getItem(KEY);
    if (!raw) return structuredClone(DEFAULTS);
    const parsed = JSON.parse(raw) as Partial<LayoutState>;
    return {
      sizes: { ...DEFAULTS.sizes, ...(parsed.sizes ?? {}) },
      tabs: { ...(parsed.tabs ?? {}) },
      theme: parsed.theme === "light" ? "light" : "dark",
    };
  } catch {
    return structuredClone(DEFAULTS);
  }
}

export class Layout {
  readonly state: LayoutState;
  private saveTimer: ReturnType<typeof setTimeout> | null = null;
  private readonly resizeListeners = new Set<() => void>();

  constructor(private readonly root: HTMLElement) {
    this.state = loadLayout();
    this.applySizes();
    this.applyTheme();
  }

  onResize(fn: () => void): void {
    this.resizeListeners.add(fn);
  }

  private save(): void {
    if (this.saveTimer) clearTimeout(this.saveTimer);
    this.saveTimer = setTimeout(() => {
      try {
        localStorage.setItem(KEY, JSON.stringify(this.state));
      } catch {
        /* private mode: the layout is simply not remembered */
      }
    }, 200);
  }

  private applySizes(): void {
    for (const [name, px] of Object.entries(this.state.sizes)) this.root.style.setProperty(`--size-${name}`, `${Math.round(px)}px`);
    for (const fn of this.resizeListeners) fn();
  }

  applyTheme(): void {
    document.documentElement.dataset.theme = this.state.theme;
  }

  toggleTheme(): void {
    this.state.theme = this.state.theme === "dark" ? "light" : "dark";
    this.applyTheme();
    this.save();
    for (const fn of this.resizeListeners) fn();
  }

  /// A splitter that resizes region `name`; `sign` is +1 when dragging right/down grows it.
  splitter(name: string, orientation: "vertical" | "horizontal", sign: 1 | -1, min = 120, max = 2000): HTMLElement {
    const el = h("div.splitter", {
      class: `splitter ${orientation}`,
      role: "separator",
      tabindex: 0,
      "aria-orientation": orientation,
      "aria-label": `resize ${name}`,
      title: "Drag (or focus and use the arrow keys) to resize; double-click to reset",
    });
    const set = (px: number): void => {
      this.state.sizes[name] = Math.max(min, Math.min(max, px));
      this.applySizes();
      this.save();
    };
    el.addEventListener("pointerdown", (ev) => {
      ev.preventDefault();
      el.setPointerCapture(ev.pointerId);
      const start = orientation === "vertical" ? ev.clientX : ev.clientY;
      const size = this.state.sizes[name] ?? 200;
      el.classList.add("dragging");
      const move = (e: PointerEvent): void => {
        const now = orientation === "vertical" ? e.clientX : e.clientY;
        set(size + sign * (now - start));
      };
      const up = (): void => {
        el.classList.remove("dragging");
        el.removeEventListener("pointermove", move);
        el.removeEventListener("pointerup", up);
      };
      el.addEventListener("pointermove", move);
      el.addEventListener("pointerup", up);
    });
    el.addEventListener("dblclick", () => set(DEFAULTS.sizes[name] ?? 300));
    el.addEventListener("keydown", (ev) => {
      const step = ev.shiftKey ? 64 : 16;
      const grow: Record<string, number> = orientation === "vertical" ? { ArrowRight: sign, ArrowLeft: -sign } : { ArrowDown: sign, ArrowUp: -sign };
      const d = grow[ev.key];
      if (d) {
        ev.preventDefault();
        set((this.state.sizes[name] ?? 200) + d * step);
      }
    });
    return el;
  }

  /// A tab group; the chosen tab is remembered under `group`.
  tabs(group: string, tabs: Array<{ name: string; label: string; key?: string; pane: HTMLElement }>, onChange?: (name: string) => void): Tabs {
    return new Tabs(group, tabs, this.state.tabs[group], (name) => {
      this.state.tabs[group] = name;
      this.save();
      onChange?.(name);
    });
  }
}

export class Tabs {
  readonly element: HTMLElement;
  active: string;
  private readonly buttons = new Map<string, HTMLButtonElement>();
  private readonly panes = new Map<string, HTMLElement>();

  constructor(
    readonly group: string,
    tabs: Array<{ name: string; label: string; key?: string; pane: HTMLElement }>,
    initial: string | undefined,
    private readonly changed: (name: string) => void,
  ) {
    const bar = h("div.tabbar", { role: "tablist", "aria-label": group });
    const body = h("div.tabbody");
    for (const t of tabs) {
      const button = h(
        "button.tab",
        { role: "tab", title: t.key ? `${t.label} (${t.key})` : t.label, "data-tab": t.name, onclick: () => this.activate(t.name) },
        t.label,
        t.key ? h("kbd", {}, t.key) : null,
      );
      this.buttons.set(t.name, button);
      this.panes.set(t.name, t.pane);
      t.pane.classList.add("tabpane");
      t.pane.setAttribute("role", "tabpanel");
      bar.append(button);
      body.append(t.pane);
    }
    this.element = h("div.tabs", {}, bar, body);
    this.active = initial && this.panes.has(initial) ? initial : (tabs[0]?.name ?? "");
    this.show();
  }

  private show(): void {
    for (const [name, pane] of this.panes) {
      const on = name === this.active;
      pane.hidden = !on;
      this.buttons.get(name)?.setAttribute("aria-selected", String(on));
    }
  }

  activate(name: string): void {
    if (!this.panes.has(name)) return;
    const changed = name !== this.active;
    this.active = name;
    this.show();
    if (changed) this.changed(name);
  }

  isActive(name: string): boolean {
    return this.active === name;
  }

  /// Show or hide a tab (panels a world announces); hiding the active one activates the first shown.
  setAvailable(name: string, on: boolean): void {
    const button = this.buttons.get(name);
    if (!button || button.hidden === !on) return;
    button.hidden = !on;
    if (!on && this.active === name) {
      const first = [...this.buttons].find(([, b]) => !b.hidden)?.[0];
      if (first) this.activate(first);
    }
  }

  isAvailable(name: string): boolean {
    return this.buttons.get(name)?.hidden === false;
  }
}
