/// Attached hosts (`xabsl attach`, docs/attach.md): one chip per host with its state (attached,
/// gone, refused) and who holds its control, and **Connect…**, a dialog that attaches one more
/// host (`attach_host`: HOST:PORT and its token). Shown only in an attached session: every tick's
/// world status carries `attached` (one entry per host) and `connect` (whether this studio lets
/// its users attach more); a `live` studio's ticks have neither, and the bar stays hidden.
import type { Connection } from "../connection";
import type { Session, SessionEvent } from "../session";
import { h, setText, toast, toggleClass } from "../ui";

/// One host as the attached session's status shows it (`server/session/attached.py` `HostConnection.info`).
export interface AttachedHost {
  address: string;
  name: string;
  connected: boolean;
  gone: boolean;
  refused: string | null;
  robots: string[];
  control: { studio: string; peer: string } | null;
  controlled_here: boolean;
  received: number;
  missed: number;
}

/// The hosts of a tick's world status, or null outside an attached session.
export function attachedHosts(status: Record<string, unknown> | null | undefined): AttachedHost[] | null {
  const hosts = status?.attached;
  return Array.isArray(hosts) ? (hosts as AttachedHost[]) : null;
}

/// What a host chip says: its state, then who holds its control.
export function hostLabel(host: AttachedHost): { state: string; control: string } {
  const state = host.refused !== null ? "refused" : host.connected ? "attached" : host.gone ? "gone" : "connecting";
  const control = host.controlled_here ? "control: this studio" : host.control ? `control: ${host.control.studio}` : "control: free";
  return { state, control };
}

/// HOST:PORT (`[::1]:7410` for IPv6), as the server checks it.
const ADDRESS = /^[^\s/]+:[0-9]{1,5}$/;

export class AttachBar {
  readonly element: HTMLElement;
  private readonly chips: HTMLElement;
  private readonly connectButton: HTMLButtonElement;
  private readonly dialog: HTMLDialogElement;
  private readonly address: HTMLInputElement;
  private readonly token: HTMLInputElement;
  private readonly problem: HTMLElement;
  private shown = "";

  constructor(
    private readonly session: Session,
    private readonly connection: Connection,
  ) {
    this.chips = h("span.attach-hosts");
    this.connectButton = h("button#connect-host", { title: "Attach one more host (HOST:PORT)", onclick: () => this.open() }, "Connect…");
    this.element = h("div.attach-bar", { hidden: true, "aria-label": "Attached hosts" }, this.chips, this.connectButton);
    this.address = h("input#connect-address", { placeholder: "127.0.0.1:7410", "aria-label": "Host address", required: true });
    this.token = h("input#connect-token", { type: "password", placeholder: "(the studio's --token)", "aria-label": "Host token", autocomplete: "off" });
    this.problem = h("div.connect-problem.muted");
    const form = h(
      "form",
      { method: "dialog", onsubmit: (e: Event) => this.submit(e) },
      h("h3", {}, "Connect to a host"),
      h("label", {}, "Address ", this.address),
      h("label", {}, "Token ", this.token),
      this.problem,
      h("div.dialog-buttons", {}, h("button", { type: "button", onclick: () => this.dialog.close() }, "Cancel"), h("button.primary#connect-go", { type: "submit" }, "Connect")),
    );
    this.dialog = h("dialog#connect-dialog", {}, form);
    document.body.append(this.dialog);
  }

  private open(): void {
    setText(this.problem, "");
    this.dialog.showModal();
    this.address.focus();
  }

  private submit(event: Event): void {
    event.preventDefault();
    const address = this.address.value.trim();
    if (!ADDRESS.test(address)) {
      setText(this.problem, "An address is HOST:PORT, e.g. 127.0.0.1:7411");
      return;
    }
    const token = this.token.value || null;
    setText(this.problem, `Connecting to ${address}…`);
    this.connection
      .command("attach_host", { address, token })
      .then((result) => {
        const host = result as unknown as AttachedHost;
        if (host.refused !== null) {
          setText(this.problem, `${address} refused: ${host.refused}`);
          return;
        }
        this.dialog.close();
        this.token.value = "";
        toast(host.connected ? `Attached ${host.name} (${host.robots.join(", ")})` : `${address} does not answer yet; the studio keeps trying`, host.connected ? "ok" : "error");
      })
      .catch((e: Error) => setText(this.problem, e.message));
  }

  render(_changes: Set<SessionEvent>): void {
    const status = this.session.view?.status as Record<string, unknown> | null | undefined;
    const hosts = attachedHosts(status);
    this.element.hidden = hosts === null;
    if (hosts === null) return;
    this.connectButton.hidden = status?.connect !== true;
    // Rebuilt only when what a chip says changes (every tick carries the hosts).
    const key = JSON.stringify(hosts.map((host) => [host.address, host.name, hostLabel(host), host.robots]));
    if (key === this.shown) return;
    this.shown = key;
    this.chips.replaceChildren(
      ...hosts.map((host) => {
        const label = hostLabel(host);
        const chip = h(
          "span.attach-host",
          { "data-address": host.address, "data-state": label.state, title: `${host.address}: ${host.robots.join(", ") || "no robots yet"}${host.refused ? ` — ${host.refused}` : ""}` },
          h("span.attach-name", {}, host.name),
          h("span.attach-state", {}, label.state),
          h("span.attach-control", {}, label.control),
        );
        toggleClass(chip, "gone", label.state === "gone" || label.state === "refused");
        toggleClass(chip, "mine", host.controlled_here);
        return chip;
      }),
    );
  }
}
