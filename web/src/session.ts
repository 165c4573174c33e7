/// The client-side session: what the server said (hello, ticks) and what the user looks at
/// (selected robot, option, time cursor), with change notification for the panels.
///
/// Frames are decoded as they arrive (cheap) and kept in a `TickBuffer`; panels never render
/// on a message. `main.ts` runs one `requestAnimationFrame` loop that asks each panel to draw
/// the tick in view (the newest one, or the one under the timeline cursor) only when something
/// it shows changed, so a burst of frames costs one draw.
///
/// Reloads and resets start a new generation of ids; the buffer keeps the ticks of earlier ones
/// (the server's `history` serves them with their descriptions), and every tick is read with
/// the description of its own generation: `programs`, `robots` and `scene` are those of the
/// generation of the tick in view (a "hello" change is raised when the view crosses into another).
import { type BehaviorDescription, type DescriptionIndex, indexDescription, unpackDescription } from "./description";
import { TickBuffer } from "./history";
import type { GenerationInfo } from "./messages.gen";
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

/// One generation of ids (from a hello, or a `history` answer for earlier ones): what reads its ticks.
export interface GenerationView {
  number: number;
  /// Why it started (the NewGeneration reason: "connect", "reload", "reset", later "fork", ...).
  reason: string;
  /// Timeline ms added to its ticks' `t` (`Tick.x`).
  offset: number;
  programs: Map<string, DescriptionIndex>;
  robots: RobotInfo[];
  scene: StaticScene | null;
  /// Behavior files whose text changed since the previous generation (null: not known yet).
  changedFiles: string[] | null;
}

const NO_PROGRAMS = new Map<string, DescriptionIndex>();

export class Session {
  hello: Hello | null = null;
  /// Every generation with ticks in the buffer (and the current one), by number.
  readonly generations = new Map<number, GenerationView>();
  /// The generation of the tick in view (the current one when live).
  private shown: GenerationView | null = null;
  readonly buffer = new TickBuffer(120_000);
  live: Tick | null = null;
  /// A replay (`xabsl serve --replay`): the recording's extent; null in a live session.
  replay: ReplayInfo | null = null;
  /// Timeline time (`Tick.x`, ms) shown by every panel, or null for live.
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

  /// The behavior sets of the generation in view, by key.
  get programs(): Map<string, DescriptionIndex> {
    return this.shown?.programs ?? NO_PROGRAMS;
  }

  /// The robots of the generation in view.
  get robots(): RobotInfo[] {
    return this.shown?.robots ?? [];
  }

  /// The static scene of the generation in view.
  get scene(): StaticScene | null {
    return this.shown?.scene ?? null;
  }

  /// The generation of the tick in view.
  get shownGeneration(): GenerationView | null {
    return this.shown;
  }

  /// The description index of a robot's behavior set in generation `gen` (null: unknown).
  indexIn(gen: number, robotId: number): DescriptionIndex | null {
    const view = this.generations.get(gen);
    const program = view?.robots.find((r) => r.id === robotId)?.program;
    return program ? (view?.programs.get(program) ?? null) : null;
  }

  /// Ids of the tick in view's generation as ids of the current one (by name; -1: it has none),
  /// for what only the current generation has (the option graph the server draws).
  currentIds(robotId: number): { option: (id: number) => number; behavior: (id: number) => number } {
    const gen = this.view?.gen;
    const current = this.hello?.generation;
    if (gen === undefined || current === undefined || gen === current) return { option: (id) => id, behavior: (id) => id };
    const then = this.indexIn(gen, robotId);
    const now = this.indexIn(current, robotId);
    return {
      option: (id) => now?.optionByName.get(then?.optionById.get(id)?.name ?? "")?.id ?? -1,
      behavior: (id) => now?.behaviorByName.get(then?.behaviorById.get(id)?.name ?? "")?.id ?? -1,
    };
  }

  applyHello(hello: Hello): void {
    const fresh = hello.reason === "connect";
    if (fresh) {
      // A (re)connect: maybe another server; the history that follows brings what it buffered.
      this.buffer.clear();
      this.generations.clear();
      this.cursor = null;
    }
    this.hello = hello;
    const known = this.generations.get(hello.generation);
    this.generations.set(hello.generation, {
      ...generationView(hello.generation, hello.structure.robots, hello.structure.programs, hello.scene),
      reason: hello.reason === "connect" || hello.reason === "resync" ? (known?.reason ?? hello.reason) : hello.reason,
      offset: hello.session.offset ?? 0,
      changedFiles: known?.changedFiles ?? null,
    });
    this.forgetGenerations();
    this.decoder.reset();
    this.live = null;
    this.transitions.clear();
    this.refreshShown(false);
    if (!this.robots.some((r) => r.id === this.selectedRobot)) {
      this.selectedRobot = this.robots.find((r) => r.program !== null)?.id ?? this.robots[0]?.id ?? 0;
    }
    const index = this.indexOf(this.selectedRobot);
    if (this.openOption !== null && !index?.optionById.has(this.openOption)) this.openOption = null;
    this.emit("hello");
  }

  applyFrame(frame: Frame): Tick {
    const tick = this.decoder.decode(frame);
    tick.x = tick.t + (this.generations.get(tick.gen)?.offset ?? 0);
    this.noteTransitions(tick);
    this.buffer.push(tick);
    this.live = tick;
    if (this.cursor === null && this.shown?.number !== tick.gen) this.refreshShown(true);
    this.emit("tick");
    return tick;
  }

  /// Merge frames of a `history` answer (their own delta stream, a full frame first for each
  /// generation) into the buffer; `generations` (of the answer) describe the earlier generations.
  applyHistory(frames: readonly Frame[], generations: readonly GenerationInfo[] = []): void {
    for (const g of generations) {
      const known = this.generations.get(g.number);
      if (known) {
        known.reason = g.reason;
        known.offset = g.offset;
        known.changedFiles = g.changed_files;
      } else if (g.structure) {
        this.generations.set(g.number, {
          ...generationView(g.number, g.structure.robots, g.structure.programs as unknown as Record<string, BehaviorDescription>, (g.scene ?? null) as StaticScene | null),
          reason: g.reason,
          offset: g.offset,
          changedFiles: g.changed_files,
        });
      }
    }
    const decoder = new FrameDecoder();
    const ticks = frames
      .filter((f) => this.generations.has(f.gen))
      .map((f) => {
        const tick = decoder.decode(f);
        tick.x = tick.t + (this.generations.get(tick.gen)?.offset ?? 0);
        return tick;
      });
    this.buffer.merge(ticks);
    this.forgetGenerations();
    this.refreshShown(true);
    this.emit("history");
  }

  /// Drop the generations no buffered tick belongs to any more (but the current one).
  private forgetGenerations(): void {
    const used = new Set(this.buffer.all.map((t) => t.gen));
    for (const n of this.generations.keys()) if (n !== this.hello?.generation && !used.has(n)) this.generations.delete(n);
  }

  /// Follow the generation of the tick in view; `announce`: raise "hello" when it changed.
  private refreshShown(announce: boolean): void {
    const gen = this.view?.gen ?? this.hello?.generation;
    const next = (gen !== undefined ? this.generations.get(gen) : undefined) ?? (this.hello ? this.generations.get(this.hello.generation) : undefined) ?? null;
    if (next === this.shown) return;
    const before = this.shown;
    this.shown = next;
    // The option open in the option view: the same option (by name) in the generation now shown.
    if (before && next && this.openOption !== null) {
      const name = this.indexIn(before.number, this.selectedRobot)?.optionById.get(this.openOption)?.name;
      const index = this.indexIn(next.number, this.selectedRobot);
      const id = name === undefined ? undefined : index?.optionByName.get(name)?.id;
      this.openOption = id ?? null;
    }
    if (announce) this.emit("hello");
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

  /// The tick every panel shows: the one under the cursor (timeline time), or the newest.
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
    if (t !== null && newest && oldest) t = Math.max(oldest.x, Math.min(newest.x, t));
    // In a replay the newest tick is the recording's last one, not "live".
    if (t !== null && newest && t >= newest.x && !this.replay) t = null;
    if (t === this.cursor) return;
    this.cursor = t;
    this.refreshShown(true);
    this.emit("cursor");
  }

  /// Show the tick at behavior time `t` of the current generation, or the tick `seq` when it is
  /// buffered (a time from the server, e.g. a breakpoint hit, to the timeline time of its tick).
  seekTick(t: number, seq?: number): void {
    const tick = seq === undefined ? null : this.buffer.bySeq(seq);
    const offset = this.hello ? (this.generations.get(this.hello.generation)?.offset ?? 0) : 0;
    this.setCursor(tick ? tick.x : t + offset);
  }

  /// Move the cursor by `n` buffered ticks (from live: back from the newest).
  stepCursor(n: number): void {
    const ticks = this.buffer.all;
    if (!ticks.length) return;
    const current = this.cursor === null ? ticks.length - 1 : this.buffer.indexAt(this.cursor);
    const next = Math.max(0, Math.min(ticks.length - 1, current + n));
    this.setCursor(next === ticks.length - 1 && n > 0 ? null : (ticks[next] as Tick).x);
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

function generationView(number: number, robots: RobotInfo[], programs: Record<string, BehaviorDescription>, scene: StaticScene | null): GenerationView {
  return {
    number,
    reason: "connect",
    offset: 0,
    programs: new Map(Object.entries(programs).map(([k, d]) => [k, indexDescription(unpackDescription(d))])),
    robots,
    scene,
    changedFiles: null,
  };
}
