/// The plan panel: the GRAPHPLAN plan as columns of layers (the operators of one layer may run in
/// any order, side by side), the current operator, the done and failed ones, the running
/// operator's time against its timeout, every replan as a new version with its reason, the
/// planning graph's level table on demand, and the world's commands to intervene (perturb the
/// world, force an operator, replan, set a fact). Shows the moment in view: the version, done
/// marks and current operator of that tick.
import "./world.css";
import type { Connection } from "../connection";
import type { Session, SessionEvent } from "../session";
import { h, setText, toast } from "../ui";
import { commandForms, commandsOf, type DDScene, seconds, worldCommand } from "./world";

export interface PlanVersion {
  version: number;
  t: number;
  reason: string;
  kind: string;
  detail: string;
  layers: string[][];
  dropped: string[];
  solved: boolean;
  failed: Record<string, string>;
  done: string[];
  current: boolean;
}

interface PlanStatsRun {
  solved: boolean;
  reason: string;
  text: string;
  levels: Array<Record<string, number | string | boolean>>;
}

export class PlanPanel {
  readonly element: HTMLElement;
  private readonly status: HTMLElement;
  private readonly timer: HTMLElement;
  private readonly graph: HTMLElement;
  private readonly versionsList: HTMLElement;
  private readonly stats: HTMLElement;
  private readonly intervene: HTMLElement;
  private versions: PlanVersion[] = [];
  private interventions: Array<{ t: number; what: string }> = [];
  private seenInterventions = -1;
  private fetched = -1;
  private fetching = false;
  /// The version picked by the user (null: the one in force at the moment in view).
  private picked: number | null = null;
  private drawnKey = "";
  private generation = -1;

  constructor(
    private readonly session: Session,
    private readonly connection: Connection,
  ) {
    this.status = h("span.plan-status");
    this.timer = h("span.plan-timer");
    this.graph = h("div.plan-graph", { "aria-label": "Plan layers" });
    this.versionsList = h("ol.plan-versions", { "aria-label": "Plan versions" });
    this.stats = h("div.plan-stats", { hidden: true });
    this.intervene = h("div.plan-intervene");
    const statsButton = h("button", { title: "The planning graph's levels (xabsl plan --stats)", onclick: () => void this.toggleStats() }, "Planning graph");
    this.element = h(
      "div.panel.plan-panel",
      {},
      h("div.toolbar", {}, h("strong", {}, "Plan"), this.status, this.timer, statsButton),
      h(
        "div.plan-body",
        {},
        this.graph,
        this.stats,
        h("div.dd-title", {}, "versions (every replan, with its reason) and interventions by hand"),
        this.versionsList,
        h("div.dd-title", {}, "intervene"),
        this.intervene,
      ),
    );
  }

  render(changes: Set<SessionEvent>): void {
    const gen = this.session.hello?.generation ?? -1;
    if (changes.has("hello") && gen !== this.generation) {
      this.generation = gen;
      this.fetched = -1;
      this.picked = null;
      this.intervene.replaceChildren(commandForms(this.connection, commandsOf(this.session.scene), ["perturb", "monitor"], () => void this.fetch()));
    }
    if (this.element.closest("[hidden]")) return;
    const live = this.session.live?.scene as DDScene | null | undefined;
    const interventions = (live as { interventions?: number } | null | undefined)?.interventions ?? 0;
    if ((live?.plan_version !== undefined && live.plan_version !== this.fetched) || interventions !== this.seenInterventions) {
      this.seenInterventions = interventions;
      void this.fetch();
    }
    this.draw();
  }

  private async fetch(): Promise<void> {
    if (this.fetching) return;
    this.fetching = true;
    try {
      const want = (this.session.live?.scene as DDScene | null | undefined)?.plan_version ?? 0;
      const result = await worldCommand<{ versions: PlanVersion[]; interventions?: Array<{ t: number; what: string }> }>(this.connection, "plan");
      this.versions = result.versions;
      this.interventions = result.interventions ?? [];
      this.fetched = Math.max(want, this.versions.length);
      this.drawnKey = "";
      this.draw();
    } catch {
      /* not connected right now: the next frame asks again */
    } finally {
      this.fetching = false;
    }
  }

  private async toggleStats(): Promise<void> {
    if (!this.stats.hidden) {
      this.stats.hidden = true;
      return;
    }
    const version = this.shownVersion()?.version ?? -1;
    try {
      const result = await worldCommand<{ version: number; runs: PlanStatsRun[] }>(this.connection, "plan_stats", { version });
      this.stats.replaceChildren(
        h("div.dd-title", {}, `planning graph of version ${result.version}`),
        ...result.runs.map((run) => h("div", {}, h("pre.plan-stats-table", {}, run.text), h("div.muted", {}, run.solved ? "solved" : `no plan: ${run.reason}`))),
      );
      this.stats.hidden = false;
    } catch (e) {
      toast(`Planning graph: ${(e as Error).message}`, "error");
    }
  }

  private shownVersion(): PlanVersion | null {
    const scene = this.session.view?.scene as DDScene | null | undefined;
    const number = this.picked ?? scene?.plan_version ?? this.versions.length;
    return this.versions[number - 1] ?? null;
  }

  private draw(): void {
    const scene = this.session.view?.scene as DDScene | null | undefined;
    const tickT = this.session.view?.t ?? 0;
    setText(this.status, scene ? `${scene.plan_status ?? ""} · ${scene.op ?? "no operator"}${scene.forced_op ? " (forced)" : ""}` : "");
    this.status.dataset.status = scene?.plan_status ?? "";
    if (scene?.op && scene.op_since !== undefined) {
      const elapsed = Math.max(0, tickT - scene.op_since);
      setText(this.timer, scene.op_timeout ? `${seconds(elapsed)} of ${seconds(scene.op_timeout)} timeout` : seconds(elapsed));
      this.timer.style.setProperty("--elapsed", scene.op_timeout ? `${Math.min(100, (100 * elapsed) / scene.op_timeout)}%` : "0%");
    } else setText(this.timer, "");
    const shown = this.shownVersion();
    const viewedVersion = scene?.plan_version ?? 0;
    const done = new Set(shown && shown.version === viewedVersion ? (scene?.done ?? []) : (shown?.done ?? []));
    const key = JSON.stringify([shown?.version, [...done], scene?.op, this.versions.length, viewedVersion, this.picked, this.interventions.length]);
    if (key === this.drawnKey) return;
    this.drawnKey = key;
    if (!shown) {
      this.graph.replaceChildren(h("div.empty", {}, this.versions.length ? "no plan at this moment" : "no plan yet"));
    } else if (!shown.layers.length) {
      this.graph.replaceChildren(h("div.empty.plan-none", {}, `no plan: ${shown.detail}`));
    } else {
      const current = shown.version === viewedVersion ? scene?.op : null;
      const columns = shown.layers.map((layer, i) =>
        h(
          "div.plan-layer",
          { "data-layer": i + 1 },
          h("div.plan-layer-title", {}, `step ${i + 1}`),
          ...layer.map((op) => {
            const state = shown.failed[op] ? "failed" : op === current ? "current" : done.has(op) ? "done" : "pending";
            return h("div.plan-op", { class: `plan-op ${state}`, "data-op": op, "data-state": state, title: shown.failed[op] ? `failed: ${shown.failed[op]}` : state }, op, shown.failed[op] ? h("span.plan-op-why", {}, shown.failed[op]) : null);
          }),
        ),
      );
      this.graph.replaceChildren(
        h("div.plan-head", {}, `version ${shown.version} · ${shown.kind} at ${seconds(shown.t)} (${shown.reason})${shown.dropped.length ? ` · left out: ${shown.dropped.join(", ")}` : ""}`),
        h("div.plan-layers", {}, ...columns),
      );
    }
    const items: Array<[number, HTMLElement]> = this.interventions.map((i) => [
      i.t,
      h("li.plan-intervention", { "data-t": i.t }, h("button.link", { title: "Go to this moment", onclick: () => this.session.seekTick(i.t) }, seconds(i.t)), ` by hand: ${i.what}`),
    ]);
    for (const v of this.versions) {
      items.push([
        v.t,
        h(
          "li.plan-version",
          { class: `plan-version${v === shown ? " shown" : ""}`, "data-version": v.version },
          h("button.link", { title: "Show this version", onclick: () => { this.picked = v.version === this.picked ? null : v.version; this.drawnKey = ""; this.draw(); } }, `v${v.version}`),
          " ",
          h("button.link", { title: "Go to this moment", onclick: () => this.session.seekTick(v.t) }, seconds(v.t)),
          ` ${v.kind} (${v.reason}): ${v.detail}`,
        ),
      ]);
    }
    // Chronological; a version and an intervention at the same moment: the intervention first.
    items.sort((a, b) => a[0] - b[0] || (a[1].classList.contains("plan-intervention") ? -1 : 1));
    this.versionsList.replaceChildren(...items.map(([, el]) => el));
  }
}
