/// The top bar: robot picker, the XABSL agent the selected robot runs (any agent of its behavior
/// set, `select_agent`; a forced root is shown beside it), simulation controls (pause/resume, step, speed, reset), the game
/// clock and score, the link-health indicator, the theme switch and the keyboard help.
import type { Connection, LinkState } from "../connection";
import type { Hello } from "../protocol";
import type { Session, SessionEvent } from "../session";
import { formatClock, formatSpeed, h, SPEEDS, setText, toast } from "../ui";

/// Milliseconds without frames after which the top bar asks the server whether it is paused.
const QUIET_MS = 1500;

export class TopBar {
  readonly element: HTMLElement;
  readonly robotPicker: HTMLSelectElement;
  readonly agentPicker: HTMLSelectElement;
  private agentKey = "";
  private readonly pauseButton: HTMLButtonElement;
  private readonly speed: HTMLSelectElement;
  private readonly clock: HTMLElement;
  private readonly link: HTMLElement;
  private readonly linkText: HTMLElement;
  private linkState: LinkState = "connecting";
  private retryAt = 0;
  private paused = false;
  private finished = false;
  /// The hello whose paused state and speed were applied: panels are redrawn with "hello" on
  /// a tab switch or a resize too, and then the hello's (older) state must not win.
  private helloApplied: Hello | null = null;
  private asking = false;
  private askedAt = 0;
  private askedFrameAt = 0;
  /// The latency shown, with the wall time of the frame it is for (see `renderLink`).
  private latency: { wall: number; ms: number } | null = null;

  constructor(
    private readonly session: Session,
    private readonly connection: Connection,
    actions: { toggleTheme(): void; help(): void },
  ) {
    this.robotPicker = h("select#robot-picker", { "aria-label": "Robot", title: "Selected robot (1..9, 0)" });
    this.robotPicker.addEventListener("change", () => session.selectRobot(Number(this.robotPicker.value)));
    this.agentPicker = h("select#agent-picker", { "aria-label": "XABSL agent", title: "The XABSL agent the selected robot runs" });
    this.agentPicker.addEventListener("change", () => {
      const robot = session.selectedRobot;
      const agent = this.agentPicker.value;
      connection
        .command("select_agent", { robot, agent })
        .then(() => toast(`${session.robotInfo(robot)?.name} runs agent ${agent}`, "ok"))
        .catch((e: Error) => toast(`Agent: ${e.message}`, "error"));
      this.agentPicker.blur();
    });
    this.pauseButton = h("button#pause", { title: "Pause / resume the simulation (Space)", onclick: () => this.togglePause() }, "❚❚ Pause");
    this.speed = h("select#speed", { "aria-label": "Speed", title: "Simulation speed" }, ...SPEEDS.map((s) => h("option", { value: s }, formatSpeed(s))));
    this.speed.value = "1";
    this.speed.addEventListener("change", () => {
      connection.command("speed", { speed: Number(this.speed.value) }).catch((e: Error) => toast(`Speed: ${e.message}`, "error"));
      // hand the keys back: Space, End, arrows are the studio's again, not the dropdown's
      this.speed.blur();
    });
    this.clock = h("span.clock");
    this.linkText = h("span.link-text", {}, "connecting…");
    this.link = h(
      "button.link-health",
      { title: "Link to the server; click to reconnect now", onclick: () => connection.reconnectNow() },
      h("span.dot"),
      this.linkText,
    );
    this.element = h(
      "header.topbar",
      {},
      h("span.brand", {}, "xabsl", h("b", {}, "studio")),
      h("label.inline", {}, h("span.label-text", {}, "Robot "), this.robotPicker),
      h("label.inline", {}, h("span.label-text", {}, "Agent "), this.agentPicker),
      h(
        "div.group",
        { role: "group", "aria-label": "Simulation" },
        this.pauseButton,
        h("button#step", { title: "Run one tick while paused (.)", onclick: () => this.step() }, "▶❚ Step"),
        this.speed,
        h("button#reset", { title: "Restart the match from time 0", onclick: () => this.reset() }, "↺ Reset"),
      ),
      this.clock,
      h("span.spacer"),
      this.link,
      h("button.icon", { title: "Light / dark theme (T)", "aria-label": "toggle theme", onclick: () => actions.toggleTheme() }, "◐"),
      h("button.icon", { title: "Keyboard shortcuts (?)", "aria-label": "help", onclick: () => actions.help() }, "?"),
    );
  }

  togglePause(): void {
    const op = this.paused ? "resume" : "pause";
    this.connection
      .command(op)
      .then((r) => this.setPaused(r?.paused ?? op === "pause"))
      .catch((e: Error) => toast(`${op}: ${e.message}`, "error"));
  }

  private setPaused(paused: boolean): void {
    if (paused !== this.paused) this.askedFrameAt = this.connection.lastFrameAt;
    this.paused = paused;
    this.pauseButton.textContent = paused ? "▶ Resume" : "❚❚ Pause";
    this.pauseButton.classList.toggle("on", paused);
  }

  step(): void {
    if (!this.paused) {
      this.connection
        .command("pause")
        .then(() => this.setPaused(true))
        .catch((e: Error) => toast(`pause: ${e.message}`, "error"));
      return;
    }
    this.connection.command("step", { ticks: 1 }).catch((e: Error) => toast(`step: ${e.message}`, "error"));
  }

  private reset(): void {
    if (!window.confirm("Restart the match from time 0? Forces and overrides are cleared.")) return;
    this.connection.command("reset").catch((e: Error) => toast(`reset: ${e.message}`, "error"));
  }

  setLink(state: LinkState, detail: { retryInMs?: number; code?: number; attempt: number }): void {
    this.linkState = state;
    this.retryAt = state === "waiting" ? performance.now() + (detail.retryInMs ?? 0) : 0;
    this.link.dataset.state = state;
  }

  render(changes: Set<SessionEvent>): void {
    const session = this.session;
    if (changes.has("hello")) {
      const info = session.hello?.session;
      if (info && session.hello !== this.helloApplied) {
        this.helloApplied = session.hello;
        this.setPaused(!!info.paused);
        this.setSpeed(info.speed);
      }
      this.robotPicker.replaceChildren(
        ...session.robots.map((a, i) => h("option", { value: a.id }, `${i < 10 ? `${(i + 1) % 10} · ` : ""}${a.name}${!a.program ? " (no engine)" : a.engine === false ? " (stands: errors)" : ""}`)),
      );
    }
    if (this.robotPicker.value !== String(session.selectedRobot)) this.robotPicker.value = String(session.selectedRobot);
    this.renderAgent(changes);
    // The tick in view (the timeline's cursor, else the newest): in a replay the newest frame is
    // only where the server's playback stands, so the clock and the score follow what is shown.
    const tick = session.view;
    const status = tick?.status;
    const parts: string[] = [];
    if (status?.score && status.teams) parts.push(`${status.teams[0]} ${status.score[0]} : ${status.score[1]} ${status.teams[1]}`);
    if (status?.game_state) parts.push(status.game_state);
    if (tick) parts.push(formatClock(tick.t));
    setText(this.clock, parts.join(" · "));
    this.renderLink();
  }

  /// The agent picker: the agents of the selected robot's behavior set, the one whose root option
  /// the robot runs selected; while a root is forced, a "forced: name" entry says so.
  private renderAgent(changes: Set<SessionEvent>): void {
    const session = this.session;
    const index = session.indexOf(session.selectedRobot);
    const key = `${session.hello?.generation ?? -1}|${session.selectedRobot}`;
    if (key !== this.agentKey || changes.has("hello")) {
      this.agentKey = key;
      const agents = index?.description.agents ?? [];
      this.agentPicker.replaceChildren(
        ...agents.map((a) => h("option", { value: a.name, title: `${a.title ?? a.name}: root option ${a.root}` }, a.name)),
      );
      this.agentPicker.disabled = agents.length === 0 || session.robotInfo(session.selectedRobot)?.engine === false;
    }
    if (!index || document.activeElement === this.agentPicker) return;
    const robot = session.robotInView();
    const root = robot?.path[0];
    const forced = robot?.forced;
    let shown = "";
    if (forced) {
      const name = forced[0] === 0 ? index.optionById.get(forced[1])?.name : index.behaviorById.get(forced[1])?.name;
      shown = `forced: ${name ?? "?"}`;
    } else if (root?.kind === "option") {
      const rootName = index.optionById.get(root.option)?.name;
      shown = index.description.agents.find((a) => a.root === rootName)?.name ?? "";
    }
    let entry = this.agentPicker.querySelector<HTMLOptionElement>("option.forced");
    if (shown.startsWith("forced: ")) {
      if (!entry) {
        entry = h("option.forced", { disabled: true });
        this.agentPicker.append(entry);
      }
      entry.value = shown;
      setText(entry, shown);
    } else entry?.remove();
    if (shown && this.agentPicker.value !== shown) this.agentPicker.value = shown;
  }

  private setSpeed(speed: number): void {
    if (![...this.speed.options].some((o) => o.value === String(speed))) this.speed.append(h("option", { value: speed }, formatSpeed(speed)));
    this.speed.value = String(speed);
  }

  /// Frames say nothing about pausing: when they stop although we think the match runs, or
  /// come although we think it is paused (another client paused or resumed), ask the server.
  private checkPaused(): void {
    const c = this.connection;
    const now = performance.now();
    if (this.asking || this.linkState !== "live" || !c.lastFrameAt || now - this.askedAt < QUIET_MS) return;
    const quiet = !this.paused && now - c.lastFrameAt > QUIET_MS;
    const moving = this.paused && c.lastFrameAt > this.askedFrameAt;
    if (!quiet && !moving) return;
    this.asking = true;
    this.askedAt = now;
    this.askedFrameAt = c.lastFrameAt;
    c.command("status")
      .then((reply) => {
        const status = reply as { paused?: boolean; speed: number; finished?: boolean };
        this.finished = !!status.finished;
        this.setPaused(!!status.paused);
        this.setSpeed(status.speed);
      })
      .catch(() => undefined)
      .finally(() => {
        this.asking = false;
      });
  }

  /// The link indicator: live with frame rate and latency, stale, or reconnecting in N s.
  /// `drawn`: a frame was drawn just now. Between frames (the render loop calls this on every
  /// display refresh, twice as often as frames come) the latency of the frame shown stays as it
  /// was when drawn: a number growing until the next frame would change the bar's text, and with
  /// it layout and paint, on every refresh for nothing one could read.
  renderLink(drawn = true): void {
    const c = this.connection;
    let text: string;
    let state: string = this.linkState;
    this.checkPaused();
    if (this.linkState === "live" && this.session.replay) {
      // a recording is never live: connected, it is a replay (paused, or playing it back)
      text = this.paused ? "replay · paused" : "replay";
    } else if (this.linkState === "live") {
      const age = performance.now() - c.lastFrameAt;
      if (this.paused) text = "live · paused";
      else if (this.finished && age > 2000) text = "live · match over";
      else if (c.lastFrameAt && age > 2000) {
        text = `no frames for ${Math.round(age / 1000)} s`;
        state = "stale";
      } else {
        const wall = this.session.live?.wall;
        const latency = wall ? this.latencyOf(wall, drawn) : null;
        text = `live · ${c.framesPerSecond} fps${latency !== null && latency < 60000 ? ` · ${Math.round(latency)} ms` : ""}`;
      }
    } else if (this.linkState === "waiting") {
      const s = Math.max(0, (this.retryAt - performance.now()) / 1000);
      text = `offline · retry in ${s.toFixed(1)} s`;
    } else text = "connecting…";
    if (this.link.dataset.state !== state) this.link.dataset.state = state;
    setText(this.linkText, text);
  }

  /// How late the frame of wall time `wall` is shown (ms): measured when it is drawn, kept until
  /// the next one.
  private latencyOf(wall: number, drawn: boolean): number {
    if (drawn || this.latency?.wall !== wall) this.latency = { wall, ms: Math.max(0, Date.now() - wall) };
    return this.latency.ms;
  }
}
