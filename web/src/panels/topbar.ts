/// The top bar: robot picker, simulation controls (pause/resume, step, speed, reset), the game
/// clock and score, the link-health indicator, the theme switch and the keyboard help.
import type { Connection, LinkState } from "../connection";
import type { Session, SessionEvent } from "../session";
import { formatMs, h, setText, toast } from "../ui";

export class TopBar {
  readonly element: HTMLElement;
  readonly robotPicker: HTMLSelectElement;
  private readonly pauseButton: HTMLButtonElement;
  private readonly speed: HTMLSelectElement;
  private readonly clock: HTMLElement;
  private readonly link: HTMLElement;
  private readonly linkText: HTMLElement;
  private linkState: LinkState = "connecting";
  private retryAt = 0;
  private paused = false;

  constructor(
    private readonly session: Session,
    private readonly connection: Connection,
    actions: { toggleTheme(): void; help(): void },
  ) {
    this.robotPicker = h("select#robot-picker", { "aria-label": "Robot", title: "Selected robot (1..9, 0)" });
    this.robotPicker.addEventListener("change", () => session.selectRobot(Number(this.robotPicker.value)));
    this.pauseButton = h("button#pause", { title: "Pause / resume the simulation (Space)", onclick: () => this.togglePause() }, "❚❚ Pause");
    this.speed = h("select#speed", { "aria-label": "Speed", title: "Simulation speed" }, ...[0.25, 0.5, 1, 2, 4].map((s) => h("option", { value: s }, `${s}×`)));
    this.speed.value = "1";
    this.speed.addEventListener("change", () => {
      connection.command("speed", { speed: Number(this.speed.value) }).catch((e: Error) => toast(`Speed: ${e.message}`, "error"));
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
      h("label.inline", {}, "Robot ", this.robotPicker),
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
      if (info) {
        this.setPaused(!!info.paused);
        this.speed.value = String(info.speed);
        if (this.speed.value !== String(info.speed)) {
          this.speed.append(h("option", { value: info.speed }, `${info.speed}×`));
          this.speed.value = String(info.speed);
        }
      }
      this.robotPicker.replaceChildren(
        ...session.robots.map((a, i) => h("option", { value: a.id }, `${i < 10 ? `${(i + 1) % 10} · ` : ""}${a.name}${a.program ? "" : " (no engine)"}`)),
      );
    }
    if (this.robotPicker.value !== String(session.selectedRobot)) this.robotPicker.value = String(session.selectedRobot);
    const tick = session.live;
    const status = tick?.status;
    const parts: string[] = [];
    if (status?.score && status.teams) parts.push(`${status.teams[0]} ${status.score[0]} : ${status.score[1]} ${status.teams[1]}`);
    if (status?.game_state) parts.push(status.game_state);
    if (tick) parts.push(formatMs(tick.t));
    setText(this.clock, parts.join(" · "));
    this.renderLink();
  }

  /// The link indicator: live with frame rate and latency, stale, or reconnecting in N s.
  renderLink(): void {
    const c = this.connection;
    let text: string;
    let state: string = this.linkState;
    if (this.linkState === "live") {
      const age = performance.now() - c.lastFrameAt;
      if (this.paused) text = "live · paused";
      else if (c.lastFrameAt && age > 2000) {
        text = `no frames for ${Math.round(age / 1000)} s`;
        state = "stale";
      } else {
        const wall = this.session.live?.wall;
        const latency = wall ? Math.max(0, Date.now() - wall) : null;
        text = `live · ${c.framesPerSecond} fps${latency !== null && latency < 60000 ? ` · ${Math.round(latency)} ms` : ""}`;
      }
    } else if (this.linkState === "waiting") {
      const s = Math.max(0, (this.retryAt - performance.now()) / 1000);
      text = `offline · retry in ${s.toFixed(1)} s`;
    } else text = "connecting…";
    this.link.dataset.state = state;
    setText(this.linkText, text);
  }
}
