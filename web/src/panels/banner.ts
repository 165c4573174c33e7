/// The problem banner under the top bar: every behavior set that has errors (or does not run on
/// this host), with the error count, whether its robots stand or the last good version keeps
/// running, and the list of errors; a click on one opens its file at its line in the editor.
/// It reads `GET /api/status` (programs) on every hello and compile event.
import { type ProgramStatus, programStatus } from "../api";
import type { Span } from "../description";
import { h } from "../ui";
import type { ServerDiagnostic } from "../xabsl/lint";

/// Errors listed per behavior set (the count says how many there are in all).
const MAX_LISTED = 50;

/// The headline of one behavior set's problems, or null when it has none.
export function problemHeadline(key: string, program: ProgramStatus): string | null {
  const errors = program.diagnostics.filter((d) => d.severity === "error").length;
  if (errors) {
    const what = `Behavior ${key} has ${errors} error${errors === 1 ? "" : "s"}`;
    return program.running
      ? `${what}: the last good version keeps running until it compiles again.`
      : `${what}: its robots stand until it compiles. The graph shows what parsed.`;
  }
  if (program.error) return `Behavior ${key} does not run here: ${program.error}`;
  return null;
}

export class ProblemBanner {
  readonly element: HTMLElement;
  private asked = 0;

  constructor(private readonly openSpan: (span: Span) => void) {
    this.element = h("div.problems", { role: "alert", "aria-label": "Behavior errors", hidden: true });
  }

  /// Ask the server again (after a hello or a compile event); the newest answer wins.
  refresh(): void {
    const ask = ++this.asked;
    programStatus()
      .then((programs) => {
        if (ask === this.asked) this.show(programs);
      })
      .catch(() => undefined);
  }

  show(programs: Record<string, ProgramStatus>): void {
    const blocks: HTMLElement[] = [];
    for (const [key, program] of Object.entries(programs)) {
      const headline = problemHeadline(key, program);
      if (!headline) continue;
      const errors = program.diagnostics.filter((d) => d.severity === "error");
      const list = h("ul.problem-list", {}, ...errors.slice(0, MAX_LISTED).map((d) => this.item(d)));
      const toggle = h("button.link", { "aria-expanded": "true" }, "hide");
      toggle.addEventListener("click", () => {
        list.hidden = !list.hidden;
        toggle.textContent = list.hidden ? `show ${errors.length}` : "hide";
        toggle.setAttribute("aria-expanded", String(!list.hidden));
      });
      blocks.push(
        h(
          "div.problem",
          { "data-program": key },
          h("div.problem-head", {}, h("strong", {}, headline), errors.length ? toggle : null),
          errors.length ? list : null,
          errors.length > MAX_LISTED ? h("div.muted", {}, `… and ${errors.length - MAX_LISTED} more`) : null,
        ),
      );
    }
    this.element.replaceChildren(...blocks);
    this.element.hidden = blocks.length === 0;
  }

  private item(d: ServerDiagnostic): HTMLElement {
    const span = d.span;
    const where = `${span?.file ?? d.file ?? "?"}:${span?.line ?? "?"}${span ? `:${span.col}` : ""}`;
    const button = h("button.link.problem-item", { title: span ? "Open in the editor" : "" }, h("code", {}, where), ` ${d.message}`);
    if (span) button.addEventListener("click", () => this.openSpan(span));
    else button.disabled = true;
    return h("li", {}, button);
  }
}
