/// The role of a robot, when its behavior has one: an output or internal symbol named `role`
/// (or `*.role`), shown as its enum element. Robot-soccer behaviors assign roles dynamically
/// (goalie, defender, supporter, striker); the field and the team strip label robots with it.
import type { DescriptionIndex, OutputSymbol } from "../description";
import type { RobotState } from "../protocol";
import type { Session } from "../session";
import { formatValue } from "../ui";

const cache = new WeakMap<DescriptionIndex, OutputSymbol | null>();

export function roleSymbol(index: DescriptionIndex): OutputSymbol | null {
  let symbol = cache.get(index);
  if (symbol === undefined) {
    const outputs = index.description.outputs;
    symbol =
      outputs.find((s) => s.name === "role") ??
      outputs.find((s) => /(^|\.)role$/.test(s.name)) ??
      outputs.find((s) => /role/i.test(s.name) && s.type === "enum") ??
      null;
    cache.set(index, symbol);
  }
  return symbol;
}

export function roleOf(session: Session, robotId: number, state: RobotState | null): string | null {
  const index = session.indexOf(robotId);
  if (!index || !state) return null;
  const symbol = roleSymbol(index);
  if (!symbol) return null;
  const value = state.outputs[symbol.id];
  return value === undefined ? null : formatValue(value, symbol.type, symbol.enum, index);
}
