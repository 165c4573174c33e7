import { describe, expect, it } from "vitest";
import { formatDuration, formatSize } from "../src/recordings";
import { forkable } from "../src/replay";

describe("recordings", () => {
  it("formats sizes and lengths as the dialog lists them", () => {
    expect(formatSize(512_000)).toBe("512 kB");
    expect(formatSize(42_600_000)).toBe("42.6 MB");
    expect(formatSize(2_100_000_000)).toBe("2.1 GB");
    expect(formatSize(10)).toBe("1 kB");
    expect(formatDuration(36)).toBe("0:36");
    expect(formatDuration(679.4)).toBe("11:19");
    expect(formatDuration(43_205)).toBe("12:00:05");
  });

  it("offers run from here only in a replay of a deterministic recording that is no fork", () => {
    expect(forkable({ replay: { header: { deterministic: true } } })).toBe(true);
    expect(forkable({ replay: { header: { deterministic: false } } })).toBe(false);
    expect(forkable({ replay: { header: { deterministic: true, first_seq: 700 } } })).toBe(false);
    expect(forkable({ paused: false })).toBe(false);
    expect(forkable(null)).toBe(false);
  });
});
