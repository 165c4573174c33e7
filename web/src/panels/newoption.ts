/// The New option dialog: name, doc line, parameters (type, range, unit), the folder and the
/// behavior set (agents file). It shows the new file and the diff of the agents file before
/// anything is written; Create writes the option file (POST), then the agents file with its
/// include line (PUT with the version previewed: the server writes atomically and refuses when the
/// file changed since), and opens the new file in the editor.
import { createFile, type FileEntry, listFiles, readFile, writeFile } from "../api";
import { addInclude, insertionDiff, type NewOption, type NewParam, optionSource, problems } from "../newoption";
import type { Session } from "../session";
import { h, toast } from "../ui";

interface Row {
  element: HTMLElement;
  read(): NewParam;
}

export class NewOptionDialog {
  readonly element: HTMLDialogElement;
  private readonly name: HTMLInputElement;
  private readonly doc: HTMLInputElement;
  private readonly params: HTMLElement;
  private readonly folder: HTMLSelectElement;
  private readonly agents: HTMLSelectElement;
  private readonly problemsList: HTMLElement;
  private readonly source: HTMLElement;
  private readonly diff: HTMLElement;
  private readonly create: HTMLButtonElement;
  private rows: Row[] = [];
  private files: FileEntry[] = [];
  /// The agents file as previewed: path, text and version (what Create writes against).
  private agentsFile: { path: string; text: string; version: string } | null = null;
  private previewed: { path: string; text: string } | null = null;
  /// The option file this dialog created already (when writing the agents file failed).
  private created: string | null = null;

  constructor(
    private readonly session: Session,
    private readonly opened: (path: string) => Promise<void>,
  ) {
    const update = (): void => this.preview();
    this.name = h("input", { type: "text", "aria-label": "Option name", placeholder: "turn_to_ball", oninput: update, spellcheck: "false" });
    this.doc = h("input", { type: "text", "aria-label": "Option doc", placeholder: "What this option decides, in one sentence.", oninput: update });
    this.params = h("div.new-option-params");
    this.folder = h("select", { "aria-label": "Folder", onchange: update });
    this.agents = h("select", { "aria-label": "Agents file", onchange: () => void this.loadAgents() });
    this.problemsList = h("ul.new-option-problems", { "aria-live": "polite" });
    this.source = h("pre.new-option-source");
    this.diff = h("pre.new-option-diff", { "aria-label": "Agents file diff" });
    this.create = h("button.primary", { onclick: () => void this.submit() }, "Create");
    this.element = h(
      "dialog.new-option",
      { "aria-label": "New option" },
      h("h2", {}, "New option"),
      h("label", {}, "Name ", this.name),
      h("label", {}, "Doc ", this.doc),
      h("div.section-title", {}, "Parameters"),
      this.params,
      h("button", { onclick: () => this.addRow(), title: "Add a parameter" }, "+ parameter"),
      h("label", {}, "Folder ", this.folder),
      h("label", {}, "Behavior set (agents file) ", this.agents),
      this.problemsList,
      h("div.section-title", {}, "New file"),
      this.source,
      h("div.section-title", {}, "Change to the agents file"),
      this.diff,
      h("div.dialog-buttons", {}, h("button", { onclick: () => this.element.close() }, "Cancel"), this.create),
    );
    document.body.append(this.element);
  }

  async show(): Promise<void> {
    try {
      this.files = await listFiles();
    } catch (error) {
      toast(`Cannot list the behavior files: ${(error as Error).message}`, "error");
      return;
    }
    const program = this.session.programOf(this.session.selectedRobot);
    const agentsFiles = this.files.filter((f) => /(^|\/)agents\.xabsl$/.test(f.path));
    const ordered = [...agentsFiles.filter((f) => program && f.programs.includes(program)), ...agentsFiles.filter((f) => !(program && f.programs.includes(program)))];
    this.agents.replaceChildren(...ordered.map((f) => h("option", { value: f.path }, f.path)));
    this.name.value = "";
    this.doc.value = "";
    this.created = null;
    this.rows = [];
    this.params.replaceChildren();
    await this.loadAgents();
    this.element.showModal();
    this.name.focus();
  }

  /// The folders of the chosen behavior set's files (option folders first).
  private fillFolders(): void {
    const agentsPath = this.agents.value;
    const program = this.files.find((f) => f.path === agentsPath)?.programs[0];
    const folders = new Set<string>();
    for (const f of this.files) if (!program || f.programs.includes(program)) folders.add(f.path.split("/").slice(0, -1).join("/"));
    const list = [...folders].sort((a, b) => Number(!/options/.test(a)) - Number(!/options/.test(b)) || a.localeCompare(b));
    const chosen = this.folder.value;
    this.folder.replaceChildren(...list.map((d) => h("option", { value: d }, d || "(the example folder)")));
    if (list.includes(chosen)) this.folder.value = chosen;
  }

  private async loadAgents(): Promise<void> {
    this.fillFolders();
    const path = this.agents.value;
    this.agentsFile = null;
    if (path) {
      try {
        const file = await readFile(path);
        this.agentsFile = { path, text: file.text, version: file.version };
      } catch (error) {
        toast(`Cannot read ${path}: ${(error as Error).message}`, "error");
      }
    }
    this.preview();
  }

  private addRow(): void {
    const name = h("input", { type: "text", "aria-label": "Parameter name", placeholder: "name", size: 10, oninput: () => this.preview() });
    const enums = this.session.indexOf(this.session.selectedRobot)?.description.enums.map((e) => e.name) ?? [];
    const type = h("select", { "aria-label": "Parameter type", onchange: () => this.preview() }, h("option", { value: "float" }, "float"), h("option", { value: "bool" }, "bool"), ...enums.map((e) => h("option", { value: e }, `enum ${e}`)));
    const min = h("input", { type: "number", "aria-label": "Range from", placeholder: "min", step: "any", oninput: () => this.preview() });
    const max = h("input", { type: "number", "aria-label": "Range to", placeholder: "max", step: "any", oninput: () => this.preview() });
    const unit = h("input", { type: "text", "aria-label": "Unit", placeholder: "unit", size: 5, oninput: () => this.preview() });
    const doc = h("input", { type: "text", "aria-label": "Parameter doc", placeholder: "what it is", oninput: () => this.preview() });
    const element = h("div.new-option-param", {}, name, type, min, max, unit, doc);
    const row: Row = {
      element,
      read: () => ({
        name: name.value.trim(),
        type: type.value,
        min: min.value === "" ? null : Number(min.value),
        max: max.value === "" ? null : Number(max.value),
        unit: unit.value.trim(),
        doc: doc.value,
      }),
    };
    element.append(h("button.icon", { title: "Remove this parameter", "aria-label": "remove parameter", onclick: () => { this.rows = this.rows.filter((r) => r !== row); element.remove(); this.preview(); } }, "×"));
    this.rows.push(row);
    this.params.append(element);
    this.preview();
  }

  private option(): NewOption {
    return { name: this.name.value.trim(), doc: this.doc.value, params: this.rows.map((r) => r.read()) };
  }

  private path(): string {
    const folder = this.folder.value;
    return `${folder ? `${folder}/` : ""}${this.option().name}.xabsl`;
  }

  /// Show the file and the agents file's diff, or what is wrong.
  private preview(): void {
    const option = this.option();
    const index = this.session.indexOf(this.session.selectedRobot);
    const existing = index?.description.options.map((o) => o.name) ?? [];
    const enums = index?.description.enums.map((e) => e.name) ?? [];
    const found = option.name === "" ? ["name: give the option a name"] : problems(option, existing, enums);
    const path = this.path();
    if (path !== this.created && this.files.some((f) => f.path === path)) found.push(`${path} exists already`);
    if (!this.agentsFile) found.push("choose the agents file that gets the include line");
    this.problemsList.replaceChildren(...found.map((p) => h("li", {}, p)));
    this.create.disabled = found.length > 0;
    this.source.textContent = optionSource(option);
    this.previewed = null;
    if (this.agentsFile && option.name) {
      const { text } = addInclude(this.agentsFile.text, this.agentsFile.path, path);
      this.previewed = { path: this.agentsFile.path, text };
      this.diff.replaceChildren(
        h("div.diff-file", {}, this.agentsFile.path),
        ...insertionDiff(this.agentsFile.text, text).map((d) => h("div", { class: d.kind === "+" ? "diff-add" : d.kind === "-" ? "diff-del" : "diff-ctx" }, `${d.kind} ${String(d.line).padStart(3)}  ${d.text}`)),
      );
    } else this.diff.replaceChildren();
  }

  private async submit(): Promise<void> {
    this.preview();
    const agents = this.agentsFile;
    const previewed = this.previewed;
    if (this.create.disabled || !agents || !previewed) return;
    const path = this.path();
    if (this.created !== path) {
      try {
        // 422 (saved, but the behavior set has errors: the option is not included yet) is fine
        await createFile(path, optionSource(this.option()));
        this.created = path;
      } catch (error) {
        this.problemsList.replaceChildren(h("li", {}, `Cannot create ${path}: ${(error as Error).message}`));
        return;
      }
    }
    try {
      const saved = await writeFile(agents.path, previewed.text, agents.version);
      if (saved.conflict) {
        this.problemsList.replaceChildren(h("li", {}, `${path} was created, but ${agents.path} changed since it was shown: look at the new diff and press Create again.`));
        await this.loadAgents();
        return;
      }
      if (saved.status === 422) toast(`${agents.path} now includes ${path}, but the behavior has errors (see the editor).`, "error", 8000);
    } catch (error) {
      this.problemsList.replaceChildren(h("li", {}, `${path} was created, but ${agents.path} could not be written: ${(error as Error).message}`));
      return;
    }
    this.created = null;
    this.element.close();
    toast(`Created ${path} and included it in ${agents.path}.`, "ok", 6000);
    await this.opened(path);
  }
}
