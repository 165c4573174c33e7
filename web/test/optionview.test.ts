// The option view's why pane as the decisions of a team's root come and go (benchmarks/ui_fps.py,
// "the root's 31-state machine in the option view"): what a decision changes is drawn anew,
// what it does not change stays the same elements.
import { afterEach, beforeEach, describe, expect, it, vi } from "vitest";
import type { Connection } from "../src/connection";
import { OptionView } from "../src/panels/optionview";
import type { Comparison } from "../src/messages.gen";
import type { Explanation } from "../src/protocol";
import { Session, type SessionEvent } from "../src/session";
import { created, fakeDomGlobals, type FakeElement } from "./dom";
import { frame, hello, playPath } from "./fake";

/// The live answer to `explain` for play (option 1) deciding in state `decidedIn` on leaf `leaf`.
function answer(decidedIn: number, leaf: number, target: number, values: boolean[]): Explanation {
  const names = ["wait", "chase", "search"];
  return {
    option: 1,
    option_name: "play",
    decided_in: decidedIn,
    decided_in_name: names[decidedIn] as string,
    leaf,
    target,
    target_name: names[target] as string,
    stay: decidedIn === target,
    leaf_span: null,
    conditions: values.map((value, i) => ({ text: `condition ${i}`, source: `condition ${i}`, value, branch: value, span: null })),
    recorded: false,
    last_transition: null,
  };
}

/// The comparison `ball.time_since_seen > 1000` with the operand's value `seen`.
function seenFor(seen: number, value: boolean): Comparison {
  return { text: "ball.time_since_seen > 1000", op: ">", left: "ball.time_since_seen", left_value: String(seen), right: "1000", right_value: "1000", value, shown: `ball.time_since_seen (${seen}) > 1000` };
}

const flush = (): Promise<void> => new Promise((resolve) => setTimeout(resolve, 0));

describe("option view: the why pane", () => {
  let session: Session;
  let view: OptionView;
  let explain: Array<(ex: Explanation) => void>;
  let seq = 0;

  const show = (path: ReturnType<typeof playPath>, changes: SessionEvent[] = ["tick"]): void => {
    seq++;
    session.applyFrame(frame(seq, seq * 25, [{ id: 0, path }, { id: 1, path: playPath(0, 0, 0, 0) }], seq === 1));
    view.render(new Set(changes));
  };
  const pane = (): FakeElement => (view.element as unknown as FakeElement).querySelector(".why") as FakeElement;
  const pickers = (): FakeElement[] => created.filter((el) => el.tagName === "SELECT" && el.classList.contains("why-not-picker"));

  beforeEach(() => {
    for (const [name, value] of Object.entries(fakeDomGlobals())) vi.stubGlobal(name, value);
    session = new Session();
    session.applyHello(hello());
    explain = [];
    seq = 0;
    const connection = {
      command: (op: string): Promise<unknown> => (op === "explain" ? new Promise((resolve) => explain.push(resolve)) : Promise.reject(new Error("offline"))),
    };
    view = new OptionView(session, connection as unknown as Connection, { edit: () => undefined, test: () => undefined, find: () => undefined });
  });
  afterEach(() => {
    vi.unstubAllGlobals();
  });

  it("shows each decision as it comes, with one Why-not picker that stays in the pane", async () => {
    show(playPath(0, 0, 0, 0), ["hello", "tick"]); // wait stays
    explain.shift()?.(answer(0, 0, 0, [true]));
    await flush();
    show(playPath(1, 0, 0, 1)); // wait -> chase
    show(playPath(1, 0, 1, 2)); // chase stays
    explain.shift()?.(answer(1, 2, 1, [false, false]));
    await flush();
    show(playPath(2, 0, 1, 1)); // chase -> search

    expect(pane().querySelector(".why-head")?.textContent).toBe("Decision of this tick: chase → search (leaf 1)");
    // A <select> made anew on every decision is a form control added to the page each time,
    // which the browser reads again (benchmarks/ui_fps.py missed frames over it).
    expect(pickers()).toHaveLength(1);
    const picker = pickers()[0] as FakeElement;
    expect(pane().contains(picker)).toBe(true);
    expect(picker.options.map((o) => o.textContent)).toEqual(["Why not…", "wait", "chase"]);
  });

  it("fills the answer's values into the rows of its decision instead of drawing them again", async () => {
    show(playPath(1, 0, 1, 2), ["hello", "tick"]); // chase stays: two conditions, both else
    const rows = pane().querySelectorAll("li.cond");
    expect(rows.map((r) => r.querySelector("code")?.textContent)).toEqual(["game.state != playing", "ball.time_since_seen > 1000"]);
    expect(pane().querySelectorAll(".value")).toHaveLength(0);
    expect(pane().textContent).toContain("Asking the server for values…");

    explain.shift()?.(answer(1, 2, 1, [false, false]));
    await flush();
    const after = pane().querySelectorAll("li.cond");
    expect(after).toHaveLength(rows.length);
    after.forEach((row, i) => expect(row).toBe(rows[i])); // the same elements, values added
    expect(after.map((r) => r.querySelector(".value")?.textContent)).toEqual(["false", "false"]);
    expect(pane().textContent).toContain("Values the decision read in the last tick.");

    show(playPath(2, 0, 1, 1)); // chase -> search: another decision, rows of its own, no values yet
    const next = pane().querySelectorAll("li.cond");
    expect(next.map((r) => r.classList.contains("taken"))).toEqual([false, true]);
    expect(next.some((r) => rows.includes(r))).toBe(false);
    expect(pane().querySelectorAll(".value")).toHaveLength(0);
  });

  it("updates the values of a decision asked again in the same elements", async () => {
    show(playPath(1, 0, 1, 2), ["hello", "tick"]); // chase stays: two conditions, both else
    const first = answer(1, 2, 1, [false, false]);
    (first.conditions[1] as Explanation["conditions"][number]).comparisons = [seenFor(400, false)];
    explain.shift()?.(first);
    await flush();
    const values = pane().querySelectorAll(".value");
    const comparisons = pane().querySelectorAll("li.comparison");
    expect(values.map((v) => v.textContent)).toEqual(["false", "false"]);
    expect(comparisons).toHaveLength(1);

    // Live, the same decision is asked again (every second, or Why?): the values it read then.
    const why = (view.element as unknown as FakeElement).querySelectorAll("button").find((b) => b.textContent === "Why?") as FakeElement;
    /// Why? again, answered with the second condition true after reading `seen` ms.
    const askAgain = async (seen: number): Promise<void> => {
      why.click();
      const again = answer(1, 2, 1, [false, true]);
      (again.conditions[1] as Explanation["conditions"][number]).comparisons = [seenFor(seen, true)];
      explain.shift()?.(again);
      await flush();
    };
    await askAgain(400);
    // A row's values taken out and put back were layout work for the pane and all below it.
    const valuesAfter = pane().querySelectorAll(".value");
    valuesAfter.forEach((v, i) => expect(v).toBe(values[i]));
    expect(valuesAfter.map((v) => [v.textContent, v.className])).toEqual([["false", "value false"], ["true", "value true"]]);
    const comparisonsAfter = pane().querySelectorAll("li.comparison");
    expect(comparisonsAfter[0]).toBe(comparisons[0]);
    expect(comparisonsAfter.map((c) => [c.textContent, c.className])).toEqual([["ball.time_since_seen (400) > 1000 = true", "comparison true"]]);

    // Other operands (another comparison read): that row's values are drawn anew.
    await askAgain(1200);
    const rebuilt = pane().querySelectorAll("li.comparison");
    expect(rebuilt.map((c) => c.textContent)).toEqual(["ball.time_since_seen (1200) > 1000 = true"]);
    expect(rebuilt[0]).not.toBe(comparisons[0]);
    expect(pane().querySelectorAll(".value")[0]).toBe(values[0]);
  });
});
