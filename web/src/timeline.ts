/// The timeline model: which option was active in which state, and when, over buffered ticks.
///
/// Pure functions from ticks to rows of segments, so the canvas only draws. A segment is a run
/// of consecutive buffered ticks in which an option (row) was active in one state (segment
/// label); it ends where the next tick starts, so adjacent segments touch. Times are timeline
/// times (`Tick.x`); ticks of different generations (reloads, resets) are read each with the
/// description of its own generation, and rows are kept by option / behavior name across them.
import type { DescriptionIndex } from "./description";
import type { PathNode, Tick } from "./protocol";

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

/// The row a path node runs in: its kind and name (rows are kept by name across generations).
function rowOf(node: PathNode, idx: DescriptionIndex | null): { key: string; label: string } {
  const label =
    node.kind === "option"
      ? (idx?.optionById.get(node.option)?.name ?? `option ${node.option}`)
      : (idx?.behaviorById.get(node.behavior)?.name ?? `behavior ${node.behavior}`);
  return { key: `${node.kind === "option" ? "o" : "b"}${label}`, label };
}

function nodeId(node: PathNode): number {
  return node.kind === "option" ? node.option : node.behavior;
}

/// The segment a node adds to its row (`rowLabel`): its state (options), the behavior itself.
function segmentOf(node: PathNode, idx: DescriptionIndex | null, rowLabel: string): { key: number; label: string } {
  if (node.kind === "behavior") return { key: node.behavior, label: rowLabel };
  const stateName = idx?.optionById.get(node.option)?.states[node.state]?.name ?? `state ${node.state}`;
  return { key: stateKey(stateName), label: stateName };
}

/// A team row's segment label for a robot's root node: `option/state`, or the basic behavior.
function teamLabel(root: PathNode, index: DescriptionIndex | null): string {
  if (root.kind === "option") {
    const option = index?.optionById.get(root.option);
    return `${option?.name ?? root.option}/${option?.states[root.state]?.name ?? root.state}`;
  }
  return index?.behaviorById.get(root.behavior)?.name ?? `behavior ${root.behavior}`;
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
      const { key, label } = rowOf(node, idx);
      let row = rows.get(key);
      if (!row) {
        row = { kind: node.kind, id: nodeId(node), label, depth: node.depth, segments: [], first: i };
        rows.set(key, row);
      }
      row.id = nodeId(node); // the id of the newest generation seen
      row.depth = Math.min(row.depth, node.depth);
      const seg = segmentOf(node, idx, row.label);
      extend(row, tick.x, t1, seg.key, seg.label, activeBefore.has(key));
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
      const label = teamLabel(root, indexOf(robot.id, tick.gen));
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

// ------------------------------------------------------------------------ incremental model

/// What a timeline model is built for. Another robot or another list of agents rebuilds it.
export interface TimelineContext {
  /// The robot whose options and behaviors get rows (`buildRobotTimeline`'s `robotId`).
  robotId: number;
  /// The team rows, in order (`buildTeamTimeline`'s `agents`).
  agents: ReadonlyArray<{ id: number; name: string }>;
  /// The description robot `robotId` read generation `gen` with. Its answers must not change
  /// until `TimelineBuilder.invalidate` (a hello or history answer changes them).
  indexOf: (robotId: number, gen: number) => DescriptionIndex | null;
}

/// How `TimelineBuilder.update` brought the model up to date.
export type TimelineUpdate = "rebuilt" | "appended" | "unchanged";

/// The timeline model kept up to date with a `TickBuffer` at the cost of the ticks that changed.
///
/// `rows` and `team` equal `buildRobotTimeline` and `buildTeamTimeline` over the ticks of the
/// last `update`. The buffer only appends at its end and drops ticks from its front between
/// merges, so an update adds the new ticks (the newest tick's end is provisional until the next
/// one arrives: it is set again then) and trims what the front drop took: segments that ended
/// before the new oldest tick go, one that covers it starts there instead. Row order by first
/// appearance is then first appearance in what is still buffered (ties by position in that
/// tick's path), and depths are the shallowest still buffered, as a full build would give; team
/// colours (segment keys) are renumbered when the first appearance of a label went.
///
/// It rebuilds from all ticks after `invalidate`, for another context, and whenever it cannot
/// be sure the incremental state is right: another array (a merge, clear or retain replaced
/// it), the newest tick it read is not where its seq says, something appeared before the oldest
/// one it knew, time went back at the first new tick, or the new oldest tick is ambiguous
/// (a row twice in its path, a robot twice in it, a segment over the cut that it does not hold).
export class TimelineBuilder {
  private source: readonly Tick[] | null = null;
  private oldest: Tick | null = null;
  private newest: Tick | null = null;
  private context: TimelineContext | null = null;
  private robot: RobotRows = new RobotRows(0, () => null);
  private teamRows: TeamRows = new TeamRows([], () => null);
  /// Rows of the context's robot, as `buildRobotTimeline` orders them.
  rows: TimelineRow[] = [];
  /// One row per agent, as `buildTeamTimeline`.
  team: TimelineRow[] = [];

  /// Forget everything: the next update builds from all ticks (descriptions changed).
  invalidate(): void {
    this.source = null;
  }

  /// Bring `rows` and `team` up to date with `ticks` (the buffer's array, `TickBuffer.all`).
  update(ticks: readonly Tick[], context: TimelineContext): TimelineUpdate {
    const from = this.context && sameContext(this.context, context) ? this.follow(ticks) : null;
    if (from === null || !this.trim(ticks)) {
      this.rebuild(ticks, context);
      return "rebuilt";
    }
    const unchanged = from === ticks.length && ticks[0] === this.oldest;
    this.context = context;
    for (let i = from; i < ticks.length; i++) this.step(ticks, i);
    this.finish(ticks);
    return unchanged ? "unchanged" : "appended";
  }

  private rebuild(ticks: readonly Tick[], context: TimelineContext): void {
    this.context = context;
    this.robot = new RobotRows(context.robotId, (gen) => context.indexOf(context.robotId, gen));
    this.teamRows = new TeamRows(context.agents, context.indexOf);
    for (let i = 0; i < ticks.length; i++) this.step(ticks, i);
    this.finish(ticks);
  }

  /// Where the ticks new since the last update start in `ticks` (null: rebuild).
  private follow(ticks: readonly Tick[]): number | null {
    const newest = this.newest;
    const oldest = this.oldest;
    if (ticks !== this.source || !newest || !oldest) return null;
    const at = indexOfSeq(ticks, newest.seq);
    if (at < 0 || ticks[at] !== newest) return null;
    const front = ticks[0] as Tick; // at >= 0: not empty
    // Only drops may have happened at the front: the oldest is the one known or a later one.
    if (front.seq < oldest.seq || (front.seq === oldest.seq && front !== oldest)) return null;
    // The newest was read with a provisional end, which is only as good as a later start.
    const next = ticks[at + 1];
    if (next && next.x < newest.x) return null;
    return at + 1;
  }

  /// Cut the model to a front drop of the buffer (false: it cannot be done exactly).
  private trim(ticks: readonly Tick[]): boolean {
    const front = ticks[0];
    if (!front || front === this.oldest) return true;
    return this.robot.trimTo(front) && this.teamRows.trimTo(front);
  }

  /// Read tick `i`: the previous tick's segments end where it starts, its own at its end.
  private step(ticks: readonly Tick[], i: number): void {
    const tick = ticks[i] as Tick;
    this.robot.endNewest(tick.x);
    this.teamRows.endNewest(tick.x);
    const t1 = tickEnd(ticks, i);
    this.robot.add(tick, t1);
    this.teamRows.add(tick, t1);
  }

  private finish(ticks: readonly Tick[]): void {
    this.source = ticks;
    this.oldest = ticks[0] ?? null;
    this.newest = ticks[ticks.length - 1] ?? null;
    if (ticks.length) {
      // The newest tick's end depends on the one before it, which a front drop may have taken.
      const end = tickEnd(ticks, ticks.length - 1);
      this.robot.endNewest(end);
      this.teamRows.endNewest(end);
    }
    this.rows = this.robot.ordered();
    this.team = this.teamRows.rows;
  }
}

function sameContext(a: TimelineContext, b: TimelineContext): boolean {
  if (a.robotId !== b.robotId || a.agents.length !== b.agents.length) return false;
  return a.agents.every((agent, i) => agent.id === b.agents[i]?.id && agent.name === b.agents[i]?.name);
}

/// Index of the tick with `seq` in `ticks` (ordered by seq), or -1.
function indexOfSeq(ticks: readonly Tick[], seq: number): number {
  let lo = 0;
  let hi = ticks.length - 1;
  while (lo <= hi) {
    const mid = (lo + hi) >> 1;
    const s = (ticks[mid] as Tick).seq;
    if (s === seq) return mid;
    if (s < seq) lo = mid + 1;
    else hi = mid - 1;
  }
  return -1;
}

/// A row's segments with what a front drop needs per segment: the seqs of its first and last
/// tick, and its node's position in its first tick (the path, or the tick's robots), which
/// orders rows and labels that first appear in the same tick.
class Runs {
  private readonly firstSeq: number[] = [];
  private readonly firstPos: number[] = [];
  private readonly lastSeq: number[] = [];

  constructor(readonly segments: Segment[]) {}

  /// `extend`, noting the ticks; returns the segment the tick went into.
  add(seq: number, pos: number, t0: number, t1: number, key: number, label: string, continuing: boolean): Segment {
    const n = this.segments.length;
    const last = this.segments[n - 1];
    if (continuing && last && last.key === key && last.label === label && last.t1 >= t0) {
      last.t1 = t1;
      this.lastSeq[n - 1] = seq;
      return last;
    }
    const segment = { t0, t1, key, label };
    this.segments.push(segment);
    this.firstSeq.push(seq);
    this.firstPos.push(pos);
    this.lastSeq.push(seq);
    return segment;
  }

  /// Drop the segments whose ticks are all older than `seq`.
  dropBefore(seq: number): void {
    let k = 0;
    while (k < this.lastSeq.length && (this.lastSeq[k] as number) < seq) k++;
    if (!k) return;
    this.segments.splice(0, k);
    this.firstSeq.splice(0, k);
    this.firstPos.splice(0, k);
    this.lastSeq.splice(0, k);
  }

  /// Whether the first segment started before `seq` (it goes over a front cut).
  startsBefore(seq: number): boolean {
    return this.firstSeq.length > 0 && (this.firstSeq[0] as number) < seq;
  }

  /// Let the first segment start at tick `seq` (time `x`, the node at `pos`).
  startAt(seq: number, pos: number, x: number): void {
    (this.segments[0] as Segment).t0 = x;
    this.firstSeq[0] = seq;
    this.firstPos[0] = pos;
  }

  /// The first tick (seq) and position in it of the first segment (Infinity: none).
  get first(): { seq: number; pos: number } {
    return { seq: this.firstSeq[0] ?? Infinity, pos: this.firstPos[0] ?? Infinity };
  }

  /// First tick and position of each segment, in order.
  forEachStart(fn: (segment: Segment, seq: number, pos: number) => void): void {
    this.segments.forEach((segment, k) => fn(segment, this.firstSeq[k] as number, this.firstPos[k] as number));
  }
}

/// The minimum of values pushed in seq order, over those not older than a moving front (a
/// monotonic queue: each value enters and leaves once).
class WindowMin {
  private readonly seqs: number[] = [];
  private readonly values: number[] = [];
  private head = 0;

  push(seq: number, value: number): void {
    // A value not smaller than a newer one can never be the minimum again.
    while (this.values.length > this.head && (this.values[this.values.length - 1] as number) >= value) {
      this.values.pop();
      this.seqs.pop();
    }
    this.seqs.push(seq);
    this.values.push(value);
  }

  dropBefore(seq: number): void {
    while (this.head < this.seqs.length && (this.seqs[this.head] as number) < seq) this.head++;
    if (this.head > 64 && this.head * 2 > this.seqs.length) {
      this.seqs.splice(0, this.head);
      this.values.splice(0, this.head);
      this.head = 0;
    }
  }

  get min(): number {
    return this.values[this.head] ?? Infinity;
  }
}

interface RobotRow {
  row: TimelineRow;
  runs: Runs;
  depths: WindowMin;
}

/// The selected robot's rows, as `buildRobotTimeline` reads ticks, kept for front drops.
class RobotRows {
  private readonly byKey = new Map<string, RobotRow>();
  private activeBefore = new Set<string>();
  /// The segments the newest tick went into (their end is the newest tick's).
  private newest: Segment[] = [];

  constructor(
    private readonly robotId: number,
    private readonly indexOf: (gen: number) => DescriptionIndex | null,
  ) {}

  endNewest(t1: number): void {
    for (const segment of this.newest) segment.t1 = t1;
  }

  add(tick: Tick, t1: number): void {
    const path = tick.robots.find((a) => a.id === this.robotId)?.path ?? [];
    const idx = path.length ? this.indexOf(tick.gen) : null;
    const activeNow = new Set<string>();
    this.newest = [];
    path.forEach((node, pos) => {
      const { key, label } = rowOf(node, idx);
      let state = this.byKey.get(key);
      if (!state) {
        const row: TimelineRow = { kind: node.kind, id: nodeId(node), label, depth: node.depth, segments: [] };
        state = { row, runs: new Runs(row.segments), depths: new WindowMin() };
        this.byKey.set(key, state);
      }
      state.row.id = nodeId(node); // the id of the newest generation seen
      state.depths.push(tick.seq, node.depth);
      state.row.depth = state.depths.min;
      const seg = segmentOf(node, idx, state.row.label);
      this.newest.push(state.runs.add(tick.seq, pos, tick.x, t1, seg.key, seg.label, this.activeBefore.has(key)));
      activeNow.add(key);
    });
    this.activeBefore = activeNow;
  }

  /// Forget what is older than `front`, the new oldest tick (false: not exactly possible).
  trimTo(front: Tick): boolean {
    // A full build reads `front` as the first tick: every row in its path starts a segment
    // there, at the node's position (a row twice in the path would start two: rebuild).
    const path = front.robots.find((a) => a.id === this.robotId)?.path ?? [];
    const idx = path.length ? this.indexOf(front.gen) : null;
    const posAtFront = new Map<string, number>();
    for (let pos = 0; pos < path.length; pos++) {
      const { key } = rowOf(path[pos] as PathNode, idx);
      if (posAtFront.has(key)) return false;
      posAtFront.set(key, pos);
    }
    for (const [key, state] of this.byKey) {
      state.runs.dropBefore(front.seq);
      if (!state.runs.segments.length) {
        this.byKey.delete(key); // ran only in dropped ticks: a full build has no such row
        continue;
      }
      if (state.runs.startsBefore(front.seq)) {
        const pos = posAtFront.get(key);
        if (pos === undefined) return false;
        state.runs.startAt(front.seq, pos, front.x);
      }
      state.depths.dropBefore(front.seq);
      state.row.depth = state.depths.min;
    }
    return true;
  }

  /// Shallowest depth first, options before behaviors, then first appearance (tick, then path position).
  ordered(): TimelineRow[] {
    return [...this.byKey.values()]
      .map((state) => ({ state, first: state.runs.first }))
      .sort(
        (a, b) =>
          a.state.row.depth - b.state.row.depth ||
          (a.state.row.kind === b.state.row.kind ? 0 : a.state.row.kind === "option" ? -1 : 1) ||
          a.first.seq - b.first.seq ||
          a.first.pos - b.first.pos,
      )
      .map(({ state }) => state.row);
  }
}

/// The team rows, as `buildTeamTimeline` reads ticks, kept for front drops.
class TeamRows {
  readonly rows: TimelineRow[];
  private readonly byId = new Map<number, Runs>();
  /// Per label: its key (the rank of its first appearance) and that first appearance.
  private labels = new Map<string, { key: number; seq: number; pos: number }>();
  private newest: Segment[] = [];

  constructor(
    agents: ReadonlyArray<{ id: number; name: string }>,
    private readonly indexOf: (robotId: number, gen: number) => DescriptionIndex | null,
  ) {
    this.rows = agents.map<TimelineRow>((a) => ({ kind: "robot", id: a.id, label: a.name, depth: 0, segments: [] }));
    for (const row of this.rows) this.byId.set(row.id, new Runs(row.segments));
  }

  endNewest(t1: number): void {
    for (const segment of this.newest) segment.t1 = t1;
  }

  add(tick: Tick, t1: number): void {
    this.newest = [];
    tick.robots.forEach((robot, pos) => {
      const runs = this.byId.get(robot.id);
      const root = robot.path[0];
      if (!runs || !root) return;
      const label = teamLabel(root, this.indexOf(robot.id, tick.gen));
      let known = this.labels.get(label);
      if (!known) {
        known = { key: this.labels.size, seq: tick.seq, pos };
        this.labels.set(label, known);
      }
      const last = runs.segments[runs.segments.length - 1];
      this.newest.push(runs.add(tick.seq, pos, tick.x, t1, known.key, label, !!last && last.t1 >= tick.x));
    });
  }

  /// Forget what is older than `front`, the new oldest tick (false: not exactly possible).
  trimTo(front: Tick): boolean {
    const posAtFront = new Map<number, number>();
    for (let pos = 0; pos < front.robots.length; pos++) {
      const robot = front.robots[pos] as Tick["robots"][number];
      if (!this.byId.has(robot.id) || !robot.path[0]) continue;
      if (posAtFront.has(robot.id)) return false;
      posAtFront.set(robot.id, pos);
    }
    for (const [id, runs] of this.byId) {
      runs.dropBefore(front.seq);
      if (!runs.startsBefore(front.seq)) continue;
      // A segment over the cut continued across ticks without the robot: not what a full build reads.
      const pos = posAtFront.get(id);
      if (pos === undefined) return false;
      runs.startAt(front.seq, pos, front.x);
    }
    for (const known of this.labels.values()) {
      if (known.seq < front.seq) {
        this.rankLabels();
        break;
      }
    }
    return true;
  }

  /// Key the labels still buffered by their first appearance, as a full build numbers them.
  private rankLabels(): void {
    const firsts = new Map<string, { seq: number; pos: number }>();
    for (const runs of this.byId.values()) {
      runs.forEachStart((segment, seq, pos) => {
        const known = firsts.get(segment.label);
        if (!known || seq < known.seq || (seq === known.seq && pos < known.pos)) firsts.set(segment.label, { seq, pos });
      });
    }
    const ranked = [...firsts].sort(([, a], [, b]) => a.seq - b.seq || a.pos - b.pos);
    const labels = new Map(ranked.map(([label, first], key) => [label, { key, ...first }]));
    const renumbered = ranked.some(([label], key) => this.labels.get(label)?.key !== key);
    this.labels = labels;
    if (!renumbered) return;
    for (const row of this.rows) for (const segment of row.segments) segment.key = (labels.get(segment.label) as { key: number }).key;
  }
}
