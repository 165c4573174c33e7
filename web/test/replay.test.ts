import { describe, expect, it } from "vitest";
import { HUNK_TICKS, hunks, replayOf } from "../src/replay";

describe("replay", () => {
  it("reads the replay from a status answer, null for a live session", () => {
    expect(replayOf({ example: "soccer" })).toBeNull();
    expect(replayOf({ replay: { file: "m.mcap", ticks: 10, t0: 25, t1: 250 } })).toEqual({ file: "m.mcap", ticks: 10, t0: 25, t1: 250 });
  });

  it("covers the whole recording with adjacent hunks no longer than the server allows", () => {
    const info = { file: "m.mcap", ticks: 24_000, t0: 0, t1: 599_975 };
    const parts = hunks(info, 40);
    expect(parts[0]?.[0]).toBe(0);
    expect(parts[parts.length - 1]?.[1]).toBe(599_975);
    for (let i = 1; i < parts.length; i++) expect((parts[i] as [number, number])[0]).toBe((parts[i - 1] as [number, number])[1] + 1);
    for (const [a, b] of parts) expect((b - a + 1) / 25).toBeLessThanOrEqual(HUNK_TICKS);
  });
});
