import { describe, expect, it } from "vitest";
import { Backoff, backoffDelay } from "../src/backoff";

describe("backoff", () => {
  const mid = (): number => 0.5; // no jitter
  it("doubles from the base up to the cap", () => {
    const delays = [0, 1, 2, 3, 4, 5, 6, 10, 40].map((a) => backoffDelay(a, { base: 250, max: 5000, jitter: 0.2 }, mid));
    expect(delays).toEqual([250, 500, 1000, 2000, 4000, 5000, 5000, 5000, 5000]);
  });
  it("jitters within the fraction and never exceeds the cap", () => {
    expect(backoffDelay(1, { base: 250, max: 5000, jitter: 0.2 }, () => 0)).toBe(400);
    expect(backoffDelay(1, { base: 250, max: 5000, jitter: 0.2 }, () => 0.999999)).toBe(600);
    expect(backoffDelay(9, { base: 250, max: 5000, jitter: 0.2 }, () => 0.999999)).toBe(5000);
  });
  it("counts attempts and starts over after success", () => {
    const b = new Backoff({ base: 100, max: 1000, jitter: 0 });
    expect([b.next(), b.next(), b.next()]).toEqual([100, 200, 400]);
    b.succeeded();
    expect(b.next()).toBe(100);
  });
});
