/// xabsl studio: wires the session, the connection and the panels, and runs the render loop.
///
/// Messages only update the session; one requestAnimationFrame loop draws the tick in view
/// (the newest, or the one under the timeline cursor) in every visible panel, so a burst of
/// frames costs one draw and a hidden panel costs nothing.
import "./style.css";
import { clearGraphCache, websocketUrl } from "./api";
import { Connection } from "./connection";
import { Layout } from "./layout";
import { ActivationPanel } from "./panels/activation";
import { EditorPanel } from "./panels/editor";
import { FieldPanel } from "./panels/field";
import { GraphPanel } from "./panels/graph";
import { CoveragePanel } from "./panels/coverage";
import { OptionView } from "./panels/optionview";
import { PlotPanel } from "./panels/plot";
import { SymbolsPanel } from "./panels/symbols";
import { TeamStrip } from "./panels/teamstrip";
import { AttachBar } from "./panels/attach";
import { TesterPanel } from "./panels/tester";
import { SearchControls } from "./panels/search";
import { TimelinePanel } from "./panels/timeline";
import { ForkControls } from "./panels/fork";
import { forkable, loadReplay, replayOf } from "./replay";
import { CompareView } from "./panels/compare";
import { Recordings } from "./recordings";
import { TopBar } from "./panels/topbar";
import { DynamicsPanel } from "./panels/dynamics";
import { FactsPanel } from "./panels/facts";
import { PlanPanel } from "./panels/plan";
import { panelsOf } from "./panels/world";
import { ProblemBanner } from "./panels/banner";
import { Session, type SessionEvent } from "./session";
import { h, isTyping, toast } from "./ui";

/// The server's ring buffer holds 120 s; the page keeps as much (every generation in it).
const HISTORY_MS = 120_000;

function main(): void {
  const app = document.getElementById("app") as HTMLElement;
  const session = new Session();
  const layout = new Layout(app);

  const connection = new Connection(
    { url: websocketUrl(), rate: 30 },
    {
      hello: (hello) => {
        if (hello.reason !== "connect" && hello.reason !== "resync") clearGraphCache();
        session.applyHello(hello);
        problems.refresh();
        void optionView.breakpoints.refresh();
        // Fill the timeline with what the server buffered before we came (or before a reload);
        // a replay: with the whole recording.
        const t = hello.session.t + (hello.session.offset ?? 0); // timeline time
        // After a reload or reset the buffer holds the earlier ticks already: fetch only the gap.
        const from = hello.reason === "connect" ? t - HISTORY_MS : Math.min(t, session.buffer.newest?.x ?? t - HISTORY_MS);
        void connection
          .command("status", {})
          .then((status) => {
            recordings.setReplay(forkable(status as Record<string, unknown>));
            return replayOf(status as Record<string, unknown>);
          })
          .catch(() => null)
          .then((replay) =>
            replay
              ? loadReplay(connection, session, replay)
              : connection.historyOf(Math.max(0, from), t, 1).then((h) => session.applyHistory(h.frames, h.generations)),
          )
          .catch(() => undefined);
      },
      frame: (frame) => session.applyFrame(frame),
      event: (event) => {
        if (event.event === "file") editor.fileEvent(event);
        else if (event.event === "compile") {
          editor.compileEvent(event);
          problems.refresh();
        } else if (event.event === "breakpoint") {
          optionView.breakpoints.onHit(event);
          center.activate("option");
        } else if (event.event === "crash")
          toast(`The simulation stopped: ${event.message}. Reset (top bar) starts it again.`, "error", 15000);
      },
      link: (state, detail) => topbar.setLink(state, detail),
    },
  );

  // ------------------------------------------------------------------------------- panels
  const openOption = (id: number): void => {
    session.openOptionById(id);
    center.activate("option");
  };
  const openBehavior = (id: number): void => {
    const b = session.indexOf(session.selectedRobot)?.behaviorById.get(id);
    if (b) {
      tester.choose({ kind: "behavior", name: b.name });
      right.activate("test");
    }
  };
  const help = h(
    "dialog#help",
    {},
    h("h2", {}, "xabsl studio"),
    h(
      "p",
      {},
      "Watch a team play, see which options and states each robot runs and why, edit the behavior and save to hot-reload it, and run any option by hand.",
    ),
    h(
      "table",
      {},
      ...[
        ["1 … 9, 0", "select robot"],
        ["Space", "pause / resume"],
        [".", "step one tick (pauses first)"],
        ["← →  (in the timeline)", "step back / forward in time"],
        ["L  or  End", "back to live (End also from a dropdown)"],
        ["Run from here (timeline)", "restart the world at the cursor's tick with the current behavior"],
        ["G / O", "option graph / option view"],
        ["E", "editor, at the option shown in the option view"],
        ["Esc then Tab (in the editor)", "move the focus out of the editor"],
        ["D / P / F", "dual dynamics / plan / facts (worlds that have them)"],
        ["A / S / X", "activation tree / symbols / test panel"],
        ["/", "find an option or a state (Enter: jump, Shift+Enter: open)"],
        ["J", "jump to the active option"],
        ["W", "why did the option decide this?"],
        ["Ctrl+S", "save the file: compile and hot reload"],
        ["F12, Ctrl+click", "go to definition"],
        ["Shift+F12", "find references"],
        ["T", "light / dark theme"],
        ["?", "this help"],
      ].map(([k, v]) => h("tr", {}, h("td", {}, h("kbd", {}, k as string)), h("td", {}, v as string))),
    ),
    h("form", { method: "dialog" }, h("button.primary", {}, "Close")),
  );
  document.body.append(help);

  const topbar = new TopBar(session, connection, { toggleTheme: () => layout.toggleTheme(), help: () => help.showModal() });
  const field = new FieldPanel(session);
  const team = new TeamStrip(session);
  // Attached hosts and Connect… (xabsl attach only; hidden otherwise), under the top bar's controls
  const attachBar = new AttachBar(session, connection);
  topbar.element.append(attachBar.element);
  // Find in the graph jumps to a state by opening its option at that state.
  const graph = new GraphPanel(session, openOption, openBehavior, (option, state) => {
    openOption(option);
    optionView.reveal(state);
  });
  const plot = new PlotPanel(session);
  const editor = new EditorPanel(session);
  const tester = new TesterPanel(session, connection);
  const optionView = new OptionView(session, connection, {
    edit: (option) => {
      center.activate("editor");
      if (option.span) editor.openSpan(option.span);
    },
    test: (option) => {
      tester.choose({ kind: "option", name: option.name });
      right.activate("test");
    },
    find: (option, state) => void search.find(`${option.name}.state == ${state}`),
  });
  const problems = new ProblemBanner((span) => {
    center.activate("editor");
    editor.openSpan(span);
  });
  const activation = new ActivationPanel(session, openOption);
  const symbols = new SymbolsPanel(session, connection, plot);
  const timeline = new TimelinePanel(session, openOption);
  // Search the run (a query): in the timeline's toolbar, its matches marked on the timeline.
  const search = new SearchControls(session, connection);
  timeline.toolbar.append(search.element);
  search.onMatches = (matches) => {
    timeline.markMatches(matches);
    pending.add("cursor"); // paused: no tick follows that would redraw
  };
  const fork = new ForkControls(session, connection);
  timeline.toolbar.append(fork.button, fork.badge);
  activation.element.firstElementChild?.after(fork.original, fork.divergence);
  fork.onDivergence = (divergence) => {
    timeline.markDivergence(divergence);
    pending.add("cursor"); // paused: no tick follows that would redraw
  };
  // Recordings (a dialog, opens a replay in a new tab) and, in a replay, "Run from here" at the
  // tick in view: in the timeline's toolbar, beside the history they are about.
  const recordings = new Recordings(session);
  timeline.element.querySelector(".toolbar")?.append(recordings.button);
  // Compare versions (a dialog): beside the recordings; a reload mark's dialog opens it too.
  const compare = new CompareView(() => [...session.programs.keys()]);
  timeline.element.querySelector(".toolbar")?.append(compare.button);
  timeline.changes.onStructure = (gen) => void compare.showGeneration(gen);
  compare.onDivergence = (divergence) => {
    timeline.markDivergence(divergence);
    pending.add("cursor"); // paused: no tick follows that would redraw
  };
  optionView.breakpoints.onHitsChanged = () => {
    timeline.markHits(optionView.breakpoints.hits);
    pending.add("cursor"); // paused: no tick follows that would redraw
  };
  const coverage = new CoveragePanel(session, graph, () => ({ option: optionView.current(), element: optionView.element }));
  // Panels of worlds that announce them in their static scene (`panels`, see panels/world.ts).
  const dynamics = new DynamicsPanel(session, connection);
  const plan = new PlanPanel(session, connection);
  const facts = new FactsPanel(session, connection);

  const rerender = new Set<SessionEvent>(["hello", "select", "cursor", "option", "history"]);
  const forceAll = (): void => {
    for (const e of rerender) pending.add(e);
  };
  const center = layout.tabs(
    "center",
    [
      { name: "graph", label: "Option graph", key: "G", pane: graph.element },
      { name: "option", label: "Option", key: "O", pane: optionView.element },
      { name: "editor", label: "Editor", key: "E", pane: editor.element },
      { name: "dynamics", label: "Dynamics", key: "D", pane: dynamics.element },
      { name: "plan", label: "Plan", key: "P", pane: plan.element },
      { name: "facts", label: "Facts", key: "F", pane: facts.element },
    ],
    forceAll,
  );
  const worldPanels = (): void => {
    const announced = panelsOf(session.scene);
    for (const name of ["dynamics", "plan", "facts"]) center.setAvailable(name, announced.includes(name));
  };
  const right = layout.tabs(
    "right",
    [
      { name: "activation", label: "Activation", key: "A", pane: activation.element },
      { name: "symbols", label: "Symbols", key: "S", pane: symbols.element },
      { name: "test", label: "Test", key: "X", pane: tester.element },
      { name: "coverage", label: "Coverage", pane: coverage.element },
    ],
    forceAll,
  );

  const HINT_KEY = "xabsl-studio.hint-dismissed";
  const hint = h(
    "div.hint",
    { role: "note" },
    h("strong", {}, "Start here: "),
    "click a robot (or press 1–9) · the graph lights up what it runs · click an option to see ",
    h("em", {}, "why"),
    " it decided · E edits, Ctrl+S hot-reloads · X runs an option by hand · drag the timeline to go back, L for live · ? for all keys",
    h("button.icon", { title: "Hide this hint", "aria-label": "hide hint", onclick: () => { hint.remove(); localStorage.setItem(HINT_KEY, "1"); } }, "×"),
  );
  // The notices row under the top bar: the problem banner, then the first-visit hint.
  const notices = h("div.notices", {}, problems.element);
  app.append(
    topbar.element,
    notices,
    h(
      "main.workspace",
      {},
      h("section.region.left", { "aria-label": "Field and team" }, h("div.field-wrap", {}, field.element), layout.splitter("field", "horizontal", 1, 120, 1200), team.element),
      layout.splitter("left", "vertical", 1, 200, 1400),
      h("section.region.center", { "aria-label": "Graphs and editor" }, center.element),
      layout.splitter("right", "vertical", -1, 220, 1200),
      h("section.region.right", { "aria-label": "Activation, symbols and test" }, right.element),
    ),
    layout.splitter("bottom", "horizontal", -1, 60, 900),
    h(
      "section.region.bottom",
      { "aria-label": "Timeline and plot" },
      timeline.element,
      layout.splitter("plot", "vertical", -1, 160, 1600),
      plot.element,
    ),
  );

  if (!localStorage.getItem(HINT_KEY)) notices.append(hint);

  // -------------------------------------------------------------------------- render loop
  const pending = new Set<SessionEvent>();
  let frameCount = 0;
  let frameWindowStart = performance.now();
  const loop = (): void => {
    for (const e of session.takeChanges()) pending.add(e);
    if (pending.size) {
      const changes = new Set(pending);
      pending.clear();
      const started = performance.now();
      topbar.render(changes);
      field.render(changes);
      team.render(changes);
      attachBar.render(changes);
      if (center.isActive("graph")) graph.render(changes);
      if (center.isActive("option")) optionView.render(changes);
      if (center.isActive("editor")) editor.render(changes);
      if (changes.has("hello")) worldPanels();
      if (center.isActive("dynamics") || changes.has("hello")) dynamics.render(changes);
      if (center.isActive("plan") || changes.has("hello")) plan.render(changes);
      if (center.isActive("facts") || changes.has("hello")) facts.render(changes);
      if (right.isActive("activation")) activation.render(changes);
      if (right.isActive("symbols")) symbols.render(changes);
      if (right.isActive("test")) tester.render(changes);
      if (right.isActive("coverage")) coverage.render(changes);
      fork.render(changes);
      timeline.render(changes);
      plot.render(changes);
      stats.renderMs = stats.renderMs * 0.9 + (performance.now() - started) * 0.1;
      frameCount++;
    } else {
      topbar.renderLink(false); // no frame drawn: the link's state and countdowns only
    }
    const now = performance.now();
    if (now - frameWindowStart >= 1000) {
      stats.drawsPerSecond = (frameCount * 1000) / (now - frameWindowStart);
      frameCount = 0;
      frameWindowStart = now;
    }
    requestAnimationFrame(loop);
  };
  const stats = { renderMs: 0, drawsPerSecond: 0 };
  // For e2e tests and curious users: how fast the UI draws.
  (window as unknown as { xabslStudio: unknown }).xabslStudio = { session, connection, stats, field, problems, plot, timeline, editor, recordings, search };
  layout.onResize(forceAll);
  window.addEventListener("resize", forceAll);

  // ------------------------------------------------------------------------------ keyboard
  document.addEventListener("keydown", (ev) => {
    if (ev.ctrlKey || ev.metaKey || ev.altKey) return;
    if (isTyping(ev)) {
      const target = ev.target as HTMLElement;
      // A dropdown keeps its arrows and letters, but End is "back to live" there too (natively
      // it would pick the last choice: 20x in the speed dropdown).
      if (target.tagName === "SELECT" && (ev.key === "End" || ev.key === "Escape")) {
        target.blur();
        if (ev.key === "End") session.setCursor(null);
        ev.preventDefault();
      } else if (ev.key === "Escape" && !target.closest(".cm-editor")) target.blur();
      // In the editor Escape belongs to CodeMirror (closing completion, search, the lint panel);
      // focus stays, so the next letters are text. Escape then Tab moves focus on.
      return;
    }
    const key = ev.key;
    const robots = session.robots;
    if (/^[0-9]$/.test(key)) {
      const i = key === "0" ? 9 : Number(key) - 1;
      const robot = robots[i];
      if (robot) session.selectRobot(robot.id);
    } else if (key === " ") topbar.togglePause();
    else if (key === ".") topbar.step();
    else if (key === "l" || key === "L" || key === "End") session.setCursor(null);
    else if (key === "g") center.activate("graph");
    else if (key === "o") center.activate("option");
    else if (key === "e") {
      // E opens the file of the option shown in the option view, at its declaration; in the
      // editor already it only gives the focus back to the text.
      const option = center.isActive("editor") ? null : optionView.current();
      center.activate("editor");
      if (option?.span) editor.openSpan(option.span);
      else editor.editorView.focus();
    }
    else if (key === "a") right.activate("activation");
    else if (key === "s") {
      right.activate("symbols");
      symbols.search.focus();
    } else if (key === "x") right.activate("test");
    else if (key === "/") {
      center.activate("graph");
      graph.search.focus();
    } else if (key === "j") {
      center.activate("graph");
      graph.jump();
    } else if (key === "w") {
      center.activate("option");
    } else if ((key === "d" || key === "p" || key === "f") && center.isAvailable({ d: "dynamics", p: "plan", f: "facts" }[key])) {
      center.activate({ d: "dynamics", p: "plan", f: "facts" }[key]);
    } else if (key === "t") layout.toggleTheme();
    else if (key === "?") help.showModal();
    else if (key === "ArrowLeft" && !session.isLive) session.stepCursor(-1);
    else if (key === "ArrowRight" && !session.isLive) session.stepCursor(1);
    else return;
    ev.preventDefault();
  });

  worldPanels(); // none until a world announces them (a remembered world tab falls back)
  connection.start();
  forceAll();
  requestAnimationFrame(loop);
}

main();
