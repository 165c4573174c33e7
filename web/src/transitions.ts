/// The transitions of an option's state machine with their conditions in full, and the last one
/// that fired at a moment of the history (for the option view's marks and list).
import { type DecisionTree, isLeaf, type Option } from "./description";
import type { OptionNode, Tick } from "./protocol";

/// One state-changing leaf: `from` and `to` are state ids, `condition` the whole path to it.
export interface TransitionInfo {
  from: number;
  to: number;
  leaf: number;
  condition: string;
}

/// Every edge of the state machine, in state order then leaf order (as the server draws them).
export function transitionsOf(option: Option): TransitionInfo[] {
  const byName = new Map(option.states.map((s) => [s.name, s.id]));
  const out: TransitionInfo[] = [];
  for (const state of option.states) {
    const walk = (tree: DecisionTree, path: string[]): void => {
      if (isLeaf(tree)) {
        const to = tree.to === null ? undefined : byName.get(tree.to);
        if (!tree.stay && to !== undefined && to !== state.id) out.push({ from: state.id, to, leaf: tree.leaf, condition: path.length ? path.join(" && ") : "always" });
        return;
      }
      walk(tree.then, [...path, tree.if]);
      walk(tree.else, [...path, `!(${tree.if})`]);
    };
    walk(state.decision, []);
  }
  return out;
}

/// The last state change of option `optionId` of robot `robotId` at or before `ticks[end]`
/// (looking back at most `limit` ticks), or null.
export function lastTransitionBefore(ticks: readonly Tick[], end: number, robotId: number, optionId: number, limit = 4800): { from: number; to: number; leaf: number; t: number } | null {
  for (let i = Math.min(end, ticks.length - 1); i >= 0 && end - i < limit; i--) {
    const tick = ticks[i] as Tick;
    const robot = tick.robots.find((r) => r.id === robotId);
    const node = robot?.path.find((n) => n.kind === "option" && n.option === optionId) as OptionNode | undefined;
    if (node && node.leaf >= 0 && node.decidedIn !== node.state) return { from: node.decidedIn, to: node.state, leaf: node.leaf, t: tick.t };
  }
  return null;
}
