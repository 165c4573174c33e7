/// The studio protocol, version 1: the web UI's mirror of server/protocol.py and docs/protocol.md.
///
/// Message and field names are exactly the server's. Besides the wire types this module owns the
/// decoding a client must do: activation paths from their compact arrays
/// (`decodePath`), and symbol values from full frames and deltas (`applyValues`).
import type { BehaviorDescription } from "./description";

export const PROTOCOL_VERSION = 1;

/// Websocket close codes (server/protocol.py `CloseCode`).
export const CloseCode = {
  NORMAL: 1000,
  GOING_AWAY: 1001,
  UNSUPPORTED_DATA: 1003,
  POLICY_VIOLATION: 1008,
  MESSAGE_TOO_BIG: 1009,
  INTERNAL_ERROR: 1011,
  TRY_AGAIN_LATER: 1013,
} as const;

/// Largest client message the server accepts (bytes).
export const MAX_CLIENT_MESSAGE = 64 * 1024;

/// A symbol value on the wire: decimals, booleans, enum element indices (-1: no element).
export type Value = number | boolean;

export type HelloReason = "connect" | "reload" | "reset" | "resync";

export interface SessionInfo {
  example: string;
  paused: boolean;
  speed: number;
  seed: number;
  behavior_hz: number;
  seq: number;
  t: number;
  token_required: boolean;
  [key: string]: unknown;
}

export interface AgentInfo {
  id: number;
  name: string;
  team: string;
  number: number;
  program: string | null;
}

export interface Structure {
  programs: Record<string, BehaviorDescription>;
  agents: AgentInfo[];
}

/// The world's static scene (soccer: examples/soccer/field.py `static_scene` + world.py).
export interface StaticScene {
  kind: string;
  units?: Record<string, string>;
  /// Soccer: `{length, width, border, line_width}`; simpler worlds: `{x: [lo, hi], y: [lo, hi]}`.
  field?: { length?: number; width?: number; border?: number; line_width?: number; x?: number[]; y?: number[] };
  lines?: number[][];
  circles?: number[][];
  marks?: number[][];
  goals?: Array<{ side: number; posts: number[][]; net: number[][] }>;
  walls?: number[][];
  teams?: Array<{ name: string; color: string }>;
  agents?: Array<{ name: string; team: string; number: number }>;
  robot_radius?: number;
  ball_radius?: number;
  [key: string]: unknown;
}

/// The world's dynamic scene (soccer: `dynamic_scene`): poses in mm, headings in degrees.
export interface DynamicScene {
  t: number;
  ball?: [number, number];
  robots?: Array<[number, number, number]>;
  state?: number;
  score?: [number, number];
  [key: string]: unknown;
}

export interface Status {
  time_ms?: number;
  game_state?: string;
  score?: number[];
  teams?: string[];
  half?: number;
  half_time_left_ms?: number;
  finished?: boolean;
  [key: string]: unknown;
}

export interface Hello {
  type: "hello";
  version: number;
  reason: HelloReason;
  generation: number;
  session: SessionInfo;
  structure: Structure;
  scene: StaticScene;
}

/// An option node on the wire:
/// `[0, depth, option_id, state_id, option_time, state_time, decided_in_state_id, leaf_id, [params]]`.
export type WireOptionNode = [0, number, number, number, number, number, number, number, Value[]];
/// A basic behavior node on the wire: `[1, depth, behavior_id, time_of_execution, [params]]`.
export type WireBehaviorNode = [1, number, number, number, Value[]];
export type WirePathNode = WireOptionNode | WireBehaviorNode;

export interface Fault {
  message: string;
  option: string | null;
  state: string | null;
}

export interface WireAgentFrame {
  id: number;
  path: WirePathNode[];
  outputs?: Record<string, Value>;
  inputs?: Record<string, Value>;
  fault?: Fault;
  forced?: [0 | 1, number];
  overrides?: Record<string, Value>;
}

export interface Frame {
  type: "frame";
  seq: number;
  gen: number;
  t: number;
  wall: number;
  full: boolean;
  agents: WireAgentFrame[];
  scene?: DynamicScene;
  status?: Status;
}

export interface Reply {
  type: "reply";
  id: number | string | null;
  ok: boolean;
  result?: unknown;
  error?: string;
}

export interface HistoryChunk {
  type: "history";
  id: number | string;
  chunk: number;
  last: boolean;
  frames: Frame[];
}

export interface FileEvent {
  type: "event";
  event: "file";
  path: string;
  version: string | null;
  deleted: boolean;
}

export interface CompileEvent {
  type: "event";
  event: "compile";
  program: string;
  ok: boolean;
  diagnostics: unknown[];
}

/// The simulation process stopped (the world raised or the process died); `reset` restarts it.
export interface CrashEvent {
  type: "event";
  event: "crash";
  message: string;
  seq: number;
  t: number;
}

export type ServerEvent = FileEvent | CompileEvent | CrashEvent;

export type ServerMessage = Hello | Frame | Reply | HistoryChunk | ServerEvent;

/// Commands (`{"type": "command", "id", "op", ...arguments}`), by op.
export type CommandOp =
  | "pause"
  | "resume"
  | "step"
  | "speed"
  | "reset"
  | "select_agent"
  | "force_option"
  | "force_behavior"
  | "release"
  | "override_input"
  | "release_input"
  | "reset_agent"
  | "reload"
  | "explain"
  | "history"
  | "status"
  | "world_command";

export interface Subscribe {
  type: "subscribe";
  rate?: number;
  agents?: number[] | null;
  id?: number | string;
}

export interface Resync {
  type: "resync";
}

export interface Command {
  type: "command";
  id: number | string;
  op: CommandOp;
  [argument: string]: unknown;
}

export type ClientMessage = Subscribe | Resync | Command;

/// The `explain` result.
export interface Explanation {
  option: number;
  option_name: string;
  decided_in: number;
  decided_in_name: string;
  leaf: number;
  target: number;
  target_name: string;
  stay: boolean;
  conditions: Array<{
    text: string;
    source: string;
    value: Value | string | null;
    branch: boolean;
    span: import("./description").Span | null;
  }>;
}

// ------------------------------------------------------------------------------- decoding

/// An option node of a decoded activation path.
export interface OptionNode {
  kind: "option";
  depth: number;
  option: number;
  state: number;
  optionTime: number;
  stateTime: number;
  decidedIn: number;
  leaf: number;
  params: Value[];
}

/// A basic behavior node of a decoded activation path.
export interface BehaviorNode {
  kind: "behavior";
  depth: number;
  behavior: number;
  time: number;
  params: Value[];
}

export type PathNode = OptionNode | BehaviorNode;

/// Decode a wire activation path (pre-order, depth 0 = a root).
///
/// Malformed nodes are dropped rather than thrown on: a frame must never take the UI down.
export function decodePath(wire: readonly WirePathNode[] | undefined): PathNode[] {
  const out: PathNode[] = [];
  if (!wire) return out;
  for (const n of wire) {
    if (!Array.isArray(n)) continue;
    if (n[0] === 0 && n.length >= 8) {
      out.push({
        kind: "option",
        depth: n[1],
        option: n[2],
        state: n[3],
        optionTime: n[4],
        stateTime: n[5],
        decidedIn: n[6],
        leaf: n[7],
        params: Array.isArray(n[8]) ? n[8] : [],
      });
    } else if (n[0] === 1 && n.length >= 4) {
      out.push({ kind: "behavior", depth: n[1], behavior: n[2], time: n[3], params: Array.isArray(n[4]) ? n[4] : [] });
    }
  }
  return out;
}

/// The key of a path's shape (which options/states/behaviors, not times or values): equal keys
/// mean panels can update texts in place instead of rebuilding rows.
export function pathShape(path: readonly PathNode[]): string {
  let key = "";
  for (const n of path) key += n.kind === "option" ? `o${n.depth}.${n.option}.${n.state};` : `b${n.depth}.${n.behavior};`;
  return key;
}

/// The parent index of every node of a pre-order path (-1 for roots).
export function pathParents(path: readonly PathNode[]): number[] {
  const parents: number[] = [];
  const stack: number[] = [];
  path.forEach((n, i) => {
    while (stack.length > n.depth) stack.pop();
    parents.push(stack.length ? (stack[stack.length - 1] as number) : -1);
    stack.push(i);
  });
  return parents;
}

/// Symbol values of one agent, indexed by symbol id (`undefined`: not received yet).
export type Values = Array<Value | undefined>;

/// Apply a frame's `{id: value}` map to `previous` (a full frame replaces, a delta patches).
///
/// Returns `previous` itself when nothing changed, else a new array: frames kept in the history
/// share unchanged arrays, so buffering many frames stays cheap.
export function applyValues(previous: Values, wire: Record<string, Value> | undefined, full: boolean): Values {
  if (full) {
    const next: Values = [];
    if (wire) for (const key in wire) next[Number(key)] = wire[key];
    return next;
  }
  if (!wire) return previous;
  let next: Values | null = null;
  for (const key in wire) {
    const id = Number(key);
    const value = wire[key];
    if (previous[id] === value) continue;
    if (!next) next = previous.slice();
    next[id] = value;
  }
  return next ?? previous;
}

/// One agent at one tick, decoded, with all symbol values known at that tick.
export interface AgentState {
  id: number;
  path: PathNode[];
  shape: string;
  inputs: Values;
  outputs: Values;
  fault: Fault | null;
  forced: [0 | 1, number] | null;
  overrides: Record<string, Value> | null;
}

/// One tick, decoded: what every panel renders.
export interface Tick {
  seq: number;
  gen: number;
  t: number;
  wall: number;
  agents: AgentState[];
  scene: DynamicScene | null;
  status: Status | null;
}

/// Turns a stream of frames (live, or one history stream) into `Tick`s, applying deltas against
/// the previous frame of the same stream.
export class FrameDecoder {
  private last: Tick | null = null;

  /// Forget the previous frame (after a hello: the next frame is full).
  reset(): void {
    this.last = null;
  }

  get previous(): Tick | null {
    return this.last;
  }

  decode(frame: Frame): Tick {
    const prev = this.last;
    const prevAgents = new Map<number, AgentState>();
    if (prev && !frame.full) for (const a of prev.agents) prevAgents.set(a.id, a);
    const agents: AgentState[] = frame.agents.map((wire) => {
      const before = prevAgents.get(wire.id);
      const path = decodePath(wire.path);
      return {
        id: wire.id,
        path,
        shape: pathShape(path),
        inputs: applyValues(before?.inputs ?? [], wire.inputs, frame.full || !before),
        outputs: applyValues(before?.outputs ?? [], wire.outputs, frame.full || !before),
        fault: wire.fault ?? null,
        forced: wire.forced ?? null,
        overrides: wire.overrides ?? null,
      };
    });
    const tick: Tick = {
      seq: frame.seq,
      gen: frame.gen,
      t: frame.t,
      wall: frame.wall,
      agents,
      scene: frame.scene ?? prev?.scene ?? null,
      status: frame.status ?? (frame.full ? null : (prev?.status ?? null)),
    };
    this.last = tick;
    return tick;
  }
}

/// Parse one websocket text message; `null` for anything that is not a known server message.
export function parseServerMessage(text: string): ServerMessage | null {
  let data: unknown;
  try {
    data = JSON.parse(text);
  } catch {
    return null;
  }
  if (typeof data !== "object" || data === null) return null;
  const type = (data as { type?: unknown }).type;
  if (type === "hello" || type === "frame" || type === "reply" || type === "history" || type === "event") {
    return data as ServerMessage;
  }
  return null;
}
