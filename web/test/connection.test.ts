import { describe, expect, it, vi } from "vitest";
import { Backoff } from "../src/backoff";
import { Connection, type SocketLike } from "../src/connection";
import { frame, hello } from "./fake";

class FakeSocket implements SocketLike {
  readyState = 0;
  sent: unknown[] = [];
  onopen: ((ev: unknown) => void) | null = null;
  onclose: ((ev: { code: number; reason: string }) => void) | null = null;
  onerror: ((ev: unknown) => void) | null = null;
  onmessage: ((ev: { data: unknown }) => void) | null = null;
  constructor(readonly url: string) {}
  send(data: string): void {
    this.sent.push(JSON.parse(data));
  }
  close(code = 1000): void {
    this.readyState = 3;
    this.onclose?.({ code, reason: "" });
  }
  open(): void {
    this.readyState = 1;
    this.onopen?.({});
  }
  serve(message: unknown): void {
    this.onmessage?.({ data: JSON.stringify(message) });
  }
  drop(code = 1006): void {
    this.readyState = 3;
    this.onclose?.({ code, reason: "" });
  }
}

function setup() {
  const sockets: FakeSocket[] = [];
  const timers: Array<{ fn: () => void; ms: number }> = [];
  const events = { hellos: 0, frames: [] as number[], links: [] as string[] };
  const connection = new Connection(
    {
      url: "ws://x/ws",
      createSocket: (url) => {
        const s = new FakeSocket(url);
        sockets.push(s);
        return s;
      },
      backoff: new Backoff({ base: 100, max: 800, jitter: 0 }),
      setTimer: (fn, ms) => {
        timers.push({ fn, ms });
        return timers.length;
      },
      clearTimer: () => undefined,
    },
    {
      hello: () => events.hellos++,
      frame: (f) => events.frames.push(f.seq),
      link: (state) => events.links.push(state),
    },
  );
  return { connection, sockets, timers, events };
}

/// What the server sends in `structure_z` (zlib, then base64), made with the platform's own streams.
async function deflateBase64(text: string): Promise<string> {
  const stream = new Blob([text]).stream().pipeThrough(new CompressionStream("deflate"));
  const bytes = new Uint8Array(await new Response(stream).arrayBuffer());
  let binary = "";
  for (const byte of bytes) binary += String.fromCharCode(byte);
  return btoa(binary);
}

describe("Connection", () => {
  it("inflates a hello's compressed structure before it, and the messages after it, are handled", async () => {
    const structures: unknown[] = [];
    const { connection, sockets, events } = setup();
    (connection as unknown as { handlers: { hello: (h: { structure: unknown }) => void } }).handlers.hello = (h) => {
      events.hellos++;
      structures.push(h.structure);
    };
    connection.start();
    sockets[0]?.open();
    const plain = hello(4);
    const packed = await deflateBase64(JSON.stringify(plain.structure));
    sockets[0]?.serve({ ...plain, structure: null, structure_z: packed });
    sockets[0]?.serve(frame(7, 100, [], true, 4)); // arrives while the structure inflates
    expect(events.frames).toEqual([]);
    await vi.waitFor(() => expect(events.hellos).toBe(1));
    expect(structures[0]).toEqual(plain.structure);
    expect(connection.generation).toBe(4);
    expect(events.frames).toEqual([7]); // after the hello, in order
    sockets[0]?.serve(frame(8, 125, [], false, 4));
    expect(events.frames).toEqual([7, 8]); // nothing waits any more
  });

  it("subscribes on open and goes live on hello", () => {
    const { connection, sockets, events } = setup();
    connection.start();
    sockets[0]?.open();
    expect(sockets[0]?.sent[0]).toEqual({ type: "subscribe", rate: 30, robots: null });
    sockets[0]?.serve(hello(4));
    expect(connection.state).toBe("live");
    expect(connection.generation).toBe(4);
    sockets[0]?.serve(frame(7, 100, [], true, 4));
    expect(events.frames).toEqual([7]);
  });

  it("reconnects with growing delays and resets them after a hello", () => {
    const { connection, sockets, timers, events } = setup();
    connection.start();
    sockets[0]?.drop();
    sockets[0]?.drop();
    expect(timers.map((t) => t.ms)).toEqual([100]);
    timers[0]?.fn();
    sockets[1]?.drop();
    timers[1]?.fn();
    sockets[2]?.drop();
    expect(timers.map((t) => t.ms)).toEqual([100, 200, 400]);
    timers[2]?.fn();
    sockets[3]?.open();
    sockets[3]?.serve(hello(1));
    sockets[3]?.drop();
    expect(timers[3]?.ms).toBe(100);
    expect(events.links).toContain("waiting");
    expect(events.links.at(-1)).toBe("waiting");
    connection.stop();
  });

  it("asks for a resync once when a frame's generation is not the hello's", () => {
    const { connection, sockets, events } = setup();
    connection.start();
    sockets[0]?.open();
    sockets[0]?.serve(hello(1));
    sockets[0]?.serve(frame(1, 25, [], false, 2));
    sockets[0]?.serve(frame(2, 50, [], false, 2));
    expect(events.frames).toEqual([]);
    expect(sockets[0]?.sent.filter((m) => (m as { type: string }).type === "resync")).toHaveLength(1);
  });

  it("resolves and rejects commands by id and fails pending ones on close", async () => {
    const { connection, sockets } = setup();
    connection.start();
    sockets[0]?.open();
    sockets[0]?.serve(hello(1));
    const ok = connection.command("pause");
    const bad = connection.command("force_option", { robot: 0, option: "kik" });
    const sent = sockets[0]?.sent.slice(1) as Array<{ id: number; op: string; option?: string }>;
    expect(sent.map((m) => m.op)).toEqual(["pause", "force_option"]);
    expect(sent[1]?.option).toBe("kik");
    sockets[0]?.serve({ type: "reply", id: sent[0]?.id, ok: true, result: { paused: true } });
    sockets[0]?.serve({ type: "reply", id: sent[1]?.id, ok: false, error: "unknown option 'kik'" });
    await expect(ok).resolves.toEqual({ paused: true });
    await expect(bad).rejects.toThrow("unknown option 'kik'");
    const lost = connection.command("step");
    sockets[0]?.drop();
    await expect(lost).rejects.toThrow("connection closed");
    await expect(connection.command("pause")).rejects.toThrow("not connected");
  });

  it("collects history chunks after the reply", async () => {
    const { connection, sockets } = setup();
    connection.start();
    sockets[0]?.open();
    sockets[0]?.serve(hello(1));
    const result = connection.history(0, 1000);
    const id = (sockets[0]?.sent.at(-1) as { id: number }).id;
    sockets[0]?.serve({ type: "reply", id, ok: true, result: { frames: 3, chunks: 2 } });
    sockets[0]?.serve({ type: "history", id, chunk: 0, last: false, frames: [frame(1, 25, [], true), frame(2, 50, [])] });
    sockets[0]?.serve({ type: "history", id, chunk: 1, last: true, frames: [frame(3, 75, [])] });
    expect((await result).map((f) => f.seq)).toEqual([1, 2, 3]);
    const empty = connection.history(5000, 6000);
    const id2 = (sockets[0]?.sent.at(-1) as { id: number }).id;
    sockets[0]?.serve({ type: "reply", id: id2, ok: true, result: { frames: 0, chunks: 0 } });
    expect(await empty).toEqual([]);
  });

  it("times out a command without reply", async () => {
    vi.useFakeTimers();
    try {
      const { connection, sockets } = setup();
      connection.start();
      sockets[0]?.open();
      const p = connection.command("status");
      vi.advanceTimersByTime(10_001);
      await expect(p).rejects.toThrow("no reply to status");
    } finally {
      vi.useRealTimers();
    }
  });
});
