/// A replay (`xabsl serve --replay FILE.mcap`): the whole recording in the timeline, not a window.
///
/// The server says in its status (`replay`) that it serves a recording, how many ticks it holds
/// and the behavior times of its first and last tick. The page then keeps every tick it loads
/// (no time window) and fetches the recording with `history` in hunks of at most `HUNK_TICKS`
/// ticks (the server decodes those from the file on demand); a recording longer than `MAX_TICKS`
/// is loaded at every n-th tick, enough for the timeline and the plots. "Why" asks the server for
/// the explanation of the tick in view (`explain` with `seq`): any tick of a replay is explainable.
import type { Connection } from "./connection";
import type { ReplayInfo as ReplayStatus } from "./messages.gen";
import type { Session } from "./session";

/// What the page keeps of a replay's status (`replay` of `GET /api/status`, server/protocol/rest.py).
export type ReplayInfo = Pick<ReplayStatus, "file" | "ticks" | "t0" | "t1">;

/// Ticks one `history` request spans (the server refuses more than 4800).
export const HUNK_TICKS = 4000;
/// The most ticks the page keeps of a recording.
export const MAX_TICKS = 12_000;

/// The replay described by a status answer, or null for a live session.
export function replayOf(status: Record<string, unknown> | null | undefined): ReplayInfo | null {
  const replay = status?.["replay"] as Partial<ReplayStatus> | undefined;
  if (!replay || typeof replay.ticks !== "number" || typeof replay.t0 !== "number" || typeof replay.t1 !== "number") return null;
  return { file: String(replay.file ?? ""), ticks: replay.ticks, t0: replay.t0, t1: replay.t1 };
}

/// Whether a status answer is of a replay that can be forked ("Run from here"): a recording of a
/// deterministic run that is not itself a fork.
export function forkable(status: Record<string, unknown> | null | undefined): boolean {
  const header = (status?.["replay"] as { header?: Record<string, unknown> } | undefined)?.header;
  return !!header && header["deterministic"] === true && !header["first_seq"];
}

/// The hunks `[t0, t1]` (inclusive behavior times) that together cover a recording.
export function hunks(info: ReplayInfo, behaviorHz: number): Array<[number, number]> {
  const span = (HUNK_TICKS * 1000) / behaviorHz;
  const out: Array<[number, number]> = [];
  for (let t = info.t0; t <= info.t1; t += span) out.push([t, Math.min(info.t1, t + span - 1)]);
  return out;
}

/// Load the whole recording into the session's buffer, hunk by hunk (the timeline fills as it comes).
export async function loadReplay(connection: Connection, session: Session, info: ReplayInfo): Promise<void> {
  session.replay = info;
  session.buffer.windowMs = Number.POSITIVE_INFINITY;
  const every = Math.max(1, Math.ceil(info.ticks / MAX_TICKS));
  const hz = session.hello?.session.behavior_hz ?? 40;
  for (const [t0, t1] of hunks(info, hz)) {
    if (session.replay !== info) return; // a new hello started over
    session.applyHistory(await connection.history(t0, t1, every));
  }
}
