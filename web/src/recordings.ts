/// Recordings from inside the studio: the "Recordings" dialog lists the server's record folder
/// (`GET api/recordings`: newest first, size, duration, example) and opens one as a replay in a new
/// tab (`POST api/recordings/open` answers its address, `/replay/ID/`, served by the same server);
/// in a replay of a deterministic recording, "Run from here" starts a live session from the tick in
/// view (`POST api/fork`, `/fork/ID/`) in a new tab, so the original stays beside the fork.
import { apiJson, token } from "./api";
import type { Session } from "./session";
import { h, toast } from "./ui";

export interface RecordingEntry {
  name: string;
  size: number;
  modified: number;
  example?: string | null;
  ticks?: number;
  seconds?: number;
  agents?: number;
  deterministic?: boolean;
  forked_from?: { file: string; seq: number } | null;
  /// set when the file was recovered after its writer died: why it ended there
  cut?: { reason: string; file_bytes: number; kept_bytes: number } | null;
  error?: string | null;
}

export interface OpenStudio {
  id: number;
  kind: "replay" | "fork";
  label: string;
  url: string;
  clients: number;
  file?: string;
  seq?: number;
}

interface Listing {
  folder: string | null;
  recordings: RecordingEntry[];
  open: OpenStudio[];
}

/// The address of a studio served beside this one, with the page's token.
export function studioAddress(url: string): string {
  const target = new URL(url, globalThis.location.origin);
  if (token) target.searchParams.set("token", token);
  return target.toString();
}

/// "12.3 MB", "840 kB".
export function formatSize(bytes: number): string {
  if (bytes >= 1e9) return `${(bytes / 1e9).toFixed(1)} GB`;
  if (bytes >= 1e6) return `${(bytes / 1e6).toFixed(1)} MB`;
  return `${Math.max(1, Math.round(bytes / 1e3))} kB`;
}

/// "1:05" for 65 s, "12:00:00" for half a day.
export function formatDuration(seconds: number): string {
  const s = Math.round(seconds);
  const hh = Math.floor(s / 3600);
  const mm = Math.floor((s % 3600) / 60);
  const ss = String(s % 60).padStart(2, "0");
  return hh ? `${hh}:${String(mm).padStart(2, "0")}:${ss}` : `${mm}:${ss}`;
}

function openTab(studio: OpenStudio): void {
  const tab = globalThis.open(studioAddress(studio.url), "_blank");
  if (!tab) toast(`${studio.label} is open at ${studio.url} (the browser blocked the new tab)`, "info", 10000);
}

/// The timeline's "Recordings…" button, its dialog, and the replay's "Run from here" button.
export class Recordings {
  readonly button: HTMLButtonElement;
  readonly forkButton: HTMLButtonElement;
  private readonly dialog: HTMLDialogElement;
  private readonly body: HTMLElement;

  constructor(private readonly session: Session) {
    this.body = h("div.recordings-list");
    this.dialog = h(
      "dialog.recordings",
      { "aria-label": "Recordings" },
      h("h2", {}, "Recordings"),
      this.body,
      h("div.dialog-buttons", {}, h("button", { onclick: () => this.dialog.close() }, "Close")),
    );
    document.body.append(this.dialog);
    this.button = h("button#recordings", { title: "Open a recording of this studio's record folder in a new tab", onclick: () => void this.show() }, "Recordings…");
    this.forkButton = h(
      "button#run-from-here-replay",
      { title: "Start a live session from the tick in view, with the behavior on disk, in a new tab", onclick: () => void this.runFromHere() },
      "Run from here",
    );
  }

  /// "Run from here" is beside the Recordings button only in a replay of a deterministic recording.
  setReplay(deterministic: boolean): void {
    if (deterministic && !this.forkButton.isConnected) this.button.after(this.forkButton);
    else if (!deterministic) this.forkButton.remove();
  }

  async show(): Promise<void> {
    this.body.replaceChildren(h("p", {}, "Loading…"));
    if (!this.dialog.open) this.dialog.showModal();
    try {
      this.render(await apiJson<Listing>("GET", "recordings"));
    } catch (e) {
      this.body.replaceChildren(h("p.error", {}, `Recordings: ${(e as Error).message}`));
    }
  }

  private render(listing: Listing): void {
    const rows = listing.recordings.map((r) =>
      h(
        "tr",
        { "data-name": r.name },
        h("td", {}, r.name),
        h("td", {}, new Date(r.modified * 1000).toLocaleString()),
        h("td.num", {}, formatSize(r.size)),
        h("td.num", {}, r.seconds !== undefined ? formatDuration(r.seconds) : ""),
        h("td", {}, r.error ? `unreadable: ${r.error}` : `${r.example ?? "?"}${r.deterministic ? "" : " (live)"}${r.forked_from ? ` · fork of ${r.forked_from.file} at ${r.forked_from.seq}` : ""}${r.cut ? ` · cut, recovered to its last complete tick (${r.cut.reason})` : ""}`),
        h("td", {}, r.error ? "" : h("button.open-recording", { onclick: () => void this.open(r.name) }, "Open")),
      ),
    );
    const open = listing.open.map((o) =>
      h("li", {}, h("a", { href: studioAddress(o.url), target: "_blank" }, o.label), ` (${o.clients} page${o.clients === 1 ? "" : "s"}) `, h("button", { onclick: () => void this.close(o.id) }, "Close")),
    );
    this.body.replaceChildren(
      h("p", {}, listing.folder ? `In ${listing.folder}, newest first. A recording opens read-only in a new tab.` : "This studio records into no folder."),
      rows.length
        ? h("table", {}, h("thead", {}, h("tr", {}, ...["File", "Recorded", "Size", "Length", "Example", ""].map((t) => h("th", {}, t)))), h("tbody", {}, ...rows))
        : h("p", {}, "No recordings yet (the file being written appears when it is rolled or the session ends)."),
      ...(open.length ? [h("h3", {}, "Open beside this studio"), h("ul", {}, ...open)] : []),
    );
  }

  private async open(name: string): Promise<void> {
    try {
      openTab(await apiJson<OpenStudio>("POST", "recordings/open", { name }));
      await this.show();
    } catch (e) {
      toast(`Open ${name}: ${(e as Error).message}`, "error", 8000);
    }
  }

  private async close(id: number): Promise<void> {
    try {
      await apiJson("DELETE", `recordings/open/${id}`);
      await this.show();
    } catch (e) {
      toast(`Close: ${(e as Error).message}`, "error");
    }
  }

  /// Fork the replay at the tick in view (the timeline cursor, else the playback position).
  async runFromHere(): Promise<void> {
    const tick = this.session.view;
    if (!tick) return;
    const seq = Math.max(1, tick.seq);
    this.forkButton.disabled = true;
    toast(`Re-simulating the recording to tick ${seq}…`, "info");
    try {
      openTab(await apiJson<OpenStudio>("POST", "fork", { seq }));
    } catch (e) {
      toast(`Run from here: ${(e as Error).message}`, "error", 10000);
    } finally {
      this.forkButton.disabled = false;
    }
  }
}
