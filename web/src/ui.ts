/// Small DOM helpers shared by the panels (no framework: panels own their DOM and update it in
/// place; see session.ts for the render loop).
import type { Value } from "./protocol";
import type { DescriptionIndex, ValueType } from "./description";

type Child = Node | string | number | null | undefined | false;
type Attrs = Record<string, string | number | boolean | EventListener | null | undefined>;

/// Create an element: `h("button.primary#save", {title: "Save", onclick}, "Save")`.
export function h<K extends keyof HTMLElementTagNameMap>(spec: K | `${K}.${string}` | `${K}#${string}`, attrs: Attrs = {}, ...children: Child[]): HTMLElementTagNameMap[K] {
  const m = /^([a-z0-9]+)((?:[.#][\w-]+)*)$/.exec(spec);
  const tag = (m?.[1] ?? spec) as K;
  const el = document.createElement(tag);
  for (const part of m?.[2]?.match(/[.#][\w-]+/g) ?? []) {
    if (part[0] === ".") el.classList.add(part.slice(1));
    else el.id = part.slice(1);
  }
  for (const [key, value] of Object.entries(attrs)) {
    if (value === null || value === undefined || value === false) continue;
    if (key.startsWith("on") && typeof value === "function") el.addEventListener(key.slice(2), value);
    else if (key === "class") el.className = String(value);
    else if (value === true) el.setAttribute(key, "");
    else el.setAttribute(key, String(value));
  }
  for (const c of children) {
    if (c === null || c === undefined || c === false) continue;
    el.append(typeof c === "object" ? c : String(c));
  }
  return el;
}

/// Set text only when it differs (avoids layout work on every frame).
export function setText(el: Element, text: string): void {
  if (el.textContent !== text) el.textContent = text;
}

export function toggleClass(el: Element, name: string, on: boolean): void {
  if (el.classList.contains(name) !== on) el.classList.toggle(name, on);
}

/// A value for display: decimals with up to 3 digits, booleans, enum element names.
export function formatValue(value: Value | undefined | null, type?: ValueType, enumName?: string | null, index?: DescriptionIndex | null): string {
  if (value === undefined || value === null) return "–";
  if (type === "enum" || (enumName && typeof value === "number")) {
    const elements = enumName ? index?.enumByName.get(enumName)?.elements : undefined;
    if (elements && typeof value === "number") return value >= 0 && value < elements.length ? shortElement(elements[value] as string, enumName) : "?";
  }
  if (typeof value === "boolean") return value ? "true" : "false";
  if (type === "boolean") return value ? "true" : "false";
  if (Number.isInteger(value)) return String(value);
  return String(Math.round(value * 1000) / 1000);
}

/// An enum element without its enumeration's prefix (`game.state.playing` -> `playing`).
export function shortElement(element: string, enumName: string | null | undefined): string {
  return enumName && element.startsWith(`${enumName}.`) ? element.slice(enumName.length + 1) : element;
}

/// Milliseconds as seconds: "12.3 s", or "850 ms" below one second.
export function formatMs(ms: number): string {
  if (ms < 1000) return `${Math.round(ms)} ms`;
  if (ms < 600_000) return `${(ms / 1000).toFixed(1)} s`;
  const m = Math.floor(ms / 60000);
  const s = Math.floor((ms % 60000) / 1000);
  return `${m}:${String(s).padStart(2, "0")}`;
}

/// The match clock to the millisecond, so that one tick (25 ms at 40 Hz) shows: "12.325 s",
/// "3:07.050" from ten minutes on.
export function formatClock(ms: number): string {
  const whole = Math.max(0, Math.round(ms));
  if (whole < 600_000) return `${(whole / 1000).toFixed(3)} s`;
  const m = Math.floor(whole / 60000);
  const s = ((whole % 60000) / 1000).toFixed(3).padStart(6, "0");
  return `${m}:${s}`;
}

/// The speeds the top bar offers (the server accepts any in 0.1..20).
export const SPEEDS: readonly number[] = [0.1, 0.25, 0.5, 1, 2, 4, 10, 20];

/// A speed for display: "0.25×", "20×".
export function formatSpeed(speed: number): string {
  return `${Math.round(speed * 1000) / 1000}×`;
}

/// A transient message in the corner ("saved", "forced striker on blue3", errors).
export function toast(message: string, kind: "ok" | "error" | "info" = "info", ms = 3500): void {
  let host = document.getElementById("toasts");
  if (!host) {
    host = h("div#toasts", { role: "status", "aria-live": "polite" });
    document.body.append(host);
  }
  const el = h("div.toast", { class: `toast ${kind}` }, message);
  host.append(el);
  setTimeout(() => el.remove(), kind === "error" ? ms * 2 : ms);
}

/// Whether a keyboard event is typed into a text field (global shortcuts must not fire then).
export function isTyping(ev: KeyboardEvent): boolean {
  const t = ev.target as HTMLElement | null;
  if (!t) return false;
  return t.isContentEditable || t.closest(".cm-editor") !== null || ["INPUT", "TEXTAREA", "SELECT"].includes(t.tagName);
}

/// Parse an SVG text into an element (the server's graphviz output).
export function parseSvg(text: string): SVGSVGElement | null {
  const doc = new DOMParser().parseFromString(text, "image/svg+xml");
  const svg = doc.documentElement;
  if (svg.nodeName !== "svg") return null;
  return document.importNode(svg, true) as unknown as SVGSVGElement;
}
