/// The live link to `xabsl serve`: one websocket, reconnected with backoff, commands with replies.
///
/// States: `connecting` (socket opening, or open and waiting for the first hello), `live`
/// (hello received, frames flowing), `waiting` (closed, a reconnect is scheduled). Every hello
/// resets the backoff. A frame whose `gen` is not the last hello's means a hello was lost: the
/// connection asks for a `resync` once per generation. Commands pending when the socket closes
/// fail at once (the caller shows the error); nothing is retried behind the user's back.
import { Backoff } from "./backoff";
import type { GenerationInfo } from "./messages.gen";
import {
  type ClientMessage,
  type CommandArgs,
  type CommandOp,
  type CommandResults,
  type Frame,
  type Hello,
  type HistoryChunk,
  PROTOCOL_VERSION,
  parseServerMessage,
  type Reply,
  type ServerEvent,
  type ServerMessage,
  type Structure,
} from "./protocol";

/// A hello's compressed structure (base64 of zlib data: server/protocol/packing.py) as JSON.
export async function inflateStructure(packed: string): Promise<Structure> {
  const bytes = Uint8Array.from(atob(packed), (c) => c.charCodeAt(0));
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
  return JSON.parse(await new Response(stream).text()) as Structure;
}

export type LinkState = "connecting" | "live" | "waiting";

/// What the connection needs from a WebSocket (the browser's, or a fake in tests).
export interface SocketLike {
  readyState: number;
  onopen: ((ev: unknown) => void) | null;
  onclose: ((ev: { code: number; reason: string }) => void) | null;
  onerror: ((ev: unknown) => void) | null;
  onmessage: ((ev: { data: unknown }) => void) | null;
  send(data: string): void;
  close(code?: number, reason?: string): void;
}

export interface ConnectionHandlers {
  hello(hello: Hello): void;
  frame(frame: Frame): void;
  event?(event: ServerEvent): void;
  link?(state: LinkState, detail: { retryInMs?: number; code?: number; attempt: number }): void;
}

export class CommandError extends Error {}

interface Pending {
  resolve(value: unknown): void;
  reject(error: Error): void;
  timer: ReturnType<typeof setTimeout>;
}

interface HistoryCollector {
  frames: Frame[];
  resolve(frames: Frame[]): void;
  reject(error: Error): void;
}

export interface ConnectionOptions {
  url: string;
  rate?: number;
  createSocket?: (url: string) => SocketLike;
  backoff?: Backoff;
  setTimer?: (fn: () => void, ms: number) => unknown;
  clearTimer?: (handle: unknown) => void;
  commandTimeoutMs?: number;
}

const OPEN = 1;

/// Ops whose reply may take long (ms to wait): the first `query` of a name reads it from the whole
/// recording (seconds for a long match on a busy machine; docs/queries.md).
const SLOW_OPS: Partial<Record<string, number>> = { query: 120000 };

export class Connection {
  state: LinkState = "connecting";
  generation = -1;
  /// Frames received in the last second (for the link indicator).
  framesPerSecond = 0;
  lastFrameAt = 0;
  private socket: SocketLike | null = null;
  /// Messages received while a hello's compressed structure inflates (null: none inflating).
  private waiting: string[] | null = null;
  private nextId = 1;
  private pending = new Map<number, Pending>();
  private histories = new Map<number, HistoryCollector>();
  private resyncAskedFor = -1;
  private retryTimer: unknown = null;
  private stopped = false;
  private frameTimes: number[] = [];
  private rate: number;
  private readonly backoff: Backoff;
  private readonly createSocket: (url: string) => SocketLike;
  private readonly setTimer: (fn: () => void, ms: number) => unknown;
  private readonly clearTimer: (handle: unknown) => void;

  constructor(
    private readonly options: ConnectionOptions,
    private readonly handlers: ConnectionHandlers,
  ) {
    this.rate = options.rate ?? 30;
    this.backoff = options.backoff ?? new Backoff();
    this.createSocket = options.createSocket ?? ((url) => new WebSocket(url) as unknown as SocketLike);
    this.setTimer = options.setTimer ?? ((fn, ms) => setTimeout(fn, ms));
    this.clearTimer = options.clearTimer ?? ((h) => clearTimeout(h as ReturnType<typeof setTimeout>));
  }

  /// Open the socket (and keep it open until `stop`).
  start(): void {
    this.stopped = false;
    this.open();
  }

  stop(): void {
    this.stopped = true;
    if (this.retryTimer !== null) this.clearTimer(this.retryTimer);
    this.retryTimer = null;
    this.socket?.close(1000, "client stops");
    this.socket = null;
  }

  /// Close the socket and reconnect now (the "reconnect" button).
  reconnectNow(): void {
    if (this.retryTimer !== null) this.clearTimer(this.retryTimer);
    this.retryTimer = null;
    const old = this.socket;
    this.socket = null;
    if (old) {
      old.onclose = null;
      old.close(1000, "reconnect");
    }
    this.failPending("reconnecting");
    this.open();
  }

  private setState(state: LinkState, detail: { retryInMs?: number; code?: number } = {}): void {
    this.state = state;
    this.handlers.link?.(state, { ...detail, attempt: this.backoff.attempt });
  }

  private open(): void {
    this.setState("connecting");
    let socket: SocketLike;
    try {
      socket = this.createSocket(this.options.url);
    } catch {
      this.scheduleRetry(0);
      return;
    }
    this.socket = socket;
    socket.onopen = () => {
      this.sendRaw({ type: "subscribe", rate: this.rate, robots: null });
    };
    socket.onmessage = (ev) => {
      if (typeof ev.data === "string") this.receive(ev.data);
    };
    socket.onerror = () => {
      /* onclose follows and handles it */
    };
    socket.onclose = (ev) => {
      if (this.socket !== socket) return;
      this.socket = null;
      this.waiting = null; // what waited behind a hello of this socket is of no use now
      this.failPending(`connection closed (${ev.code})`);
      if (!this.stopped) this.scheduleRetry(ev.code);
    };
  }

  private scheduleRetry(code: number): void {
    const delay = this.backoff.next();
    this.setState("waiting", { retryInMs: delay, code });
    this.retryTimer = this.setTimer(() => {
      this.retryTimer = null;
      if (!this.stopped) this.open();
    }, delay);
  }

  private failPending(reason: string): void {
    for (const p of this.pending.values()) {
      this.clearTimer(p.timer);
      p.reject(new CommandError(reason));
    }
    this.pending.clear();
    for (const h of this.histories.values()) h.reject(new CommandError(reason));
    this.histories.clear();
  }

  /// Handle one text message from the server (public for tests).
  ///
  /// A hello with a compressed structure (`structure_z`, a team-sized set) is inflated first;
  /// the messages after it wait, in order, until it is handled.
  receive(text: string): void {
    if (this.waiting !== null) {
      this.waiting.push(text);
      return;
    }
    const message = parseServerMessage(text);
    if (!message) return;
    const compressed = message.type === "hello" ? message.structure_z : null;
    if (message.type === "hello" && compressed) {
      const queue: string[] = (this.waiting = []);
      const socket = this.socket;
      void inflateStructure(compressed).then(
        (structure) => {
          if (this.waiting !== queue || this.socket !== socket) return; // that socket is gone
          this.waiting = null;
          this.handle({ ...message, structure, structure_z: null });
          for (let next = queue.shift(); next !== undefined; next = queue.shift()) this.receive(next);
        },
        (error: unknown) => {
          console.error("a hello's compressed structure does not inflate:", error);
          if (this.waiting === queue) this.waiting = null;
          this.socket?.close(4000, "bad hello");
        },
      );
      return;
    }
    this.handle(message);
  }

  private handle(message: ServerMessage): void {
    switch (message.type) {
      case "hello":
        if (message.version !== PROTOCOL_VERSION) console.warn(`server speaks protocol ${message.version}, UI ${PROTOCOL_VERSION}`);
        this.generation = message.generation;
        this.backoff.succeeded();
        this.setState("live");
        this.handlers.hello(message);
        break;
      case "frame":
        this.countFrame();
        if (message.gen !== this.generation) {
          if (this.resyncAskedFor !== message.gen) {
            this.resyncAskedFor = message.gen;
            this.sendRaw({ type: "resync" });
          }
          return;
        }
        this.handlers.frame(message);
        break;
      case "reply":
        this.reply(message);
        break;
      case "history":
        this.historyChunk(message);
        break;
      case "event":
        this.handlers.event?.(message);
        break;
    }
  }

  private countFrame(): void {
    const now = performance.now();
    this.lastFrameAt = now;
    this.frameTimes.push(now);
    while (this.frameTimes.length && (this.frameTimes[0] as number) < now - 1000) this.frameTimes.shift();
    this.framesPerSecond = this.frameTimes.length;
  }

  private reply(message: Reply): void {
    if (typeof message.id !== "number") {
      if (!message.ok) console.warn("server:", message.error);
      return;
    }
    const pending = this.pending.get(message.id);
    if (!pending) return;
    this.pending.delete(message.id);
    this.clearTimer(pending.timer);
    if (message.ok) pending.resolve(message.result ?? null);
    else pending.reject(new CommandError(message.error ?? "command failed"));
  }

  private historyChunk(message: HistoryChunk): void {
    const collector = typeof message.id === "number" ? this.histories.get(message.id) : undefined;
    if (!collector) return;
    collector.frames.push(...message.frames);
    if (message.last) {
      this.histories.delete(message.id as number);
      collector.resolve(collector.frames);
    }
  }

  private sendRaw(message: ClientMessage): boolean {
    if (!this.socket || this.socket.readyState !== OPEN) return false;
    this.socket.send(JSON.stringify(message));
    return true;
  }

  /// Change the frame rate wanted (frames per second, 1..60).
  subscribe(rate: number): void {
    this.rate = Math.max(1, Math.min(60, Math.round(rate)));
    this.sendRaw({ type: "subscribe", rate: this.rate, robots: null });
  }

  /// Send a command and wait for its reply; rejects with the server's error text.
  ///
  /// `args` are the op's arguments as `server/protocol/commands.py` declares them (generated types).
  command<Op extends CommandOp>(
    op: Op,
    ...rest: {} extends CommandArgs<Op> ? [args?: CommandArgs<Op>] : [args: CommandArgs<Op>]
  ): Promise<CommandResults[Op]> {
    type T = CommandResults[Op];
    const id = this.nextId++;
    const args = rest[0] ?? {};
    return new Promise<T>((resolve, reject) => {
      if (!this.sendRaw({ type: "command", id, op, ...args } as ClientMessage)) {
        reject(new CommandError("not connected"));
        return;
      }
      const timer = setTimeout(() => {
        this.pending.delete(id);
        reject(new CommandError(`no reply to ${op}`));
      }, this.options.commandTimeoutMs ?? SLOW_OPS[op] ?? 10000);
      this.pending.set(id, { resolve: resolve as (v: unknown) => void, reject, timer });
    });
  }

  /// Frames of the server's ring buffer between behavior times t0 and t1 (ms, inclusive).
  async history(t0: number, t1: number, every = 1): Promise<Frame[]> {
    return (await this.historyOf(t0, t1, every)).frames;
  }

  /// `history` with the generations its frames belong to (a live session: timeline times, every
  /// generation still in the ring, the descriptions of the earlier ones).
  async historyOf(t0: number, t1: number, every = 1): Promise<{ frames: Frame[]; generations: GenerationInfo[] }> {
    const id = this.nextId++;
    const frames = new Promise<Frame[]>((resolve, reject) => {
      this.histories.set(id, { frames: [], resolve, reject });
    });
    frames.catch(() => undefined); // awaited below, or abandoned when the reply fails
    const reply = new Promise<CommandResults["history"]>((resolve, reject) => {
      if (!this.sendRaw({ type: "command", id, op: "history", t0, t1, every })) {
        this.histories.delete(id);
        reject(new CommandError("not connected"));
        return;
      }
      const timer = setTimeout(() => {
        this.pending.delete(id);
        reject(new CommandError("no reply to history"));
      }, this.options.commandTimeoutMs ?? 10000);
      this.pending.set(id, { resolve: resolve as (v: unknown) => void, reject, timer });
    });
    let result: CommandResults["history"];
    try {
      result = await reply;
    } catch (error) {
      this.histories.delete(id);
      throw error;
    }
    const generations = result?.generations ?? [];
    if (!result || !result.chunks) {
      this.histories.delete(id);
      return { frames: [], generations };
    }
    return { frames: await frames, generations };
  }
}
