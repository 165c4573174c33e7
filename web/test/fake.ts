// A small fake stream for unit tests only: hello and frames built from the real demo program
// JSON (examples/demo, `xabsl compile --json`) and the soccer world's real static scene.
import demo from "./fixtures/demo.json";
import scene from "./fixtures/soccer-static.json";
import type { BehaviorDescription } from "../src/description";
import type { Frame, Hello, RobotFrame, WirePathNode } from "../src/protocol";

export const description = demo as unknown as BehaviorDescription;

/// The demo description after a reload that renamed option `play` and reversed the ids of its states.
export function editedDescription(): BehaviorDescription {
  const d = structuredClone(description) as BehaviorDescription & { options: Array<{ id: number; name: string; states: Array<{ id: number; name: string }> }> };
  const play = d.options.find((o) => o.id === 1);
  if (!play) throw new Error("the demo has no option 1");
  play.name = "play_edited";
  play.states = play.states.map((s, i, all) => ({ ...s, id: all.length - 1 - i })).reverse();
  return d as BehaviorDescription;
}

export function hello(generation = 1, t = 0): Hello {
  return {
    type: "hello",
    version: 1,
    reason: "connect",
    generation,
    session: { example: "demo", paused: false, speed: 1, seed: 1, behavior_hz: 40, seq: 0, t, token_required: false },
    structure: {
      programs: { behavior: description },
      robots: [
        { id: 0, name: "blue1", team: "blue", number: 1, program: "behavior" },
        { id: 1, name: "blue2", team: "blue", number: 2, program: "behavior" },
      ],
    },
    scene: scene as Hello["scene"],
  };
}

/// play (id 1) in `playState`, calling approach_ball (id 0) in state `approachState` when chasing.
export function playPath(playState: number, approachState = 0, decidedIn = playState, leaf = 2): WirePathNode[] {
  const path: WirePathNode[] = [[0, 0, 1, playState, 5000, 800, decidedIn, leaf, []]];
  if (playState === 1) {
    path.push([0, 1, 0, approachState, 800, 300, approachState, 1, [250]]);
    path.push([1, 2, 1, 800, [120.5, -3]]);
  } else {
    path.push([1, 1, 0, 5000, []]);
  }
  return path;
}

export function frame(seq: number, t: number, robots: RobotFrame[], full = false, gen = 1): Frame {
  return { type: "frame", seq, gen, t, wall: 1_700_000_000_000 + t, full, robots };
}
