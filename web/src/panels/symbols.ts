/// Symbols of the selected robot: inputs and outputs (and internal symbols) with their values,
/// units, ranges and doc comments; search; pin any to the plot; override an input (and release).
/// Rows are built once per hello and robot; a tick only changes value texts.
import type { Connection } from "../connection";
import type { DescriptionIndex, InputSymbol, OutputSymbol } from "../description";
import { rangeText } from "../description";
import { checkNumber } from "../params";
import type { Session, SessionEvent } from "../session";
import { formatValue, h, setText, shortElement, toast, toggleClass } from "../ui";
import type { PlotPanel } from "./plot";

interface SymbolRow {
  kind: "input" | "output";
  symbol: InputSymbol | OutputSymbol;
  el: HTMLElement;
  value: HTMLElement;
  pin: HTMLButtonElement;
  /// releases an override with one click (shown while the input is overridden)
  release: HTMLButtonElement | null;
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

  private build(index: DescriptionIndex | null): void {
    this.rows = [];
    const sections: HTMLElement[] = [];
    const add = (title: string, kind: "input" | "output", symbols: Array<InputSymbol | OutputSymbol>): void => {
      if (!symbols.length) return;
      sections.push(h("div.section-title", {}, title));
      for (const symbol of symbols) {
        if (kind === "input" && (symbol as InputSymbol).params.length) continue; // functions are not streamed
        const value = h("span.value");
        const pin = h("button.icon", { title: "Pin to the plot (P)", "aria-label": `pin ${symbol.name}` }, "plot");
        pin.addEventListener("click", () => this.plot.toggle(this.session.selectedRobot, kind, symbol.id));
        const facts = [symbol.type === "enum" ? `enum ${symbol.enum}` : symbol.type === "boolean" ? "bool" : "", rangeText(symbol.range, symbol.unit)].filter((x) => x).join(" · ");
        const override =
          kind === "input"
            ? h("button.icon", { title: "Override this input", "aria-label": `override ${symbol.name}`, onclick: () => this.editOverride(row) }, "set…")
            : null;
        const release =
          kind === "input"
            ? h("button.icon.release", { title: "Release the override: read the world's value again", "aria-label": `release ${symbol.name}`, hidden: true, onclick: () => this.releaseInput(symbol) }, "release")
            : null;
        const el = h(
          "div.symbol-row",
          { role: "row", "data-symbol": symbol.name, "data-kind": kind, title: symbol.doc ?? "" },
          h("span.name", {}, symbol.name, h("span.facts", {}, facts)),
          value,
          h("span.actions", {}, pin, override, release),
          symbol.doc ? h("div.sdoc", {}, symbol.doc) : null,
        );
        const row: SymbolRow = { kind, symbol, el, value, pin, release, text: `${symbol.name} ${symbol.doc ?? ""}`.toLowerCase() };
        this.rows.push(row);
        sections.push(el);
      }
    };
    add("Inputs", "input", index?.description.inputs ?? []);
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
    for (const row of this.rows) {
      if (row.el.hidden) continue;
      const values = row.kind === "input" ? robot?.inputs : robot?.outputs;
      setText(row.value, formatValue(values?.[row.symbol.id], row.symbol.type, row.symbol.enum, index));
      const overridden = row.kind === "input" && String(row.symbol.id) in overrides;
      toggleClass(row.el, "overridden", overridden);
      if (row.release && row.release.hidden === overridden) row.release.hidden = !overridden;
      toggleClass(row.pin, "on", this.plot.has(session.selectedRobot, row.kind, row.symbol.id));
    }
  }

  /// Release the override of `symbol` on robot `robotId` (the selected one by default).
  private releaseInput(symbol: InputSymbol | OutputSymbol, robotId = this.session.selectedRobot): void {
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
    const current = session.robotInView()?.inputs[symbol.id];
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
      this.connection
        .command("override_input", { robot: robotId, symbol: symbol.id, value })
        .then(() => toast(`${symbol.name} overridden on ${session.robotInfo(robotId)?.name}`, "ok"))
        .catch((e: Error) => toast(`Override failed: ${e.message}`, "error"));
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
      h("button.primary", { onclick: apply }, "Override"),
      h("button", { onclick: release, title: "Back to the world's value" }, "Release"),
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
