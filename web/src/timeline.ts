/// The timeline model: which option was active in which state, and when, over buffered ticks.
///
/// Pure functions from ticks to rows of segments, so the canvas only draws. A segment is a run
/// of consecutive buffered ticks in which an option (row) was active in one state (segment
/// label); it ends where the next tick starts, so adjacent segments touch. Times are timeline
/// times (`Tick.x`); ticks of different generations (reloads, resets) are read each with the
/// description of its own generation, and rows are kept by option / behavior name across them.
import type { DescriptionIndex } from "./description";
import type { Tick } from "./protocol";

export interface Segment {
  t0: number;
  t1: number;
  /// State id (option rows), behavior id (behavior rows), or a key of the label (team rows).
  key: number;
  label: string;
}

export interface TimelineRow {
  kind: "option" | "behavior" | "robot";
  /// Option id, behavior id, or robot id.
  id: number;
  label: string;
  depth: number;
  segments: Segment[];
}

function extend(row: TimelineRow, t0: number, t1: number, key: number, label: string, continuing: boolean): void {
  const last = row.segments[row.segments.length - 1];
  if (continuing && last && last.key === key && last.label === label && last.t1 >= t0) last.t1 = t1;
  else row.segments.push({ t0, t1, key, label });
}

/// End of tick `i`: the start of the next one, or one typical tick later for the newest.
function tickEnd(ticks: readonly Tick[], i: number): number {
  const next = ticks[i + 1];
  if (next) return next.x;
  const tick = ticks[i] as Tick;
  const prev = ticks[i - 1];
  return tick.x + (prev ? Math.max(1, tick.x - prev.x) : 25);
}

/// One row per option (segments per state) and per basic behavior the robot ran in `ticks`.
///
/// Rows are ordered by the shallowest depth the option ran at (options before basic behaviors of
/// the same depth), then by first appearance, so the root comes first and the chart reads like
/// the option graph from top to bottom.
export function buildRobotTimeline(
  ticks: readonly Tick[],
  robotId: number,
  index: DescriptionIndex | null | ((gen: number) => DescriptionIndex | null),
): TimelineRow[] {
  const rows = new Map<string, TimelineRow & { first: number }>();
  const activeBefore = new Set<string>();
  const indexOf = typeof index === "function" ? index : () => index;
  ticks.forEach((tick, i) => {
    const robot = tick.robots.find((a) => a.id === robotId);
    const t1 = tickEnd(ticks, i);
    const activeNow = new Set<string>();
    const idx = robot?.path.length ? indexOf(tick.gen) : null;
    for (const node of robot?.path ?? []) {
      const label =
        node.kind === "option"
          ? (idx?.optionById.get(node.option)?.name ?? `option ${node.option}`)
          : (idx?.behaviorById.get(node.behavior)?.name ?? `behavior ${node.behavior}`);
      const key = `${node.kind === "option" ? "o" : "b"}${label}`;
      let row = rows.get(key);
      if (!row) {
        row = { kind: node.kind, id: node.kind === "option" ? node.option : node.behavior, label, depth: node.depth, segments: [], first: i };
        rows.set(key, row);
      }
      row.id = node.kind === "option" ? node.option : node.behavior; // the id of the newest generation seen
      row.depth = Math.min(row.depth, node.depth);
      if (node.kind === "option") {
        const option = idx?.optionById.get(node.option);
        const stateName = option?.states[node.state]?.name ?? `state ${node.state}`;
        extend(row, tick.x, t1, stateKey(stateName), stateName, activeBefore.has(key));
      } else {
        extend(row, tick.x, t1, node.behavior, row.label, activeBefore.has(key));
      }
      activeNow.add(key);
    }
    activeBefore.clear();
    for (const k of activeNow) activeBefore.add(k);
  });
  return [...rows.values()]
    .sort((a, b) => a.depth - b.depth || (a.kind === b.kind ? 0 : a.kind === "option" ? -1 : 1) || a.first - b.first)
    .map(({ first: _first, ...row }) => row);
}

/// One row per robot: segments labelled `root option/state` of its root (or the basic behavior).
export function buildTeamTimeline(
  ticks: readonly Tick[],
  agents: ReadonlyArray<{ id: number; name: string }>,
  indexOf: (robotId: number, gen: number) => DescriptionIndex | null,
): TimelineRow[] {
  const rows = agents.map<TimelineRow>((a) => ({ kind: "robot", id: a.id, label: a.name, depth: 0, segments: [] }));
  const byId = new Map(rows.map((r) => [r.id, r]));
  const labels = new Map<string, number>();
  ticks.forEach((tick, i) => {
    const t1 = tickEnd(ticks, i);
    for (const robot of tick.robots) {
      const row = byId.get(robot.id);
      const root = robot.path[0];
      if (!row || !root) continue;
      const index = indexOf(robot.id, tick.gen);
      let label: string;
      if (root.kind === "option") {
        const option = index?.optionById.get(root.option);
        label = `${option?.name ?? root.option}/${option?.states[root.state]?.name ?? root.state}`;
      } else {
        label = index?.behaviorById.get(root.behavior)?.name ?? `behavior ${root.behavior}`;
      }
      let key = labels.get(label);
      if (key === undefined) {
        key = labels.size;
        labels.set(label, key);
      }
      const last = row.segments[row.segments.length - 1];
      extend(row, tick.x, t1, key, label, !!last && last.t1 >= tick.x);
    }
  });
  return rows;
}

/// A segment key for a state by name (its colour stays when a reload renumbers the states).
function stateKey(name: string): number {
  let hash = 0;
  for (let i = 0; i < name.length; i++) hash = (hash * 31 + name.charCodeAt(i)) | 0;
  return Math.abs(hash) % 9973;
}

/// A stable colour for a segment key (state id or label key): hue spread by the golden angle.
export function segmentHue(key: number): number {
  return Math.round((key * 137.508 + 200) % 360);
}
