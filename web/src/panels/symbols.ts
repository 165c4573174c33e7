/// Symbols of the selected robot: inputs and outputs (and internal symbols) with their values,
/// units, ranges and doc comments; search; pin any to the plot; override an input (and release).
/// Input functions are listed with the arguments and results of this tick's calls where the
/// world reports them (the bench world's `calls`). In the bench world (its static scene has
/// `bench`), "set…" sets the robot's own value of a plain input or of an input function
/// without a binding (world commands `set_input`, `set_function`): it stays until set again and
/// is marked "by hand"; inputs the user's bindings module supplies are overridden as elsewhere.
/// An input function the bench computes (`abs(value)`, or an expression of the bench file) is
/// marked "computed: abs(value)"; set by hand it reads the value set until released.
/// Rows are built once per hello and robot; a tick only changes value texts.
import type { Connection } from "../connection";
import type { DescriptionIndex, InputSymbol, OutputSymbol } from "../description";
import { rangeText } from "../description";
import { checkNumber } from "../params";
import type { Session, SessionEvent } from "../session";
import { formatValue, h, setText, shortElement, toast, toggleClass } from "../ui";
import type { PlotPanel } from "./plot";

/// What the bench world says about the symbols (static scene `bench`).
interface BenchInfo {
  world_inputs: string[];
  bound: string[];
  functions: string[];
  /// what the bench computes, by input function: "abs(value)", "bench.toml: a * 10 + b"
  computed?: Record<string, string>;
}

/// The bench world's per-robot part of a dynamic scene (`scene.bench[robot]`).
interface BenchRobot {
  calls?: Record<string, Array<[Array<number | boolean>, number | boolean]>>;
  functions?: Record<string, number | boolean>;
  hand?: string[];
}

/// How a value by hand reaches the robot: a debugger override, or the bench world's own value.
type SetMode = "override" | "set_input" | "set_function";

/// The text of an input function's calls in one tick: `f(1, 2) = 3; f(4, 5) = 6`.
export function callsText(name: string, calls: BenchRobot["calls"], format: (v: number | boolean) => string): string {
  const list = calls?.[name];
  if (!list?.length) return "not called";
  const short = name.split(".").pop() ?? name;
  return list.map(([args, value]) => `${short}(${args.map((a) => (typeof a === "number" ? String(Math.round(a * 1000) / 1000) : String(a))).join(", ")}) = ${format(value)}`).join("; ");
}

interface SymbolRow {
  kind: "input" | "output" | "function";
  symbol: InputSymbol | OutputSymbol;
  el: HTMLElement;
  value: HTMLElement;
  pin: HTMLButtonElement;
  /// releases an override with one click (shown while the input is overridden)
  release: HTMLButtonElement | null;
  /// "by hand" / "bound" mark (bench world)
  mark: HTMLElement | null;
  /// the calls of an input function
  calls: HTMLElement | null;
  mode: SetMode;
  /// what the bench computes for this input function (undefined: not computed)
  computed: string | undefined;
  text: string;
}

export class SymbolsPanel {
  readonly element: HTMLElement;
  readonly search: HTMLInputElement;
  private readonly list: HTMLElement;
  private rows: SymbolRow[] = [];
  private key = "";

  constructor(
    private readonly session: Session,
    private readonly connection: Connection,
    private readonly plot: PlotPanel,
  ) {
    this.search = h("input.search", { type: "search", placeholder: "Filter symbols…  (S)", "aria-label": "Filter symbols" });
    this.search.addEventListener("input", () => this.filter());
    this.list = h("div.symbols", { role: "table", "aria-label": "Symbols" });
    this.element = h("div.panel.symbols-panel", {}, h("div.toolbar", {}, this.search), this.list);
  }

  /// The bench world's symbol facts (null: another world).
  private bench(): BenchInfo | null {
    const info = this.session.scene?.bench as BenchInfo | undefined;
    return info && Array.isArray(info.bound) ? info : null;
  }

  private build(index: DescriptionIndex | null): void {
    this.rows = [];
    const sections: HTMLElement[] = [];
    const bench = this.bench();
    const add = (title: string, kind: "input" | "output" | "function", symbols: Array<InputSymbol | OutputSymbol>): void => {
      if (!symbols.length) return;
      sections.push(h("div.section-title", {}, title));
      for (const symbol of symbols) {
        const value = h("span.value");
        const pin = h("button.icon", { title: "Pin to the plot (P)", "aria-label": `pin ${symbol.name}`, hidden: kind === "function" }, "plot");
        pin.addEventListener("click", () => this.plot.toggle(this.session.selectedRobot, kind === "output" ? "output" : "input", symbol.id));
        const params = kind === "function" ? `(${(symbol as InputSymbol).params.map((p) => p.name.slice(symbol.name.length + 1) || p.name).join(", ")})` : "";
        const facts = [symbol.type === "enum" ? `enum ${symbol.enum}` : symbol.type === "boolean" ? "bool" : "", rangeText(symbol.range, symbol.unit)].filter((x) => x).join(" · ");
        const bound = bench?.bound.includes(symbol.name) ?? false;
        const mode: SetMode = !bench || bound ? "override" : kind === "function" ? "set_function" : "set_input";
        const settable = kind === "input" || (kind === "function" && mode === "set_function");
        const override = settable
          ? h(
              "button.icon",
              {
                title: mode === "override" ? "Override this input" : "Set this robot's value: it stays until set again",
                "aria-label": `${mode === "override" ? "override" : "set"} ${symbol.name}`,
                onclick: () => this.editOverride(row),
              },
              "set…",
            )
          : null;
        const computed = kind === "function" && mode === "set_function" ? bench?.computed?.[symbol.name] : undefined;
        const release =
          kind === "input" || computed !== undefined
            ? h("button.icon.release", { title: "Release the override: read the world's value again", "aria-label": `release ${symbol.name}`, hidden: true, onclick: () => this.releaseInput(symbol) }, "release")
            : null;
        const markTitle = bound ? `from ${String((this.session.scene?.bench as { bindings?: string })?.bindings ?? "the bindings module")}` : computed !== undefined ? "the bench computes it; set… overrides it" : "set by hand";
        const mark = bench && kind !== "output" ? h("span.by-hand", { title: markTitle }, bound ? "bound" : computed !== undefined ? `computed: ${computed}` : "") : null;
        const calls = kind === "function" ? h("span.calls") : null;
        const el = h(
          "div.symbol-row",
          { role: "row", "data-symbol": symbol.name, "data-kind": kind, title: symbol.doc ?? "" },
          h("span.name", {}, symbol.name, params, mark, h("span.facts", {}, facts)),
          value,
          h("span.actions", {}, pin, override, release),
          calls,
          symbol.doc ? h("div.sdoc", {}, symbol.doc) : null,
        );
        const row: SymbolRow = { kind, symbol, el, value, pin, release, mark, calls, mode, computed, text: `${symbol.name} ${symbol.doc ?? ""}`.toLowerCase() };
        this.rows.push(row);
        sections.push(el);
      }
    };
    const inputs = index?.description.inputs ?? [];
    add("Inputs", "input", inputs.filter((s) => !s.params.length));
    add("Input functions", "function", inputs.filter((s) => s.params.length));
    add("Outputs", "output", (index?.description.outputs ?? []).filter((s) => !(s as OutputSymbol).internal));
    add("Internal", "output", (index?.description.outputs ?? []).filter((s) => (s as OutputSymbol).internal));
    if (!sections.length) sections.push(h("div.empty", {}, this.session.hello ? "No symbols: this robot has no XABSL behavior." : "Connecting…"));
    this.list.replaceChildren(...sections);
    this.filter();
  }

  private filter(): void {
    const q = this.search.value.trim().toLowerCase();
    for (const row of this.rows) row.el.hidden = q !== "" && !row.text.includes(q);
  }

  render(changes: Set<SessionEvent>): void {
    const session = this.session;
    const key = `${session.hello?.generation ?? -1}|${session.programOf(session.selectedRobot)}`;
    const index = session.indexOf(session.selectedRobot);
    if (key !== this.key || changes.has("hello")) {
      this.key = key;
      this.build(index);
    }
    const robot = session.robotInView();
    const overrides = robot?.overrides ?? {};
    const benchScene = (session.view?.scene?.bench as BenchRobot[] | undefined)?.[session.selectedRobot];
    const hand = new Set(benchScene?.hand ?? []);
    const worldInputs = new Set(this.bench()?.world_inputs ?? []);
    for (const row of this.rows) {
      if (row.el.hidden) continue;
      const symbol = row.symbol;
      const format = (v: number | boolean | null | undefined): string => formatValue(v, symbol.type, symbol.enum, index);
      if (row.kind === "function") {
        const set = benchScene?.functions?.[symbol.name];
        // a computed function has no one value: its calls say what it answered
        const shown = row.computed !== undefined && set === undefined ? "" : format(set ?? (symbol.type === "boolean" ? false : 0));
        setText(row.value, row.mode === "set_function" ? shown : "");
        if (row.calls) setText(row.calls, benchScene ? callsText(symbol.name, benchScene.calls, format) : "not reported by this world");
        if (row.mark && row.mode === "set_function") setText(row.mark, set !== undefined ? "by hand" : row.computed !== undefined ? `computed: ${row.computed}` : "");
        if (row.release && row.computed !== undefined && row.release.hidden === (set !== undefined)) row.release.hidden = set === undefined;
        continue;
      }
      const values = row.kind === "input" ? robot?.inputs : robot?.outputs;
      setText(row.value, format(values?.[symbol.id]));
      const overridden = row.kind === "input" && String(symbol.id) in overrides;
      toggleClass(row.el, "overridden", overridden);
      // a world input set by hand on the bench can follow the world again
      const following = row.mode === "set_input" && hand.has(symbol.name) && worldInputs.has(symbol.name);
      const releasable = overridden || following;
      if (row.release && row.release.hidden === releasable) row.release.hidden = !releasable;
      if (row.mark && row.mode === "set_input") setText(row.mark, hand.has(symbol.name) ? "by hand" : "");
      toggleClass(row.pin, "on", this.plot.has(session.selectedRobot, row.kind, symbol.id));
    }
  }

  /// Release the override of `symbol` on robot `robotId` (the selected one by default).
  private releaseInput(symbol: InputSymbol | OutputSymbol, robotId = this.session.selectedRobot): void {
    const overridden = String(symbol.id) in (this.session.robotInView()?.overrides ?? {});
    const bench = this.bench();
    if (!overridden && (bench?.world_inputs.includes(symbol.name) || bench?.computed?.[symbol.name] !== undefined)) {
      this.connection
        .command("world_command", { name: "follow_world", args: { robot: robotId, symbol: symbol.name } })
        .then(() => toast(bench?.computed?.[symbol.name] !== undefined ? `${symbol.name} is computed again` : `${symbol.name} follows the world again`, "ok"))
        .catch((e: Error) => toast(`Release failed: ${e.message}`, "error"));
      return;
    }
    this.connection
      .command("release_input", { robot: robotId, symbol: symbol.id })
      .then(() => toast(`${symbol.name} reads the world again`, "ok"))
      .catch((e: Error) => toast(`Release failed: ${e.message}`, "error"));
  }

  /// The inline override editor of an input row: a typed control, Enter applies, Escape cancels.
  private editOverride(row: SymbolRow): void {
    const session = this.session;
    const index = session.indexOf(session.selectedRobot);
    const symbol = row.symbol;
    const robotId = session.selectedRobot;
    const benchScene = (session.view?.scene?.bench as BenchRobot[] | undefined)?.[robotId];
    const current = row.kind === "function" ? benchScene?.functions?.[symbol.name] : session.robotInView()?.inputs[symbol.id];
    let control: HTMLInputElement | HTMLSelectElement;
    if (symbol.type === "boolean") {
      control = h("select", {}, h("option", { value: "true" }, "true"), h("option", { value: "false" }, "false"));
      control.value = current ? "true" : "false";
    } else if (symbol.type === "enum") {
      const elements = index?.enumByName.get(symbol.enum ?? "")?.elements ?? [];
      control = h("select", {}, ...elements.map((e, i) => h("option", { value: i }, shortElement(e, symbol.enum))));
      control.value = String(typeof current === "number" ? current : 0);
    } else {
      control = h("input", { type: "number", step: "any", value: typeof current === "number" ? current : 0 });
    }
    const problem = h("div.param-error", { role: "alert", hidden: true });
    const apply = (): void => {
      let value: number | boolean;
      if (symbol.type === "boolean") value = control.value === "true";
      else if (symbol.type === "enum") value = Number(control.value);
      else {
        // an empty or out-of-range number is said, not sent (it used to become 0)
        const input = control as HTMLInputElement;
        const checked = input.validity.badInput ? ({ ok: false, error: "not a number" } as const) : checkNumber(input.value, symbol.range);
        problem.hidden = checked.ok;
        problem.textContent = checked.ok ? "" : `${symbol.name}: ${checked.error}${symbol.unit ? ` (${symbol.unit})` : ""}`;
        if (!checked.ok) {
          control.setAttribute("aria-invalid", "true");
          control.focus();
          return;
        }
        value = checked.value;
      }
      const name = session.robotInfo(robotId)?.name;
      const sent =
        row.mode === "override"
          ? this.connection.command("override_input", { robot: robotId, symbol: symbol.id, value }).then(() => `${symbol.name} overridden on ${name}`)
          : this.connection.command("world_command", { name: row.mode, args: { robot: robotId, symbol: symbol.name, value } }).then(() => `${symbol.name} set on ${name}: it stays until set again`);
      sent.then((text) => toast(text, "ok")).catch((e: Error) => toast(`Set failed: ${e.message}`, "error"));
      editor.remove();
    };
    const release = (): void => {
      this.releaseInput(symbol, robotId);
      editor.remove();
    };
    const editor = h(
      "div.override-editor",
      {},
      control,
      h("button.primary", { onclick: apply }, row.mode === "override" ? "Override" : "Set"),
      row.mode === "override" ? h("button", { onclick: release, title: "Back to the world's value" }, "Release") : null,
      h("button", { onclick: () => editor.remove() }, "Cancel"),
      problem,
    );
    control.addEventListener("keydown", (ev) => {
      const key = (ev as KeyboardEvent).key;
      if (key === "Enter") apply();
      else if (key === "Escape") editor.remove();
    });
    row.el.querySelector(".override-editor")?.remove();
    row.el.append(editor);
    control.focus();
  }
}
