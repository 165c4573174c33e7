import { describe, expect, it } from "vitest";
import { attachedHosts, hostLabel, type AttachedHost } from "../src/panels/attach";

const host = (over: Partial<AttachedHost>): AttachedHost => ({
  address: "127.0.0.1:7411",
  name: "robot1",
  connected: true,
  gone: false,
  refused: null,
  robots: ["robot1"],
  control: null,
  controlled_here: false,
  received: 10,
  missed: 0,
  ...over,
});

describe("attached hosts", () => {
  it("are read from an attached session's tick status only", () => {
    expect(attachedHosts({ attached: [host({})], connect: true })).toHaveLength(1);
    expect(attachedHosts({ time_ms: 100 })).toBeNull(); // a studio on its own world
    expect(attachedHosts(null)).toBeNull();
  });

  it("say their state and who holds their control", () => {
    expect(hostLabel(host({ control: { studio: "me", peer: "p1" }, controlled_here: true }))).toEqual({ state: "attached", control: "control: this studio" });
    expect(hostLabel(host({ control: { studio: "laptop-2", peer: "p2" } })).control).toBe("control: laptop-2");
    expect(hostLabel(host({ connected: false, gone: true }))).toEqual({ state: "gone", control: "control: free" });
    expect(hostLabel(host({ connected: false, refused: "a valid token is required" })).state).toBe("refused");
    expect(hostLabel(host({ connected: false })).state).toBe("connecting");
  });
});
