/// The test panel: pick an option or basic behavior, fill a parameter form generated from its
/// declaration (types, ranges, units, enum choices), run it as the root of the selected robot
/// (`force_option` / `force_behavior`), watch it, release. The simulation controls (pause, step,
/// speed, reset) sit in the top bar and work from here too.
import { unavailable } from "../capabilities";
import type { Connection } from "../connection";
import { type Parameter, parseRange, rangeText } from "../description";
import { checkNumber } from "../params";
import type { Session, SessionEvent } from "../session";
import { h, setText, shortElement, toast } from "../ui";
import { saveDraft, testDraftBody } from "./testdraft";

type Target = { kind: "option" | "behavior"; name: string };

export class TesterPanel {
  readonly element: HTMLElement;
  private readonly picker: HTMLSelectElement;
  private readonly form: HTMLFormElement;
  private readonly state: HTMLElement;
  private readonly doc: HTMLElement;
  private readonly note: HTMLElement;
  private readonly forcing: HTMLButtonElement[];
  private key = "";
  private controls: Array<{ param: Parameter; control: HTMLInputElement | HTMLSelectElement; error: HTMLElement }> = [];

  constructor(
    private readonly session: Session,
    private readonly connection: Connection,
  ) {
    this.picker = h("select#test-target", { "aria-label": "Option or basic behavior to run" });
    this.picker.addEventListener("change", () => this.buildForm());
    this.form = h("form.param-form", { "aria-label": "Parameters" });
    this.form.addEventListener("submit", (ev) => {
      ev.preventDefault();
      this.run();
    });
    this.state = h("div.test-state");
    this.doc = h("div.muted.small");
    this.note = h("div.test-unavailable", { role: "note", hidden: true });
    this.forcing = [
      h<"button">("button.primary#test-run", { title: "Force it as the root (Ctrl+Enter)", onclick: () => this.run() }, "▶ Run on robot"),
      h("button#test-release", { title: "Back to the robot's own root", onclick: () => this.release() }, "Release"),
      h("button", { title: "Restart every option of this robot's XABSL agent and clear a fault", onclick: () => this.resetAgent() }, "Reset agent"),
    ];
    this.element = h(
      "div.panel.tester-panel",
      {},
      h("label.field-label", { for: "test-target" }, "Run as root of the selected robot"),
      this.picker,
      this.doc,
      this.form,
      this.note,
      h(
        "div.toolbar",
        {},
        ...this.forcing,
        h(
          "button#test-save",
          { title: "Write a behavior test (tests/NAME.xabsl-test.toml) that reproduces this situation and asserts what is active now", onclick: () => void this.saveAsTest() },
          "Save as test",
        ),
      ),
      this.state,
    );
    this.element.addEventListener("keydown", (ev) => {
      if (ev.key === "Enter" && (ev.ctrlKey || ev.metaKey)) this.run();
    });
  }

  /// Preselect an option or basic behavior (from the graph or the option view).
  choose(target: Target): void {
    this.fillPicker();
    this.picker.value = `${target.kind}:${target.name}`;
    this.buildForm();
  }

  private target(): Target | null {
    const [kind, ...rest] = this.picker.value.split(":");
    const name = rest.join(":");
    return kind === "option" || kind === "behavior" ? { kind, name } : null;
  }

  private fillPicker(): void {
    const index = this.session.indexOf(this.session.selectedRobot);
    const key = `${this.session.hello?.generation}|${this.session.programOf(this.session.selectedRobot)}`;
    if (key === this.key) return;
    this.key = key;
    const previous = this.picker.value;
    const options = [...(index?.description.options ?? [])].sort((a, b) => a.name.localeCompare(b.name));
    const behaviors = [...(index?.description.behaviors ?? [])].sort((a, b) => a.name.localeCompare(b.name));
    this.picker.replaceChildren(
      h("optgroup", { label: "Options" }, ...options.map((o) => h("option", { value: `option:${o.name}` }, o.name))),
      h("optgroup", { label: "Basic behaviors" }, ...behaviors.map((b) => h("option", { value: `behavior:${b.name}` }, b.name))),
    );
    if ([...this.picker.options].some((o) => o.value === previous)) this.picker.value = previous;
    this.buildForm();
  }

  private buildForm(): void {
    const index = this.session.indexOf(this.session.selectedRobot);
    const target = this.target();
    const decl = target?.kind === "option" ? index?.optionByName.get(target.name) : target ? index?.behaviorByName.get(target.name) : undefined;
    setText(this.doc, decl?.doc ?? "");
    this.controls = [];
    const rows: HTMLElement[] = [];
    for (const param of decl?.params ?? []) {
      let control: HTMLInputElement | HTMLSelectElement;
      const id = `param-${param.short_name.replace(/\W/g, "_")}`;
      if (param.type === "boolean") {
        control = h("input", { type: "checkbox", id, name: param.short_name });
      } else if (param.type === "enum") {
        const elements = index?.enumByName.get(param.enum ?? "")?.elements ?? [];
        control = h("select", { id, name: param.short_name }, ...elements.map((e, i) => h("option", { value: i }, shortElement(e, param.enum))));
      } else {
        const range = parseRange(param.range);
        control = h("input", {
          type: "number",
          step: "any",
          id,
          name: param.short_name,
          value: range.min !== undefined && range.min > 0 ? range.min : 0,
          min: range.min,
          max: range.max,
        });
      }
      const error = h("div.param-error", { id: `${id}-error`, role: "alert", hidden: true });
      control.setAttribute("aria-describedby", error.id);
      control.addEventListener("input", () => this.showError(control, error, null));
      this.controls.push({ param, control, error });
      rows.push(
        h(
          "div.param-row",
          { title: param.doc ?? "" },
          h("label", { for: id }, param.type === "boolean" ? param.short_name : `${param.short_name}`),
          control,
          h("span.unit", {}, rangeText(param.range, param.unit)),
          error,
          param.doc ? h("div.muted.small", {}, param.doc) : null,
        ),
      );
    }
    if (!rows.length) rows.push(h("div.muted", {}, target ? "No parameters." : "Nothing to run: the robot has no XABSL behavior."));
    this.form.replaceChildren(...rows);
  }

  private showError(control: HTMLElement, error: HTMLElement, message: string | null): void {
    error.hidden = message === null;
    error.textContent = message ?? "";
    if (message === null) control.removeAttribute("aria-invalid");
    else control.setAttribute("aria-invalid", "true");
  }

  /// The parameter values, or null when a field is empty or out of its declared range (each
  /// such field then says what is wrong, and the first one gets the focus).
  private params(): Record<string, number | boolean> | null {
    const out: Record<string, number | boolean> = {};
    let first: HTMLElement | null = null;
    for (const { param, control, error } of this.controls) {
      if (param.type === "boolean") out[param.short_name] = (control as HTMLInputElement).checked;
      else if (param.type === "enum") out[param.short_name] = Number(control.value);
      else {
        // a number input reports "" for text it cannot read ("1e", "--3"): that is not a number
        const input = control as HTMLInputElement;
        const checked = input.validity.badInput ? ({ ok: false, error: "not a number" } as const) : checkNumber(input.value, param.range);
        this.showError(control, error, checked.ok ? null : `${param.short_name}: ${checked.error}${param.unit ? ` (${param.unit})` : ""}`);
        if (checked.ok) out[param.short_name] = checked.value;
        else first ??= control;
      }
    }
    if (first) {
      first.focus();
      return null;
    }
    return out;
  }

  run(): void {
    const target = this.target();
    const robot = this.session.selectedRobot;
    if (!target) return;
    const why = unavailable(this.session, robot, "force");
    if (why) return toast(why, "error");
    const params = this.params();
    if (!params) return;
    const forced =
      target.kind === "option"
        ? this.connection.command("force_option", { robot, option: target.name, params })
        : this.connection.command("force_behavior", { robot, behavior: target.name, params });
    forced
      .then(() => toast(`${target.name} runs as the root of ${this.session.robotInfo(robot)?.name}`, "ok"))
      .catch((e: Error) => toast(`Could not run ${target.name}: ${e.message}`, "error"));
  }

  release(): void {
    const robot = this.session.selectedRobot;
    this.connection
      .command("release", { robot })
      .then(() => toast(`${this.session.robotInfo(robot)?.name} runs its own root again`, "ok"))
      .catch((e: Error) => toast(`Release failed: ${e.message}`, "error"));
  }

  /// "Save as test": the server writes tests/NAME.xabsl-test.toml in the example folder from the
  /// tick in view (forced root, parameters, overrides, what is active); the file is also offered
  /// as a download, and when the name is taken only the download is.
  async saveAsTest(): Promise<void> {
    const robot = this.session.selectedRobot;
    const state = this.session.robotInView();
    const index = this.session.indexOf(robot);
    const name = this.session.robotInfo(robot)?.name;
    if (!state || !index || !name) {
      toast("Nothing to save: the robot has no XABSL behavior in view", "error");
      return;
    }
    await saveDraft(testDraftBody(name, state, index));
  }

  private resetAgent(): void {
    const robot = this.session.selectedRobot;
    this.connection.command("reset_agent", { robot }).catch((e: Error) => toast(`Reset failed: ${e.message}`, "error"));
  }

  render(changes: Set<SessionEvent>): void {
    if (changes.has("hello") || changes.has("select") || !this.picker.options.length) this.fillPicker();
    const robot = this.session.live?.robots.find((a) => a.id === this.session.selectedRobot);
    const index = this.session.indexOf(this.session.selectedRobot);
    const name = this.session.robotInfo(this.session.selectedRobot)?.name ?? "";
    let text = `${name}: runs its own root`;
    if (robot?.forced) {
      const [kind, id] = robot.forced;
      const forced = kind === 0 ? index?.optionById.get(id)?.name : index?.behaviorById.get(id)?.name;
      text = `${name}: forced to ${kind === 0 ? "option" : "basic behavior"} ${forced ?? id} — Release to go back`;
    }
    if (robot?.fault) text += ` · fault: ${robot.fault.message}`;
    const why = unavailable(this.session, this.session.selectedRobot, "force");
    this.note.hidden = why === null;
    setText(this.note, why ?? "");
    for (const button of this.forcing) button.disabled = why !== null;
    setText(this.state, text);
    this.state.classList.toggle("forced", !!robot?.forced);
  }
}

