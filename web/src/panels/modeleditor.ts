/// Editing a world's model file (a Dual Dynamics model) through the world commands `model_source`,
/// `model_check` and `model_save`: diagnostics (file, key, line, column) as you type, Ctrl+S or
/// Save writes the file atomically and hot-reloads it into the running robot when it is clean.
/// Shown only for worlds that offer these commands.
import type { Connection } from "../connection";
import { h, setText, toast } from "../ui";
import { type WorldCommand, worldCommand } from "./world";

interface ModelDiagnostic {
  message: string;
  key: string | null;
  file: string;
  span: { line: number; col: number; start: number; end: number };
}

export class ModelEditor {
  readonly element: HTMLDetailsElement;
  private readonly text: HTMLTextAreaElement;
  private readonly diagnostics: HTMLElement;
  private readonly title: HTMLElement;
  private version = "";
  private timer: ReturnType<typeof setTimeout> | null = null;

  constructor(private readonly connection: Connection) {
    this.text = h("textarea.model-text", { spellcheck: "false", "aria-label": "Model file", rows: 18 });
    this.text.addEventListener("input", () => {
      if (this.timer) clearTimeout(this.timer);
      this.timer = setTimeout(() => void this.check(), 400);
    });
    this.text.addEventListener("keydown", (ev) => {
      if ((ev.ctrlKey || ev.metaKey) && ev.key === "s") {
        ev.preventDefault();
        void this.save();
      }
    });
    this.diagnostics = h("ul.model-diagnostics", { "aria-live": "polite" });
    this.title = h("span", {}, "model");
    this.element = h(
      "details.model-editor",
      {},
      h("summary", {}, "Edit the model: ", this.title),
      h(
        "div.toolbar",
        {},
        h("button", { onclick: () => void this.save(), title: "Save and hot-reload (Ctrl+S)", "data-run": "model_save" }, "Save"),
        h("button", { onclick: () => void this.open(), title: "Load the file from disk again" }, "Reload from disk"),
      ),
      this.text,
      this.diagnostics,
    );
    this.element.addEventListener("toggle", () => {
      if (this.element.open && !this.version) void this.open();
    });
  }

  /// Show the editor only when the world offers the model commands.
  setCommands(commands: WorldCommand[]): void {
    const names = new Set(commands.map((c) => c.name));
    this.element.hidden = !["model_source", "model_check", "model_save"].every((n) => names.has(n));
  }

  async open(): Promise<void> {
    try {
      const src = await worldCommand<{ path: string; text: string; version: string }>(this.connection, "model_source");
      this.text.value = src.text;
      this.version = src.version;
      setText(this.title, src.path);
      this.show([]);
    } catch (e) {
      toast(`Model: ${(e as Error).message}`, "error");
    }
  }

  private async check(): Promise<void> {
    try {
      const result = await worldCommand<{ diagnostics: ModelDiagnostic[] }>(this.connection, "model_check", { text: this.text.value });
      this.show(result.diagnostics);
    } catch {
      /* not connected: checked again on the next edit */
    }
  }

  private async save(): Promise<void> {
    try {
      const result = await worldCommand<{ ok: boolean; reloaded: boolean; version: string; diagnostics: ModelDiagnostic[]; message?: string }>(this.connection, "model_save", {
        text: this.text.value,
        version: this.version,
      });
      this.version = result.version;
      this.show(result.diagnostics);
      if (result.ok) toast(result.reloaded ? "Model saved and hot-reloaded" : `Model saved: ${result.message ?? ""}`, result.reloaded ? "ok" : "info", 5000);
      else toast("Model saved with errors: the robot keeps running the last model that loaded", "error", 6000);
    } catch (e) {
      toast(`Model not saved: ${(e as Error).message}`, "error", 8000);
    }
  }

  private show(diagnostics: ModelDiagnostic[]): void {
    this.diagnostics.replaceChildren(
      ...diagnostics.map((d) =>
        h(
          "li.model-diagnostic",
          {},
          h(
            "button.link",
            {
              onclick: () => {
                this.text.focus();
                this.text.setSelectionRange(d.span.start, d.span.end);
              },
            },
            `${d.file}:${d.span.line}:${d.span.col}`,
          ),
          ` ${d.key ? `${d.key}: ` : ""}${d.message}`,
        ),
      ),
    );
    this.text.classList.toggle("has-errors", diagnostics.length > 0);
  }
}
