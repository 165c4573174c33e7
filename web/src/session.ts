/// The client-side session: what the server said (hello, ticks) and what the user looks at
/// (selected agent, option, time cursor), with change notification for the panels.
///
/// Frames are decoded as they arrive (cheap) and kept in a `TickBuffer`; panels never render
/// on a message. `main.ts` runs one `requestAnimationFrame` loop that asks each panel to draw
/// the tick in view (the newest one, or the one under the timeline cursor) only when something
/// it shows changed, so a burst of frames costs one draw.
import { type DescriptionIndex, indexDescription } from "./description";
import { TickBuffer } from "./history";
import {
  type AgentInfo,
  type AgentState,
  type Frame,
  FrameDecoder,
  type Hello,
  type StaticScene,
  type Tick,
} from "./protocol";

export type SessionEvent = "hello" | "tick" | "select" | "cursor" | "option" | "history";

/// The last state change of one option of one agent (for "the transition that fired").
export interface LastTransition {
  from: number;
  to: number;
  leaf: number;
  t: number;
}

export class Session {
  hello: Hello | null = null;
  programs = new Map<string, DescriptionIndex>();
  agents: AgentInfo[] = [];
  scene: StaticScene | null = null;
  readonly buffer = new TickBuffer(60_000);
  live: Tick | null = null;
  /// Behavior time shown by every panel, or null for live.
  cursor: number | null = null;
  selectedAgent = 0;
  /// Option opened in the option view (by id, in the selected agent's program).
  openOption: number | null = null;
  /// Per agent and option id: the last state change seen.
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
    this.agents = hello.structure.agents;
    this.scene = hello.scene;
    this.decoder.reset();
    // Ids may have changed (reload, reset): ticks of the old generation cannot be read any more.
    this.buffer.clear();
    this.live = null;
    this.cursor = null;
    this.transitions.clear();
    if (!this.agents.some((a) => a.id === this.selectedAgent)) {
      this.selectedAgent = this.agents.find((a) => a.program !== null)?.id ?? this.agents[0]?.id ?? 0;
    }
    const index = this.indexOf(this.selectedAgent);
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
    for (const agent of tick.agents) {
      let perOption = this.transitions.get(agent.id);
      for (const node of agent.path) {
        if (node.kind !== "option" || node.leaf < 0 || node.decidedIn === node.state) continue;
        if (!perOption) this.transitions.set(agent.id, (perOption = new Map()));
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
    if (t !== null && newest && t >= newest.t) t = null;
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

  selectAgent(id: number): void {
    if (id === this.selectedAgent || !this.agents.some((a) => a.id === id)) return;
    const before = this.programOf(this.selectedAgent);
    this.selectedAgent = id;
    if (this.programOf(id) !== before) this.openOption = null;
    this.emit("select");
  }

  openOptionById(id: number | null): void {
    this.openOption = id;
    this.emit("option");
  }

  agentInfo(id: number): AgentInfo | undefined {
    return this.agents.find((a) => a.id === id);
  }

  programOf(agentId: number): string | null {
    return this.agentInfo(agentId)?.program ?? null;
  }

  indexOf(agentId: number): DescriptionIndex | null {
    const program = this.programOf(agentId);
    return program ? (this.programs.get(program) ?? null) : null;
  }

  /// The selected agent in the tick in view.
  agentInView(): AgentState | null {
    return this.view?.agents.find((a) => a.id === this.selectedAgent) ?? null;
  }
}
