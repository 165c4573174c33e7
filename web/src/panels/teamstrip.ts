/// The team strip: one chip per agent with its number, root option, root state and role; click
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
    this.element.style.setProperty("--chips", String(session.agents.length));
    this.chips = session.agents.map((agent, i) => {
      const color = teams.find((t) => t.name === agent.team)?.color ?? "#888";
      const root = h("span.chip-root");
      const state = h("span.chip-state");
      const role = h("span.chip-role");
      const key = i < 9 ? String(i + 1) : i === 9 ? "0" : "";
      const el = h(
        "button.chip",
        {
          role: "option",
          "data-agent": agent.id,
          title: `${agent.name}${agent.program ? ` runs ${agent.program}` : " (no XABSL engine)"}${key ? ` — key ${key}` : ""}`,
          onclick: () => session.selectAgent(agent.id),
        },
        h("span.chip-number", { style: `background:${color}` }, String(agent.number)),
        h("span.chip-text", {}, h("span.chip-name", {}, agent.name), root, state),
        role,
      );
      this.element.append(el);
      return { id: agent.id, el, root, state, role };
    });
  }

  render(changes: Set<SessionEvent>): void {
    const session = this.session;
    if (changes.has("hello") || this.chips.length !== session.agents.length) this.build();
    const tick = session.view;
    for (const chip of this.chips) {
      toggleClass(chip.el, "selected", chip.id === session.selectedAgent);
      chip.el.setAttribute("aria-selected", String(chip.id === session.selectedAgent));
      const agent = tick?.agents.find((a) => a.id === chip.id) ?? null;
      const index = session.indexOf(chip.id);
      const root = agent?.path[0];
      let rootText = "–";
      let stateText = "";
      if (root?.kind === "option") {
        const option = index?.optionById.get(root.option);
        rootText = option?.name ?? String(root.option);
        stateText = option?.states[root.state]?.name ?? "";
      } else if (root?.kind === "behavior") {
        rootText = index?.behaviorById.get(root.behavior)?.name ?? String(root.behavior);
      }
      if (agent?.fault) stateText = "fault";
      setText(chip.root, rootText);
      setText(chip.state, stateText);
      setText(chip.role, roleOf(session, chip.id, agent) ?? "");
      toggleClass(chip.el, "faulted", !!agent?.fault);
      toggleClass(chip.el, "forced", !!agent?.forced);
    }
  }
}
