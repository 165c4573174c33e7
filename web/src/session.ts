/// The client-side session: what the server said (hello, ticks) and what the user looks at
/// (selected robot, option, time cursor), with change notification for the panels.
///
/// Frames are decoded as they arrive (cheap) and kept in a `TickBuffer`; panels never render
/// on a message. `main.ts` runs one `requestAnimationFrame` loop that asks each panel to draw
/// the tick in view (the newest one, or the one under the timeline cursor) only when something
/// it shows changed, so a burst of frames costs one draw.
import { type DescriptionIndex, indexDescription } from "./description";
import { TickBuffer } from "./history";
import type { ReplayInfo } from "./replay";
import { type Frame, FrameDecoder, type Hello, type RobotInfo, type RobotState, type StaticScene, type Tick } from "./protocol";

export type SessionEvent = "hello" | "tick" | "select" | "cursor" | "option" | "history";

/// The last state change of one option of one robot (for "the transition that fired").
export interface LastTransition {
  from: number;
  to: number;
  leaf: number;
  t: number;
}

export class Session {
  hello: Hello | null = null;
  programs = new Map<string, DescriptionIndex>();
  robots: RobotInfo[] = [];
  scene: StaticScene | null = null;
  readonly buffer = new TickBuffer(60_000);
  live: Tick | null = null;
  /// A replay (`xabsl serve --replay`): the recording's extent; null in a live session.
  replay: ReplayInfo | null = null;
  /// Behavior time shown by every panel, or null for live.
  cursor: number | null = null;
  selectedRobot = 0;
  /// Option opened in the option view (by id, in the selected robot's program).
  openOption: number | null = null;
  /// Per robot and option id: the last state change seen.
  readonly transitions = new Map<number, Map<number, LastTransition>>();
  private readonly decoder = new FrameDecoder();
  private readonly listeners = new Map<SessionEvent, Set<() => void>>();
  /// Events raised since the last `takeChanges` (the render loop reads and clears them).
  private changes = new Set<SessionEvent>();

  on(event: SessionEvent, fn: () => void): () => void {
    let set = this.listeners.get(event);
    if (!set) this.listeners.set(event, (set = new Set()));
    set.add(fn);
    return () => set?.delete(fn);
  }

  private emit(event: SessionEvent): void {
    this.changes.add(event);
    for (const fn of this.listeners.get(event) ?? []) fn();
  }

  /// The events since the last call (for the render loop).
  takeChanges(): Set<SessionEvent> {
    const c = this.changes;
    this.changes = new Set();
    return c;
  }

  // ---------------------------------------------------------------------------- server side

  applyHello(hello: Hello): void {
    this.hello = hello;
    this.programs = new Map(Object.entries(hello.structure.programs).map(([k, d]) => [k, indexDescription(d)]));
    this.robots = hello.structure.robots;
    this.scene = hello.scene;
    this.decoder.reset();
    // Ids may have changed (reload, reset): ticks of the old generation cannot be read any more.
    this.buffer.clear();
    this.live = null;
    this.cursor = null;
    this.transitions.clear();
    if (!this.robots.some((r) => r.id === this.selectedRobot)) {
      this.selectedRobot = this.robots.find((r) => r.program !== null)?.id ?? this.robots[0]?.id ?? 0;
    }
    const index = this.indexOf(this.selectedRobot);
    if (this.openOption !== null && !index?.optionById.has(this.openOption)) this.openOption = null;
    this.emit("hello");
  }

  applyFrame(frame: Frame): Tick {
    const tick = this.decoder.decode(frame);
    this.noteTransitions(tick);
    this.buffer.push(tick);
    this.live = tick;
    this.emit("tick");
    return tick;
  }

  /// Merge frames of a `history` answer (their own delta stream) into the buffer.
  applyHistory(frames: readonly Frame[]): void {
    const decoder = new FrameDecoder();
    const gen = this.hello?.generation;
    const ticks = frames.filter((f) => f.gen === gen).map((f) => decoder.decode(f));
    this.buffer.merge(ticks);
    this.emit("history");
  }

  private noteTransitions(tick: Tick): void {
    for (const robot of tick.robots) {
      let perOption = this.transitions.get(robot.id);
      for (const node of robot.path) {
        if (node.kind !== "option" || node.leaf < 0 || node.decidedIn === node.state) continue;
        if (!perOption) this.transitions.set(robot.id, (perOption = new Map()));
        perOption.set(node.option, { from: node.decidedIn, to: node.state, leaf: node.leaf, t: tick.t });
      }
    }
  }

  // ------------------------------------------------------------------------------ user side

  /// The tick every panel shows: the one under the cursor, or the newest.
  get view(): Tick | null {
    if (this.cursor === null) return this.live;
    return this.buffer.at(this.cursor) ?? this.live;
  }

  get isLive(): boolean {
    return this.cursor === null;
  }

  setCursor(t: number | null): void {
    const oldest = this.buffer.oldest;
    const newest = this.buffer.newest;
    if (t !== null && newest && oldest) t = Math.max(oldest.t, Math.min(newest.t, t));
    // In a replay the newest tick is the recording's last one, not "live".
    if (t !== null && newest && t >= newest.t && !this.replay) t = null;
    if (t === this.cursor) return;
    this.cursor = t;
    this.emit("cursor");
  }

  /// Move the cursor by `n` buffered ticks (from live: back from the newest).
  stepCursor(n: number): void {
    const ticks = this.buffer.all;
    if (!ticks.length) return;
    const current = this.cursor === null ? ticks.length - 1 : this.buffer.indexAt(this.cursor);
    const next = Math.max(0, Math.min(ticks.length - 1, current + n));
    this.setCursor(next === ticks.length - 1 && n > 0 ? null : (ticks[next] as Tick).t);
  }

  selectRobot(id: number): void {
    if (id === this.selectedRobot || !this.robots.some((r) => r.id === id)) return;
    const before = this.programOf(this.selectedRobot);
    this.selectedRobot = id;
    if (this.programOf(id) !== before) this.openOption = null;
    this.emit("select");
  }

  openOptionById(id: number | null): void {
    this.openOption = id;
    this.emit("option");
  }

  robotInfo(id: number): RobotInfo | undefined {
    return this.robots.find((r) => r.id === id);
  }

  /// The behavior set the engine of a robot runs (null: no XABSL engine).
  programOf(robotId: number): string | null {
    return this.robotInfo(robotId)?.program ?? null;
  }

  indexOf(robotId: number): DescriptionIndex | null {
    const program = this.programOf(robotId);
    return program ? (this.programs.get(program) ?? null) : null;
  }

  /// The selected robot in the tick in view.
  robotInView(): RobotState | null {
    return this.view?.robots.find((r) => r.id === this.selectedRobot) ?? null;
  }
}
