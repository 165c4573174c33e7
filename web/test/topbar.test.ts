// The top bar's link indicator: the render loop calls it on every display refresh, about twice
// as often as frames come; between frames its text must not change for nothing.
import { afterEach, beforeEach, describe, expect, it, vi } from "vitest";
import type { Connection } from "../src/connection";
import { TopBar } from "../src/panels/topbar";
import { Session } from "../src/session";
import { fakeDomGlobals, type FakeElement } from "./dom";
import { frame, hello, playPath } from "./fake";

describe("top bar: the link indicator", () => {
  let session: Session;
  let bar: TopBar;
  let now: number;
  const connection = { lastFrameAt: 0, framesPerSecond: 30, command: (): Promise<never> => Promise.reject(new Error("offline")), reconnectNow: (): void => undefined };
  const text = (): string => ((bar.element as unknown as FakeElement).querySelector(".link-text") as FakeElement).textContent;
  const arrive = (seq: number): void => {
    session.applyFrame(frame(seq, seq * 25, [{ id: 0, path: playPath(0, 0, 0, 0) }], seq === 1));
    connection.lastFrameAt = performance.now();
  };

  beforeEach(() => {
    for (const [name, value] of Object.entries(fakeDomGlobals())) vi.stubGlobal(name, value);
    now = 10_000;
    vi.spyOn(performance, "now").mockImplementation(() => now);
    session = new Session();
    session.applyHello(hello());
    bar = new TopBar(session, connection as unknown as Connection, { toggleTheme: () => undefined, help: () => undefined });
    bar.setLink("live", { attempt: 0 });
  });
  afterEach(() => {
    vi.restoreAllMocks();
    vi.unstubAllGlobals();
  });

  it("shows the latency of the frame drawn until the next one, and counts the silence after", () => {
    const wall = (seq: number): number => 1_700_000_000_000 + seq * 25; // fake.ts: frame(seq, t = seq * 25)
    const clock = vi.spyOn(Date, "now");
    arrive(1);
    clock.mockReturnValue(wall(1) + 40);
    bar.render(new Set(["tick"]));
    expect(text()).toBe("live · 30 fps · 40 ms");
    // Refreshes without a frame: the frame shown is the same, so is its latency.
    for (let i = 1; i <= 3; i++) {
      now += 16;
      clock.mockReturnValue(wall(1) + 40 + 16 * i);
      bar.renderLink(false);
      expect(text()).toBe("live · 30 fps · 40 ms");
    }
    // The next frame drawn: its own latency.
    arrive(2);
    clock.mockReturnValue(wall(2) + 35);
    bar.render(new Set(["tick"]));
    expect(text()).toBe("live · 30 fps · 35 ms");
    // No frame for a while: between frames the bar still says so, and counts.
    now += 3000;
    bar.renderLink(false);
    expect(text()).toBe("no frames for 3 s");
    now += 1000;
    bar.renderLink(false);
    expect(text()).toBe("no frames for 4 s");
  });
});
