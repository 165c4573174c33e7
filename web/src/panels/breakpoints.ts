/// Breakpoints: the list of the selected robot's behavior set (enable, disable, remove), a form to
/// add one (enter/leave an option or state, a decision leaf, a condition over symbols with the
/// compiler's diagnostics as you type), and the hits (`event` `breakpoint`): a hit pauses the
/// match on the server; here it selects the robot, goes to the tick and marks it in the timeline,
/// and lists the hits of that tick, each with "Save as test" (a test file that starts from the
/// world at the hit's tick and asserts what the breakpoint waited for, docs/tests.md).
/// Breakpoints live on the server (stored per agents file); this panel only shows and edits them.
import type { Connection } from "../connection";
import type { BreakpointEvent, BreakpointInfo } from "../messages.gen";
import type { Session } from "../session";
import { formatClock, h, toast } from "../ui";
import { hitDraftBody, saveDraft } from "./testdraft";

export type BreakpointKind = "enter_option" | "leave_option" | "enter_state" | "leave_state" | "leaf" | "condition";

const KIND_LABELS: Record<BreakpointKind, string> = {
  enter_option: "enter option",
  leave_option: "leave option",
  enter_state: "enter state",
  leave_state: "leave state",
  leaf: "decision leaf",
  condition: "condition",
};

export interface Hit {
  t: number;
  seq: number;
  robot: number;
  description: string;
  program: string;
  breakpoint: number;
}

export class BreakpointsPanel {
  readonly element: HTMLElement;
  /// Hits of this session, newest last (the timeline marks them).
  readonly hits: Hit[] = [];
  onHitsChanged: () => void = () => undefined;
  private readonly list: HTMLElement;
  private readonly hitList: HTMLElement;
  private readonly kind: HTMLSelectElement;
  private readonly state: HTMLSelectElement;
  private readonly leaf: HTMLInputElement;
  private readonly condition: HTMLInputElement;
  private readonly diagnostics: HTMLElement;
  private readonly robot: HTMLSelectElement;
  private program = "";
  private checkTimer = 0;
  private checked = "";
  private batch: { seq: number; t: number; robots: number[]; descriptions: string[] } | null = null;
  private toastTimer = 0;

  constructor(
    private readonly session: Session,
    private readonly connection: Connection,
    /// The option the form is about (the option view's).
    private readonly option: () => { name: string; states: Array<{ name: string }> } | null,
  ) {
    this.list = h("ul.breakpoint-list");
    this.hitList = h("ul.breakpoint-hits", { "aria-label": "Breakpoint hits" });
    this.kind = h(
      "select",
      { "aria-label": "Breakpoint kind", onchange: () => this.formChanged() },
      ...Object.entries(KIND_LABELS).map(([value, label]) => h("option", { value }, label)),
    );
    this.state = h("select", { "aria-label": "State" });
    this.leaf = h("input", { type: "number", min: "0", step: "1", placeholder: "leaf", "aria-label": "Leaf id", size: 4 });
    this.condition = h("input.condition-input", {
      type: "text",
      placeholder: "ball.distance < 300 && ...",
      "aria-label": "Breakpoint condition",
      spellcheck: "false",
      oninput: () => this.scheduleCheck(),
      onkeydown: (ev: Event) => {
        if ((ev as KeyboardEvent).key === "Enter") void this.add();
      },
    });
    this.diagnostics = h("div.condition-diagnostics", { "aria-live": "polite" });
    this.robot = h("select", { "aria-label": "Robot" });
    const form = h(
      "div.breakpoint-form",
      {},
      this.kind,
      this.state,
      this.leaf,
      this.condition,
      this.robot,
      h("button", { onclick: () => void this.add(), title: "Add the breakpoint (it pauses the match when it hits)" }, "Add"),
      this.diagnostics,
    );
    this.element = h("div.breakpoints", {}, h("div.section-title", {}, "Breakpoints"), this.list, this.hitList, form);
    this.formChanged();
  }

  /// Re-read the list from the server (after a hello, or when the robot's behavior changes).
  async refresh(): Promise<void> {
    const program = this.session.programOf(this.session.selectedRobot);
    if (!program) return;
    try {
      const result = await this.connection.command("list_breakpoints", { program });
      this.show(program, result.breakpoints);
    } catch {
      /* not connected: the next hello refreshes */
    }
  }

  /// The form follows the option shown, and the robot list the session.
  sync(): void {
    const option = this.option();
    const states = option?.states.map((s) => s.name) ?? [];
    const current = [...this.state.options].map((o) => o.value);
    if (current.join("|") !== states.join("|")) this.state.replaceChildren(...states.map((s) => h("option", { value: s }, s)));
    const robots = this.session.robots.filter((r) => r.program !== null);
    const wanted = ["any", ...robots.map((r) => String(r.id))];
    if ([...this.robot.options].map((o) => o.value).join("|") !== wanted.join("|")) {
      const chosen = this.robot.value;
      this.robot.replaceChildren(h("option", { value: "any" }, "any robot"), ...robots.map((r) => h("option", { value: r.id }, r.name)));
      if (wanted.includes(chosen)) this.robot.value = chosen;
    }
    const program = this.session.programOf(this.session.selectedRobot);
    if (program && program !== this.program) {
      this.program = program;
      void this.refresh();
    }
  }

  private formChanged(): void {
    const kind = this.kind.value as BreakpointKind;
    this.state.hidden = !(kind === "enter_state" || kind === "leave_state" || kind === "leaf");
    this.leaf.hidden = kind !== "leaf";
    this.condition.hidden = kind !== "condition";
    this.diagnostics.hidden = kind !== "condition";
  }

  private scheduleCheck(): void {
    clearTimeout(this.checkTimer);
    this.checkTimer = window.setTimeout(() => void this.check(), 200);
  }

  /// Diagnostics of the condition typed so far (line:col in the condition, as the compiler says).
  private async check(): Promise<boolean> {
    const text = this.condition.value;
    const program = this.session.programOf(this.session.selectedRobot) ?? undefined;
    if (!text.trim()) {
      this.diagnostics.replaceChildren();
      return false;
    }
    try {
      const result = await this.connection.command("check_condition", { program, condition: text });
      if (this.condition.value !== text) return result.ok;
      this.checked = text;
      this.diagnostics.replaceChildren(
        ...result.diagnostics.map((d) => {
          const span = d.span as { line: number; col: number } | null;
          return h("div", { class: `diagnostic ${String(d.severity)}` }, span ? `${span.line}:${span.col}: ${String(d.message)}` : String(d.message));
        }),
      );
      this.condition.classList.toggle("invalid", !result.ok);
      return result.ok;
    } catch (error) {
      this.diagnostics.replaceChildren(h("div.diagnostic.error", {}, (error as Error).message));
      return false;
    }
  }

  /// Add a breakpoint of the form's kind (or of `kind` for `state`: the option view's state menu).
  async add(kind?: BreakpointKind, state?: string): Promise<void> {
    const option = this.option();
    const chosen = kind ?? (this.kind.value as BreakpointKind);
    const robotValue = this.robot.value;
    const robot = robotValue === "any" || robotValue === "" ? null : Number(robotValue);
    const program = this.session.programOf(this.session.selectedRobot) ?? undefined;
    const args: Parameters<Connection["command"]>[1] & Record<string, unknown> = { program, kind: chosen, robot };
    if (chosen !== "condition") {
      if (!option) return toast("Open an option first.", "error");
      args.option = option.name;
    }
    if (chosen === "enter_state" || chosen === "leave_state" || chosen === "leaf") args.state = state ?? this.state.value;
    if (chosen === "leaf") {
      const leaf = Number(this.leaf.value);
      if (this.leaf.value === "" || !Number.isInteger(leaf) || leaf < 0) return toast("A leaf breakpoint needs a leaf id (a whole number, 0 or more).", "error");
      args.leaf = leaf;
    }
    if (chosen === "condition") {
      args.condition = this.condition.value;
      if (this.checked !== this.condition.value && !(await this.check())) return;
    }
    try {
      const result = await this.connection.command("set_breakpoint", args as never);
      this.show(program ?? "", result.breakpoints);
      toast("Breakpoint set.", "ok");
    } catch (error) {
      const message = (error as Error).message;
      this.diagnostics.hidden = false;
      this.diagnostics.replaceChildren(h("div.diagnostic.error", {}, message));
      toast(message, "error", 6000);
    }
  }

  private show(program: string, items: BreakpointInfo[]): void {
    this.program = program;
    const robotName = (id: number | null): string => (id === null ? "any robot" : (this.session.robotInfo(id)?.name ?? `robot ${id}`));
    this.list.replaceChildren(
      ...(items.length
        ? items.map((b) => {
            const enabled = h("input", {
              type: "checkbox",
              "aria-label": `enable ${b.description}`,
              onchange: () => void this.enable(b, enabled.checked),
            });
            enabled.checked = b.enabled;
            return h(
              "li",
              { class: b.problem ? "breakpoint problem" : "breakpoint", "data-breakpoint": b.breakpoint, title: b.problem ?? "" },
              enabled,
              h("code", {}, b.description),
              h("span.muted", {}, ` ${robotName(b.robot)}`),
              b.problem ? h("span.problem", {}, ` (${b.problem})`) : null,
              h("button.icon", { title: "Remove", "aria-label": `remove ${b.description}`, onclick: () => void this.remove(b) }, "×"),
            );
          })
        : [h("li.muted", {}, "None. Right-click a state for enter/leave, or add one below.")]),
    );
  }

  private async enable(b: BreakpointInfo, enabled: boolean): Promise<void> {
    try {
      this.show(b.program, (await this.connection.command("enable_breakpoint", { program: b.program, breakpoint: b.breakpoint, enabled })).breakpoints);
    } catch (error) {
      toast((error as Error).message, "error");
    }
  }

  private async remove(b: BreakpointInfo): Promise<void> {
    try {
      this.show(b.program, (await this.connection.command("remove_breakpoint", { program: b.program, breakpoint: b.breakpoint })).breakpoints);
    } catch (error) {
      toast((error as Error).message, "error");
    }
  }

  /// A hit: select the robot, go to its tick, remember it for the timeline. Hits of one tick
  /// (several robots, several breakpoints) are told in one message; the selected robot stays
  /// selected when it is among them, else the first robot that hit is selected.
  onHit(event: BreakpointEvent): void {
    const hit = { t: event.t, seq: event.seq, robot: event.robot, description: event.description, program: event.program, breakpoint: event.breakpoint };
    this.hits.push(hit);
    if (this.hits.length > 200) this.hits.shift();
    const batch = this.batch && this.batch.seq === event.seq ? this.batch : (this.batch = { seq: event.seq, t: event.t, robots: [], descriptions: [] });
    if (!batch.robots.includes(event.robot)) batch.robots.push(event.robot);
    if (!batch.descriptions.includes(event.description)) batch.descriptions.push(event.description);
    if (!batch.robots.includes(this.session.selectedRobot) || batch.robots.length === 1) this.session.selectRobot(batch.robots[0] as number);
    this.session.seekTick(event.t, event.seq);
    clearTimeout(this.toastTimer);
    this.toastTimer = window.setTimeout(() => {
      const names = batch.robots.map((r) => this.session.robotInfo(r)?.name ?? `robot ${r}`).join(", ");
      toast(`Breakpoint: ${batch.descriptions.join("; ")} on ${names} at ${formatClock(batch.t)} (paused)`, "info", 6000);
    }, 30);
    this.showHits(event.seq);
    this.onHitsChanged();
  }

  /// The hits of tick `seq` (the newest), each with its "Save as test" button; the selected
  /// robot's first, at most 8.
  private showHits(seq: number): void {
    const selected = this.session.selectedRobot;
    const hits = this.hits.filter((x) => x.seq === seq).sort((a, b) => Number(b.robot === selected) - Number(a.robot === selected)).slice(0, 8);
    this.hitList.replaceChildren(
      ...hits.map((x) => {
        const name = this.session.robotInfo(x.robot)?.name ?? `robot ${x.robot}`;
        return h(
          "li.breakpoint-hit",
          { "data-breakpoint": x.breakpoint },
          h("span", {}, `Hit: `, h("code", {}, x.description), ` on ${name} at ${formatClock(x.t)}`),
          h("button", { title: "Write a test that starts from the world at this tick and asserts what the breakpoint waited for", onclick: () => void this.saveAsTest(x) }, "Save as test"),
        );
      }),
    );
  }

  /// "Save as test" of hit `hit`: the robot at the hit's tick, the breakpoint named for the server.
  async saveAsTest(hit: Hit): Promise<void> {
    this.session.selectRobot(hit.robot);
    this.session.seekTick(hit.t, hit.seq);
    const state = this.session.robotInView();
    const index = this.session.indexOf(hit.robot);
    const name = this.session.robotInfo(hit.robot)?.name;
    if (!state || !index || !name) return toast("Nothing to save: the robot has no XABSL behavior at the hit's tick", "error");
    const body = hitDraftBody(name, state, index, { program: hit.program, breakpoint: hit.breakpoint, seq: hit.seq }, hit.description);
    await saveDraft(body);
  }
}
