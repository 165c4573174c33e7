/// What "Save as test" sends to `POST /api/tests/draft`: the selected robot's situation in the tick
/// in view — the forced root with its parameters, the input overrides (enum values by element
/// name) and the option states and basic behaviors that were active (docs/tests.md).
import type { DescriptionIndex, Parameter } from "../description";
import type { RobotState } from "../protocol";
import type { WireValue } from "../messages.gen";

export interface TestDraftBody {
  name: string;
  robot: string;
  force: { kind: "option" | "behavior"; name: string; params: Record<string, WireValue | string> } | null;
  overrides: Record<string, WireValue | string>;
  active: Array<[string, string]>;
  behaviors: string[];
  duration: number;
}

function named(index: DescriptionIndex, param: { type: string; enum: string | null }, value: WireValue): WireValue | string {
  if (param.type !== "enum" || typeof value !== "number") return value;
  const elements = index.enumByName.get(param.enum ?? "")?.elements ?? [];
  return elements[value] ?? value;
}

function params(index: DescriptionIndex, declared: Parameter[], values: WireValue[]): Record<string, WireValue | string> {
  const out: Record<string, WireValue | string> = {};
  declared.forEach((p, i) => {
    const v = values[i];
    if (v !== undefined && v !== null) out[p.short_name] = named(index, p, v);
  });
  return out;
}

/// The draft's body for `robot` (its name) in state `state`, or null without a description.
export function testDraftBody(robotName: string, state: RobotState, index: DescriptionIndex, duration = 5): TestDraftBody {
  const active: Array<[string, string]> = [];
  const behaviors: string[] = [];
  for (const node of state.path) {
    if (node.kind === "option") {
      const option = index.optionById.get(node.option);
      const s = option?.states.find((x) => x.id === node.state);
      if (option && s) active.push([option.name, s.name]);
    } else {
      const b = index.behaviorById.get(node.behavior);
      if (b && !behaviors.includes(b.name)) behaviors.push(b.name);
    }
  }
  let force: TestDraftBody["force"] = null;
  if (state.forced) {
    const [kind, id] = state.forced;
    const root = state.path.find((n) => n.depth === 0);
    if (kind === 0) {
      const option = index.optionById.get(id);
      const values = root?.kind === "option" && root.option === id ? root.params : [];
      if (option) force = { kind: "option", name: option.name, params: params(index, option.params, values) };
    } else {
      const b = index.behaviorById.get(id);
      const values = root?.kind === "behavior" && root.behavior === id ? root.params : [];
      if (b) force = { kind: "behavior", name: b.name, params: params(index, b.params, values) };
    }
  }
  const overrides: Record<string, WireValue | string> = {};
  for (const [id, value] of Object.entries(state.overrides ?? {})) {
    const symbol = index.description.inputs.find((s) => s.id === Number(id));
    if (symbol && value !== null) overrides[symbol.name] = named(index, symbol, value);
  }
  const what = force ? force.name : (active[0]?.[0] ?? "agent");
  return { name: `${robotName} ${what}`, robot: robotName, force, overrides, active, behaviors, duration };
}
