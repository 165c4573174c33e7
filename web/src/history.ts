/// The client's buffer of decoded ticks: live frames as they arrive, merged with frames of the
/// server's ring buffer (the `history` command) so the timeline covers time before the page
/// was opened, of every generation (reloads and resets keep the ticks before them). Ordered by
/// `seq`; times are timeline times (`Tick.x`, which go on across resets); older than `windowMs`
/// behind the newest is dropped.
import type { Tick } from "./protocol";

export class TickBuffer {
  private ticks: Tick[] = [];

  constructor(public windowMs = 120_000) {}

  get length(): number {
    return this.ticks.length;
  }

  get all(): readonly Tick[] {
    return this.ticks;
  }

  get newest(): Tick | null {
    return this.ticks.length ? (this.ticks[this.ticks.length - 1] as Tick) : null;
  }

  get oldest(): Tick | null {
    return this.ticks.length ? (this.ticks[0] as Tick) : null;
  }

  clear(): void {
    this.ticks = [];
  }

  /// Append a live tick (ticks arrive in seq order; an older or repeated one is ignored).
  push(tick: Tick): void {
    const newest = this.newest;
    if (newest && tick.seq <= newest.seq) return;
    this.ticks.push(tick);
    this.trim();
  }

  /// Merge ticks of a history stream (any order, may overlap what is there).
  merge(ticks: readonly Tick[]): void {
    if (!ticks.length) return;
    const bySeq = new Map<number, Tick>();
    for (const t of ticks) bySeq.set(t.seq, t);
    // Live ticks win over history ticks of the same seq (they are what the panels showed).
    for (const t of this.ticks) bySeq.set(t.seq, t);
    this.ticks = [...bySeq.values()].sort((a, b) => a.seq - b.seq);
    this.trim();
  }

  private trim(): void {
    const newest = this.newest;
    if (!newest) return;
    const limit = newest.x - this.windowMs;
    let drop = 0;
    while (drop < this.ticks.length && (this.ticks[drop] as Tick).x < limit) drop++;
    if (drop) this.ticks.splice(0, drop);
  }

  /// Index of the last tick with `x <= time` (0 when time is before the first).
  indexAt(time: number): number {
    let lo = 0;
    let hi = this.ticks.length - 1;
    if (hi < 0) return -1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if ((this.ticks[mid] as Tick).x <= time) lo = mid;
      else hi = mid - 1;
    }
    return lo;
  }

  /// The tick shown at timeline time `time`.
  at(time: number): Tick | null {
    const i = this.indexAt(time);
    return i >= 0 ? (this.ticks[i] as Tick) : null;
  }

  bySeq(seq: number): Tick | null {
    let lo = 0;
    let hi = this.ticks.length - 1;
    while (lo <= hi) {
      const mid = (lo + hi) >> 1;
      const s = (this.ticks[mid] as Tick).seq;
      if (s === seq) return this.ticks[mid] as Tick;
      if (s < seq) lo = mid + 1;
      else hi = mid - 1;
    }
    return null;
  }

  /// Ticks with timeline times `x0 <= x <= x1`.
  range(x0: number, x1: number): Tick[] {
    const out: Tick[] = [];
    for (const t of this.ticks) if (t.x >= x0 && t.x <= x1) out.push(t);
    return out;
  }

  /// The first buffered tick of each generation after the oldest buffered one (where a reload,
  /// reset or fork started it), oldest first.
  starts(): Tick[] {
    const out: Tick[] = [];
    for (let i = 1; i < this.ticks.length; i++) {
      const tick = this.ticks[i] as Tick;
      if (tick.gen !== (this.ticks[i - 1] as Tick).gen) out.push(tick);
    }
    return out;
  }

  /// Drop the ticks of generations `keep` says no to (their description is unknown).
  retain(keep: (gen: number) => boolean): void {
    this.ticks = this.ticks.filter((t) => keep(t.gen));
  }
}
