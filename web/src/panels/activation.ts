/// The activation tree of the selected robot at the tick in view: options with their state,
/// option and state times and parameter values; basic behaviors with their parameters; and the
/// output assignments of each active state with the values the outputs hold. Rows are rebuilt
/// only when the path's shape changes; otherwise only their texts change.
import type { DescriptionIndex } from "../description";
import type { RobotState, PathNode } from "../protocol";
import type { Session, SessionEvent } from "../session";
import { formatClock, formatMs, formatValue, h, setText } from "../ui";

interface Row {
  node: PathNode;
  times: HTMLElement | null;
  params: HTMLElement[];
  outputs: Array<{ el: HTMLElement; id: number; type: string; enumName: string | null }>;
}

export class ActivationPanel {
  readonly element: HTMLElement;
  private readonly list: HTMLElement;
  private readonly head: HTMLElement;
  private rows: Row[] = [];
  private shape = "\u0000";

  constructor(
    private readonly session: Session,
    private readonly openOption: (id: number) => void,
  ) {
    this.head = h("div.toolbar.muted");
    this.list = h("div.tree", { role: "tree", "aria-label": "Activation tree" });
    this.element = h("div.panel.activation-panel", {}, this.head, this.list);
  }

  render(changes: Set<SessionEvent>): void {
    const session = this.session;
    const robot = session.robotInView();
    const index = session.indexOf(session.selectedRobot);
    const info = session.robotInfo(session.selectedRobot);
    const tick = session.view;
    setText(this.head, info ? `${info.name}${tick ? ` · t = ${formatClock(tick.t)}` : ""}${session.isLive ? "" : " · scrubbed"}${robot?.forced ? " · forced root" : ""}` : "");
    const shape = `${robot?.shape ?? ""}|${robot?.fault ? "F" : ""}|${session.selectedRobot}`;
    if (shape !== this.shape || changes.has("hello")) {
      this.shape = shape;
      this.build(robot, index);
    }
    this.update(robot, index);
  }

  private build(robot: RobotState | null, index: DescriptionIndex | null): void {
    this.rows = [];
    const children: HTMLElement[] = [];
    if (robot?.fault) {
      const f = robot.fault;
      children.push(h("div.fault", {}, h("strong", {}, "Fault: "), f.message, f.option ? ` (in ${f.option}${f.state ? `.${f.state}` : ""})` : ""));
    }
    if (!robot || !robot.path.length) {
      children.push(h("div.empty", {}, robot ? "Nothing active." : this.session.hello ? "No data for this robot yet." : "Connecting…"));
    }
    for (const node of robot?.path ?? []) {
      const indent = `padding-left:${node.depth * 16 + 4}px`;
      if (node.kind === "option") {
        const option = index?.optionById.get(node.option);
        const state = option?.states[node.state];
        const times = h("span.times");
        const params = (option?.params ?? []).map(() => h("span.pvalue"));
        const paramEls = (option?.params ?? []).map((p, i) => h("span.param", { title: p.doc ?? "" }, `@${p.short_name}=`, params[i] as HTMLElement, p.unit ? h("span.unit", {}, p.unit) : null));
        const outputs: Row["outputs"] = [];
        const assignEls: HTMLElement[] = [];
        for (const action of [...(option?.common_action ?? []), ...(state?.actions ?? [])]) {
          if (action.type !== "assign") continue;
          const symbol = index?.outputByName.get(action.symbol);
          const value = h("span.ovalue");
          if (symbol) outputs.push({ el: value, id: symbol.id, type: symbol.type, enumName: symbol.enum });
          assignEls.push(h("div.assign", { style: `padding-left:${node.depth * 16 + 26}px`, title: `${action.symbol} = ${action.value}` }, h("span.muted", {}, `${action.symbol} = `), value, h("span.muted.small", {}, `  ⟵ ${action.value}`)));
        }
        const el = h(
          "div.row.option-row",
          { role: "treeitem", style: indent, tabindex: 0, title: option?.doc ?? "", "data-option": node.option },
          h("span.kind", {}, "◆"),
          h("button.link", { onclick: () => this.openOption(node.option) }, option?.name ?? `option ${node.option}`),
          h("span.state", {}, state?.name ?? `state ${node.state}`),
          times,
          ...paramEls,
        );
        el.addEventListener("keydown", (ev) => ev.key === "Enter" && this.openOption(node.option));
        children.push(el, ...assignEls);
        this.rows.push({ node, times, params, outputs });
      } else {
        const behavior = index?.behaviorById.get(node.behavior);
        const times = h("span.times");
        const params = (behavior?.params ?? []).map(() => h("span.pvalue"));
        const paramEls = (behavior?.params ?? []).map((p, i) => h("span.param", { title: p.doc ?? "" }, `${p.short_name}=`, params[i] as HTMLElement, p.unit ? h("span.unit", {}, p.unit) : null));
        children.push(
          h("div.row.behavior-row", { role: "treeitem", style: indent, title: behavior?.doc ?? "" }, h("span.kind", {}, "●"), h("span.bname", {}, behavior?.name ?? `behavior ${node.behavior}`), times, ...paramEls),
        );
        this.rows.push({ node, times, params, outputs: [] });
      }
    }
    this.list.replaceChildren(...children);
  }

  private update(robot: RobotState | null, index: DescriptionIndex | null): void {
    if (!robot) return;
    robot.path.forEach((node, i) => {
      const row = this.rows[i];
      if (!row) return;
      if (node.kind === "option") {
        const option = index?.optionById.get(node.option);
        if (row.times) setText(row.times, `${formatMs(node.optionTime)} / ${formatMs(node.stateTime)}`);
        option?.params.forEach((p, k) => row.params[k] && setText(row.params[k] as HTMLElement, formatValue(node.params[k], p.type, p.enum, index)));
      } else {
        const behavior = index?.behaviorById.get(node.behavior);
        if (row.times) setText(row.times, formatMs(node.time));
        behavior?.params.forEach((p, k) => row.params[k] && setText(row.params[k] as HTMLElement, formatValue(node.params[k], p.type, p.enum, index)));
      }
      for (const o of row.outputs) setText(o.el, formatValue(robot.outputs[o.id], o.type as "decimal", o.enumName, index));
    });
  }
}
