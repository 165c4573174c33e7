/// Search the run: a query box in the timeline's toolbar (docs/queries.md). Enter sends the
/// condition as the `query` command; the intervals of ticks where it holds are marked on the
/// timeline (`TimelinePanel.markMatches`), ◀ / ▶ go to the previous / next one (from the tick in
/// view) and select its robot. A replay answers over its recording; a live session says why not.
/// The option view's "every tick in state …" fills the box and runs it (`find`).
import type { Connection } from "../connection";
import type { Session } from "../session";
import { formatClock, h } from "../ui";

/// One interval of matching ticks, as the `query` command answers it.
export interface Match {
  robot: number;
  name: string;
  first_seq: number;
  last_seq: number;
  first_t: number;
  last_t: number;
}

export class SearchControls {
  readonly element: HTMLElement;
  private readonly input: HTMLInputElement;
  private readonly status: HTMLElement;
  private matches: Match[] = [];
  /// The match last gone to (its index), for ◀ / ▶ from there.
  private current = -1;
  /// Called with the matches after each answer (the timeline draws them).
  onMatches: (matches: ReadonlyArray<Match>) => void = () => undefined;

  constructor(
    private readonly session: Session,
    private readonly connection: Connection,
  ) {
    this.input = h("input.query-input", {
      type: "search",
      placeholder: "find: striker.state == shoot && ball.distance > 500",
      "aria-label": "Find ticks where a condition holds (Enter)",
      title: "An XABSL condition over symbols, options (striker.state == shoot, kick.active), parameters; Enter finds every tick where it holds",
      spellcheck: false,
    });
    this.input.addEventListener("keydown", (ev) => {
      if (ev.key === "Enter") {
        ev.preventDefault();
        void this.run(this.input.value);
      } else if (ev.key === "Escape") {
        this.clear();
      }
    });
    this.status = h("span.muted.query-status", { "aria-live": "polite" });
    const previous = h("button.query-previous", { title: "Previous match", onclick: () => this.go(-1) }, "◀");
    const next = h("button.query-next", { title: "Next match", onclick: () => this.go(1) }, "▶");
    this.element = h("span.query", {}, this.input, previous, next, this.status);
  }

  /// Fill the box with `condition` and run it.
  find(condition: string): Promise<void> {
    this.input.value = condition;
    return this.run(condition);
  }

  clear(): void {
    this.input.value = "";
    this.matches = [];
    this.current = -1;
    this.status.textContent = "";
    this.status.classList.remove("error");
    this.onMatches(this.matches);
  }

  private async run(condition: string): Promise<void> {
    if (!condition.trim()) return this.clear();
    this.status.classList.remove("error");
    this.status.textContent = "searching…";
    try {
      const result = await this.connection.command("query", { condition });
      if (this.input.value !== condition) return; // typed on meanwhile
      this.matches = result.intervals;
      this.current = -1;
      const n = this.matches.length;
      const skipped = Object.keys(result.skipped);
      const unknown = result.unknown ? ` · ${result.unknown} unknown` : "";
      const notFor = skipped.length ? ` · not for ${skipped.join(", ")}` : "";
      this.status.textContent = `${n} match${n === 1 ? "" : "es"} (${result.matched} ticks)${unknown}${notFor}`;
      this.status.title = skipped.map((name) => `${name}: ${result.skipped[name]}`).join("\n");
      this.onMatches(this.matches);
      if (n) this.go(1);
    } catch (error) {
      this.matches = [];
      this.current = -1;
      this.onMatches(this.matches);
      this.status.classList.add("error");
      this.status.textContent = error instanceof Error ? error.message : String(error);
      this.status.title = this.status.textContent;
    }
  }

  /// Go to the next (`step` 1) or previous (-1) match from the tick in view.
  private go(step: number): void {
    const n = this.matches.length;
    if (!n) return;
    const at = this.session.view?.seq ?? -1;
    let index: number;
    if (this.current >= 0 && this.matches[this.current]?.first_seq === at) index = (this.current + step + n) % n;
    else if (step > 0) index = Math.max(0, this.matches.findIndex((m) => m.first_seq > at));
    else {
      const before = this.matches.map((m) => m.first_seq < at).lastIndexOf(true);
      index = before >= 0 ? before : n - 1;
    }
    const match = this.matches[index] as Match;
    this.current = index;
    this.session.selectRobot(match.robot);
    this.session.seekTick(match.first_t, match.first_seq);
    this.status.textContent = `${index + 1} of ${n}: ${match.name} ${formatClock(match.first_t)} – ${formatClock(match.last_t)}`;
  }
}
