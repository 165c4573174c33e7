/// The team strip: one chip per robot with its number, root option, root state and role; click
/// (or press 1..9, 0) to select. Rows are built once per hello and only their texts change.
import type { Session, SessionEvent } from "../session";
import { h, setText, toggleClass } from "../ui";
import { roleOf } from "./roles";

interface Chip {
  id: number;
  el: HTMLElement;
  root: HTMLElement;
  state: HTMLElement;
  role: HTMLElement;
}

export class TeamStrip {
  readonly element: HTMLElement;
  private chips: Chip[] = [];

  constructor(private readonly session: Session) {
    this.element = h("div.panel.team-strip", { role: "listbox", "aria-label": "Agents" });
  }

  private build(): void {
    const session = this.session;
    const teams = session.scene?.teams ?? [];
    this.element.replaceChildren();
    // the left region gives the strip room for every chip (style.css, .team-strip)
    this.element.style.setProperty("--chips", String(session.robots.length));
    this.chips = session.robots.map((robot, i) => {
      const color = teams.find((t) => t.name === robot.team)?.color ?? "#888";
      const root = h("span.chip-root");
      const state = h("span.chip-state");
      const role = h("span.chip-role");
      const key = i < 9 ? String(i + 1) : i === 9 ? "0" : "";
      // An attached session names each robot's host, and marks the robots of a host that went away.
      const attached = robot as { host?: string; gone?: boolean };
      const where = attached.host ? ` on ${attached.host}${attached.gone ? " (gone: its values are unknown until it reattaches)" : ""}` : "";
      const el = h(
        "button.chip",
        {
          role: "option",
          "data-robot": robot.id,
          title: `${robot.name}${robot.program ? ` runs ${robot.program}` : " (no XABSL engine)"}${where}${key ? ` — key ${key}` : ""}`,
          "data-gone": attached.gone ? "true" : null,
          onclick: () => session.selectRobot(robot.id),
        },
        h("span.chip-number", { style: `background:${color}` }, String(robot.number)),
        h("span.chip-text", {}, h("span.chip-name", {}, robot.name), root, state),
        role,
      );
      this.element.append(el);
      return { id: robot.id, el, root, state, role };
    });
  }

  render(changes: Set<SessionEvent>): void {
    const session = this.session;
    if (changes.has("hello") || this.chips.length !== session.robots.length) this.build();
    const tick = session.view;
    for (const chip of this.chips) {
      toggleClass(chip.el, "selected", chip.id === session.selectedRobot);
      chip.el.setAttribute("aria-selected", String(chip.id === session.selectedRobot));
      const robot = tick?.robots.find((a) => a.id === chip.id) ?? null;
      const index = session.indexOf(chip.id);
      const root = robot?.path[0];
      let rootText = "–";
      let stateText = "";
      if (root?.kind === "option") {
        const option = index?.optionById.get(root.option);
        rootText = option?.name ?? String(root.option);
        stateText = option?.states[root.state]?.name ?? "";
      } else if (root?.kind === "behavior") {
        rootText = index?.behaviorById.get(root.behavior)?.name ?? String(root.behavior);
      }
      if (robot?.fault) stateText = "fault";
      setText(chip.root, rootText);
      setText(chip.state, stateText);
      setText(chip.role, roleOf(session, chip.id, robot) ?? "");
      toggleClass(chip.el, "faulted", !!robot?.fault);
      toggleClass(chip.el, "forced", !!robot?.forced);
    }
  }
}
