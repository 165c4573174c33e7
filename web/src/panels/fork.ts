/// Fork: "Run from here" at the timeline cursor, the fork point on the timeline, and the original
/// run beside the fork (docs/studio.md "Fork").
///
/// The server rebuilds the world at the tick under the cursor with the behavior in force now and
/// goes on live (op `fork`, a hello with reason `fork` follows). While the running world is a
/// fork, the activation panel shows a line with the selected robot's option path in the original
/// run at the same world time, fetched from the server (`GET /api/fork/original`: the ring still
/// holds the original's ticks at older seqs), and where each robot first acts differently from
/// the original (`GET /api/fork/diverge`): the earliest marked on the timeline, each robot's
/// tick, the option whose decision parts the runs and what it did on each side, with buttons to
/// the two ticks (the why pane there shows the values).
import { ApiError, apiJson, token } from "../api";
import type { Connection } from "../connection";
import type { DecisionJson, ForkDivergenceJson, ForkOrigin, RobotDivergenceJson } from "../messages.gen";
import type { Session, SessionEvent } from "../session";
import { formatClock, h, setText, toast } from "../ui";

interface OriginalNode {
  depth: number;
  option?: string;
  state?: string | null;
  behavior?: string;
}

interface OriginalTick {
  seq: number;
  t: number;
  robots: Array<{ id: number; name: string; path: OriginalNode[] }>;
}

/// The option path as one line: `play_soccer/playing › striker/kick › kick`.
export function pathLine(path: readonly OriginalNode[]): string {
  return path.map((n) => (n.option !== undefined ? `${n.option}/${n.state ?? "?"}` : `${n.behavior ?? "?"}`)).join(" › ");
}

function decision(why: DecisionJson | null): string {
  return why ? (why.stay ? `${why.decided_in} stays` : `${why.decided_in} → ${why.target}`) : "?";
}

/// One robot's divergence in words: the tick, the parting option and what it did on each side.
/// Where samples were dropped just before it the paths may have parted earlier: said, not hidden.
export function divergenceLine(d: RobotDivergenceJson): string {
  const unsure = d.uncompared_before > 0 ? `(or in one of the ${d.uncompared_before} tick${d.uncompared_before > 1 ? "s" : ""} before it, not sampled) ` : "";
  return `${d.name}: tick ${d.seq} (${formatClock(d.t)}), ${d.option ?? "?"}: fork ${decision(d.why_fork)} · original ${decision(d.why_original)} ${unsure}`;
}

/// How often a fork's divergence is asked again while some robot still acts like the original.
const DIVERGE_POLL_MS = 1000;

export class ForkControls {
  /// Where the fork first acts differently from its original (null: nowhere yet, or no fork): the timeline marks it.
  onDivergence: (divergence: { seq: number; t: number; agent: string } | null) => void = () => undefined;
  /// Each robot's first divergence from the original, for the activation panel.
  readonly divergence: HTMLElement;
  private divergenceFor: number | null = null;
  private divergencePoll: ReturnType<typeof setTimeout> | null = null;
  /// "Run from here", for the timeline's toolbar.
  readonly button: HTMLButtonElement;
  /// Where the running world was forked (empty when it is no fork), for the timeline's toolbar.
  readonly badge: HTMLElement;
  /// The original run's path of the selected robot, for the activation panel.
  readonly original: HTMLElement;
  private readonly originalText: HTMLElement;
  private busy = false;
  private fetched = new Map<number, OriginalTick | null>();
  private asking: number | null = null;
  private lastAsk = 0;
  private retry: ReturnType<typeof setTimeout> | null = null;

  constructor(
    private readonly session: Session,
    private readonly connection: Connection,
  ) {
    this.button = h(
      "button#run-from-here",
      {
        title: "Restart the world at the tick under the cursor with the current behavior and run on live (the original run stays in the history for comparison)",
        onclick: () => this.runFromHere(),
      },
      "Run from here",
    );
    this.badge = h("span.fork-badge", { hidden: true });
    this.originalText = h("span.fork-original-path");
    this.original = h("div.fork-original.muted", { hidden: true, title: "The selected robot's option path in the original run at this world time" }, h("strong", {}, "original: "), this.originalText);
    this.divergence = h("div.fork-diverge", { hidden: true });
  }

  /// Ask where the fork parts from its original, again every second while some robot has not.
  private watchDivergence(origin: ForkOrigin | null): void {
    const start = origin?.start ?? null;
    if (start === this.divergenceFor) return;
    this.divergenceFor = start;
    if (this.divergencePoll !== null) clearTimeout(this.divergencePoll);
    this.divergencePoll = null;
    this.divergence.hidden = true;
    this.divergence.replaceChildren();
    this.onDivergence(null);
    if (start !== null) void this.askDivergence(start);
  }

  private async askDivergence(start: number): Promise<void> {
    let report: ForkDivergenceJson | null = null;
    try {
      report = await apiJson<ForkDivergenceJson>("GET", "fork/diverge");
    } catch {
      report = null; // no fork any more (a reset), or the server is gone: the next hello says
    }
    if (this.divergenceFor !== start) return;
    if (report) this.showDivergence(report);
    const robots = this.session.robots.filter((r) => r.program !== null).length;
    if (!report || (!report.ended && report.robots.length < robots)) {
      this.divergencePoll = setTimeout(() => void this.askDivergence(start), DIVERGE_POLL_MS);
    }
  }

  private showDivergence(report: ForkDivergenceJson): void {
    const first = report.earliest;
    this.onDivergence(first ? { seq: first.seq, t: first.t, agent: first.name } : null);
    const go = (d: RobotDivergenceJson, seq: number, label: string): HTMLButtonElement =>
      h("button.fork-diverge-go", { title: `Show tick ${seq} with ${d.name} selected (the why pane gives the values)`, onclick: () => this.show(d, seq) }, label);
    const rows = report.robots.map((d) =>
      h(
        "li",
        { "data-robot": String(d.robot), "data-seq": String(d.seq) },
        divergenceLine(d),
        go(d, d.seq, "fork's tick"),
        " ",
        go(d, d.original_seq, "original's tick"),
      ),
    );
    const alike = report.ended ? "acts like the original in every tick they share" : "acts like the original so far";
    this.divergence.replaceChildren(
      h("strong", {}, first ? `The fork parts from the original: ${first.name} first, at ${formatClock(first.t)}` : `The fork ${alike}`),
      h("ol.fork-diverge-list", {}, ...rows),
    );
    this.divergence.hidden = false;
  }

  private show(d: RobotDivergenceJson, seq: number): void {
    this.session.selectRobot(d.robot);
    // the tick itself, else the last one before it the client holds (frames may skip ticks)
    const tick = this.session.buffer.bySeq(seq) ?? this.session.buffer.all.filter((t) => t.seq <= seq).at(-1);
    if (tick) this.session.setCursor(tick.x);
    else toast(`Tick ${seq} is no longer in the history`, "info");
  }

  /// The fork the running world comes from (null: none).
  get origin(): ForkOrigin | null {
    return this.session.hello?.fork ?? null;
  }

  private runFromHere(): void {
    const tick = this.session.cursor === null ? null : this.session.view;
    if (!tick || this.busy) return;
    this.busy = true;
    this.button.disabled = true;
    setText(this.button, "Re-simulating…");
    void this.connection
      .command("fork", { seq: tick.seq })
      .then(async (result) => {
        toast(`Running from t = ${formatClock(result.t)} with the current behavior (${result.ticks} ticks re-simulated in ${Math.round(result.ms)} ms)`, "ok");
        // "Run": a paused session resumes (resuming a running one changes nothing; the fork's
        // hello, which says whether it is paused, may arrive after this reply).
        await this.connection.command("resume");
      })
      .catch((error: unknown) => {
        const message = error instanceof Error ? error.message : String(error);
        // A long run since the last reset re-simulates for more than the reply timeout: the fork
        // still happens (its hello follows), only its reply came too late.
        if (message.startsWith("no reply")) toast("Run from here: still re-simulating (a long run since the last reset); the fork starts when it is done", "info", 8000);
        else toast(`Run from here: ${message}`, "error", 8000);
      })
      .finally(() => {
        this.busy = false;
        setText(this.button, "Run from here");
        this.render(new Set());
      });
  }

  render(changes: Set<SessionEvent>): void {
    const session = this.session;
    if (changes.has("hello")) this.fetched.clear();
    // A replay forks into a new tab instead (its own "Run from here", recordings.ts).
    this.button.hidden = session.replay !== null;
    this.button.disabled = this.busy || session.cursor === null || session.replay !== null || !session.view;
    const origin = this.origin;
    this.watchDivergence(origin);
    this.badge.hidden = origin === null;
    if (origin) setText(this.badge, `fork of t = ${formatClock(origin.t)}`);
    const tick = session.view;
    if (!origin || !tick || tick.seq < origin.start) {
      this.original.hidden = true;
      return;
    }
    this.original.hidden = false;
    const known = this.fetched.get(tick.seq);
    if (known === undefined) {
      this.ask(tick.seq);
      return;
    }
    const robot = known?.robots.find((r) => r.id === session.selectedRobot);
    this.original.dataset.seq = String(tick.seq); // the fork's tick the line is for
    this.original.dataset.originalSeq = known ? String(known.seq) : "";
    setText(this.originalText, known === null ? "not in the history (left the ring, or the original did not run that far)" : robot ? pathLine(robot.path) || "nothing active" : "no such robot");
  }

  /// Fetch the original's tick for `seq` (one request at a time; live ticks skip ahead).
  private ask(seq: number): void {
    if (this.asking !== null) return;
    const wait = this.lastAsk + 150 - performance.now();
    if (wait > 0) {
      this.retry ??= setTimeout(() => {
        this.retry = null;
        this.render(new Set());
      }, wait);
      return;
    }
    this.lastAsk = performance.now();
    this.asking = seq;
    void fetchOriginal(seq)
      .then((tick) => this.fetched.set(seq, tick))
      .catch(() => this.fetched.set(seq, null))
      .finally(() => {
        this.asking = null;
        if (this.fetched.size > 500) this.fetched.clear();
        this.render(new Set());
      });
  }
}

async function fetchOriginal(seq: number): Promise<OriginalTick | null> {
  const response = await fetch(`api/fork/original?seq=${seq}`, { headers: token ? { Authorization: `Bearer ${token}` } : {} });
  if (response.status === 404) return null;
  if (!response.ok) throw new ApiError(`GET api/fork/original: HTTP ${response.status}`, response.status, null);
  return (await response.json()) as OriginalTick;
}
