/// The studio protocol, version 1 (docs/protocol.md): the web UI's side of server/protocol/ (commands, replies).
///
/// The wire types are generated from the server's message definitions (`messages.gen.ts`, by
/// `python -m xabsl_studio.server.protocol.tsgen --write`); this module re-exports them, narrows the parts the server
/// leaves to the world or to the program JSON (scenes, status, programs), and owns the decoding a
/// client must do: activation paths from their compact arrays (`decodePath`), and symbol values
/// from full frames and deltas (`applyValues`).
import type { BehaviorDescription } from "./description";
import type * as wire from "./messages.gen";

export { PROTOCOL_VERSION } from "./messages.gen";
export type {
  ClientMessage,
  Command,
  CommandResults,
  CompileEvent,
  CrashEvent,
  Explanation,
  Fault,
  FileEvent,
  HelloReason,
  Reply,
  RobotFrame,
  RobotInfo,
  ServerEvent,
  SessionInfo,
  Subscribe,
  Resync,
} from "./messages.gen";
export type { OptionNode as WireOptionNode, BehaviorNode as WireBehaviorNode, PathNode as WirePathNode } from "./messages.gen";

/// Websocket close codes (server/protocol/limits.py `CloseCode`).
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

/// The `op` of a command, and the arguments each op takes (without `type`, `id`, `op`).
export type CommandOp = wire.Command["op"];
export type CommandArgs<Op extends CommandOp> = Omit<Extract<wire.Command, { op: Op }>, "type" | "id" | "op">;

/// The ids of a generation, with each behavior set's program JSON typed.
export interface Structure extends Omit<wire.Structure, "programs"> {
  programs: Record<string, BehaviorDescription>;
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

/// The world's status (`world.status()`).
export interface WorldStatus {
  time_ms?: number;
  game_state?: string;
  score?: number[];
  teams?: string[];
  half?: number;
  half_time_left_ms?: number;
  finished?: boolean;
  [key: string]: unknown;
}

export interface Hello extends Omit<wire.Hello, "structure" | "scene"> {
  structure: Structure;
  scene: StaticScene;
}

export interface Frame extends Omit<wire.Frame, "scene" | "status"> {
  scene?: DynamicScene;
  status?: WorldStatus | null;
}

export interface HistoryChunk extends Omit<wire.HistoryChunk, "frames"> {
  frames: Frame[];
}

export type ServerMessage = Hello | Frame | wire.Reply | HistoryChunk | wire.ServerEvent;

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
  params: wire.WireValue[];
}

/// A basic behavior node of a decoded activation path.
export interface BehaviorNode {
  kind: "behavior";
  depth: number;
  behavior: number;
  time: number;
  params: wire.WireValue[];
}

export type PathNode = OptionNode | BehaviorNode;

/// Decode a wire activation path (pre-order, depth 0 = a root).
///
/// Malformed nodes are dropped rather than thrown on: a frame must never take the UI down.
export function decodePath(nodes: readonly wire.PathNode[] | undefined): PathNode[] {
  const out: PathNode[] = [];
  if (!nodes) return out;
  for (const n of nodes) {
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
export type Values = Array<wire.WireValue | undefined>;

/// Apply a frame's `{id: value}` map to `previous` (a full frame replaces, a delta patches).
///
/// Returns `previous` itself when nothing changed, else a new array: frames kept in the history
/// share unchanged arrays, so buffering many frames stays cheap.
export function applyValues(previous: Values, values: Record<string, wire.WireValue> | null | undefined, full: boolean): Values {
  if (full) {
    const next: Values = [];
    if (values) for (const key in values) next[Number(key)] = values[key];
    return next;
  }
  if (!values) return previous;
  let next: Values | null = null;
  for (const key in values) {
    const id = Number(key);
    const value = values[key];
    if (previous[id] === value) continue;
    if (!next) next = previous.slice();
    next[id] = value;
  }
  return next ?? previous;
}

/// One robot at one tick, decoded, with all symbol values known at that tick.
export interface RobotState {
  id: number;
  path: PathNode[];
  shape: string;
  inputs: Values;
  outputs: Values;
  fault: wire.Fault | null;
  forced: [0 | 1, number] | null;
  overrides: Record<string, wire.WireValue> | null;
}

/// One tick, decoded: what every panel renders.
export interface Tick {
  seq: number;
  gen: number;
  t: number;
  /// Timeline time (ms): `t` plus its generation's offset, so it goes on across resets (the
  /// world's clock restarts, the timeline does not); the session sets it, the decoder copies `t`.
  x: number;
  wall: number;
  robots: RobotState[];
  scene: DynamicScene | null;
  status: WorldStatus | null;
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
    const prevRobots = new Map<number, RobotState>();
    if (prev && !frame.full) for (const r of prev.robots) prevRobots.set(r.id, r);
    const robots: RobotState[] = frame.robots.map((r) => {
      const before = prevRobots.get(r.id);
      const path = decodePath(r.path);
      return {
        id: r.id,
        path,
        shape: pathShape(path),
        inputs: applyValues(before?.inputs ?? [], r.inputs, frame.full || !before),
        outputs: applyValues(before?.outputs ?? [], r.outputs, frame.full || !before),
        fault: r.fault ?? null,
        forced: r.forced ?? null,
        overrides: r.overrides ?? null,
      };
    });
    const tick: Tick = {
      seq: frame.seq,
      gen: frame.gen,
      t: frame.t,
      x: frame.t,
      wall: frame.wall,
      robots,
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
