/// A small Language Server Protocol client for the studio's editor: JSON-RPC over the websocket
/// `/lsp` to the same `xabsl lsp` every other editor uses (docs/editors.md).
///
/// The studio knows its files by paths relative to the behavior folder; the server tells the
/// folder's URI (`xabsl/root`) and documents are `ROOT/path`. Open buffers are synchronised with
/// `didOpen`/`didChange` (whole text: behavior files are small); the server publishes
/// diagnostics for every file of the behavior set, which listeners receive by path.

/// LSP positions (0-based line, UTF-16 character), ranges and the few messages the editor uses.
export interface LspPosition {
  line: number;
  character: number;
}
export interface LspRange {
  start: LspPosition;
  end: LspPosition;
}
export interface LspLocation {
  uri: string;
  range: LspRange;
}
export interface LspDiagnostic {
  range: LspRange;
  severity?: number;
  code?: string | number;
  source?: string;
  message: string;
  data?: { replacement?: string; original_code?: string; lint?: boolean } | null;
}
export interface LspTextEdit {
  range: LspRange;
  newText: string;
}
export interface LspCompletionItem {
  label: string;
  kind?: number;
  detail?: string;
  documentation?: string | { kind: string; value: string };
  textEdit?: LspTextEdit;
  insertText?: string;
  sortText?: string;
  data?: unknown;
}
export interface LspHover {
  contents: { kind: string; value: string } | string;
  range?: LspRange;
}

/// What carries the messages: a websocket in the browser, a fake in tests.
export interface Transport {
  send(text: string): void;
  onMessage(listener: (text: string) => void): void;
  onClose(listener: () => void): void;
  close(): void;
}

/// A browser websocket as a `Transport` (messages sent before it opens wait for it).
export function websocketTransport(url: string): Transport {
  const ws = new WebSocket(url);
  const pending: string[] = [];
  ws.addEventListener("open", () => {
    for (const text of pending.splice(0)) ws.send(text);
  });
  return {
    send: (text) => (ws.readyState === WebSocket.OPEN ? ws.send(text) : pending.push(text)),
    onMessage: (listener) => ws.addEventListener("message", (ev) => listener(String(ev.data))),
    onClose: (listener) => ws.addEventListener("close", () => listener()),
    close: () => ws.close(),
  };
}

/// The `/lsp` address on the page's origin (with the page's token).
export function lspUrl(token: string | null): string {
  const loc = globalThis.location;
  const scheme = loc.protocol === "https:" ? "wss:" : "ws:";
  const path = loc.pathname;
  const base = path.slice(0, path.lastIndexOf("/") + 1) || "/";
  return `${scheme}//${loc.host}${base}lsp${token ? `?token=${encodeURIComponent(token)}` : ""}`;
}

/// The pause before connecting again after a close, doubled each failed attempt up to the maximum.
const RETRY_FIRST_MS = 1000;
const RETRY_MAX_MS = 10000;

type Pending = { resolve: (value: unknown) => void; reject: (error: Error) => void };

/// The language server's client: one connection at a time. Given a way to connect (rather than one
/// transport), it connects again after the connection closed (a server restart), with a growing
/// pause, and opens the documents it knew with their latest text, so the editor's diagnostics and
/// completion come back by themselves.
export class LspClient {
  private nextId = 0;
  private readonly pending = new Map<number, Pending>();
  private readonly versions = new Map<string, { version: number; text: string }>();
  private readonly listeners = new Set<(path: string, diagnostics: LspDiagnostic[]) => void>();
  /// The latest diagnostics of every file of the behavior set, by path.
  readonly diagnostics = new Map<string, LspDiagnostic[]>();
  private root = "";
  closed = false;
  /// Settles when the current connection is initialized (rejects if it closed first).
  ready: Promise<void>;
  private transport: Transport;
  private retryMs = RETRY_FIRST_MS;
  private stopped = false;

  constructor(connect: Transport | (() => Transport)) {
    const reconnect = typeof connect === "function" ? connect : null;
    this.transport = reconnect ? reconnect() : (connect as Transport);
    this.ready = this.attach(reconnect);
  }

  private attach(reconnect: (() => Transport) | null): Promise<void> {
    const transport = this.transport;
    transport.onMessage((text) => {
      if (transport === this.transport) this.receive(text);
    });
    transport.onClose(() => {
      if (transport !== this.transport) return;
      this.closed = true;
      for (const p of this.pending.values()) p.reject(new Error("the language server connection closed"));
      this.pending.clear();
      if (reconnect && !this.stopped) {
        setTimeout(() => {
          if (this.stopped) return;
          this.transport = reconnect();
          this.closed = false;
          this.ready = this.attach(reconnect);
        }, this.retryMs);
        this.retryMs = Math.min(this.retryMs * 2, RETRY_MAX_MS);
      }
    });
    const ready = this.start().then(() => {
      this.retryMs = RETRY_FIRST_MS;
      this.reopen();
    });
    ready.catch(() => undefined); // a connection that closes before it is ready is not an error of the page
    return ready;
  }

  /// After a new connection: the server knows no document; open every known one again.
  private reopen(): void {
    for (const [path, known] of this.versions) {
      known.version = 1;
      this.notify("textDocument/didOpen", { textDocument: { uri: this.uriOf(path), languageId: "xabsl", version: 1, text: known.text } });
    }
  }

  private async start(): Promise<void> {
    await this.request("initialize", {
      processId: null,
      rootUri: null,
      capabilities: {
        general: { positionEncodings: ["utf-16"] },
        textDocument: { rename: { prepareSupport: true }, completion: { completionItem: { documentationFormat: ["markdown", "plaintext"] } } },
      },
    });
    this.notify("initialized", {});
    const root = (await this.request("xabsl/root", null)) as { uri: string | null } | null;
    this.root = (root?.uri ?? "").replace(/\/$/, "");
  }

  private receive(text: string): void {
    let message: { id?: number; method?: string; params?: unknown; result?: unknown; error?: { message: string } };
    try {
      message = JSON.parse(text);
    } catch {
      return;
    }
    if (message.method === undefined && typeof message.id === "number") {
      const p = this.pending.get(message.id);
      if (!p) return;
      this.pending.delete(message.id);
      if (message.error) p.reject(new Error(message.error.message));
      else p.resolve(message.result ?? null);
      return;
    }
    if (message.method === "textDocument/publishDiagnostics") {
      const params = message.params as { uri: string; diagnostics: LspDiagnostic[] };
      const path = this.pathOf(params.uri);
      if (path === null) return;
      this.diagnostics.set(path, params.diagnostics);
      for (const listener of this.listeners) listener(path, params.diagnostics);
    } else if (message.id !== undefined && message.method) {
      this.transport.send(JSON.stringify({ jsonrpc: "2.0", id: message.id, result: null }));
    }
  }

  request(method: string, params: unknown): Promise<unknown> {
    if (this.closed) return Promise.reject(new Error("the language server connection closed"));
    const id = ++this.nextId;
    return new Promise((resolve, reject) => {
      this.pending.set(id, { resolve, reject });
      this.transport.send(JSON.stringify({ jsonrpc: "2.0", id, method, params }));
    });
  }

  notify(method: string, params: unknown): void {
    if (!this.closed) this.transport.send(JSON.stringify({ jsonrpc: "2.0", method, params }));
  }

  /// The document URI of a behavior-folder path, and back (null: not below the folder).
  uriOf(path: string): string {
    return `${this.root}/${path.split("/").map(encodeURIComponent).join("/")}`;
  }
  pathOf(uri: string): string | null {
    if (!uri.startsWith(this.root + "/")) return null;
    return uri.slice(this.root.length + 1).split("/").map(decodeURIComponent).join("/");
  }

  /// Tell the server the current text of `path` (didOpen the first time, didChange after).
  async sync(path: string, text: string): Promise<void> {
    try {
      await this.ready;
    } catch {
      // Closed: the text is kept below and opened again on the next connection.
    }
    const known = this.versions.get(path);
    if (known?.text === text) return;
    const uri = this.uriOf(path);
    if (!known) {
      this.versions.set(path, { version: 1, text });
      this.notify("textDocument/didOpen", { textDocument: { uri, languageId: "xabsl", version: 1, text } });
    } else {
      const version = known.version + 1;
      this.versions.set(path, { version, text });
      this.notify("textDocument/didChange", { textDocument: { uri, version }, contentChanges: [{ text }] });
    }
  }

  /// The file was saved: the server reads the disk again for the files not open here.
  saved(path: string): void {
    if (this.versions.has(path)) this.notify("textDocument/didSave", { textDocument: { uri: this.uriOf(path) } });
  }

  onDiagnostics(listener: (path: string, diagnostics: LspDiagnostic[]) => void): () => void {
    this.listeners.add(listener);
    return () => this.listeners.delete(listener);
  }

  private async at<T>(method: string, path: string, position: LspPosition, extra: Record<string, unknown> = {}): Promise<T> {
    await this.ready;
    return (await this.request(method, { textDocument: { uri: this.uriOf(path) }, position, ...extra })) as T;
  }

  completion(path: string, position: LspPosition): Promise<{ items: LspCompletionItem[] } | LspCompletionItem[] | null> {
    return this.at("textDocument/completion", path, position);
  }
  async resolveCompletion(item: LspCompletionItem): Promise<LspCompletionItem> {
    return ((await this.request("completionItem/resolve", item)) as LspCompletionItem | null) ?? item;
  }
  hover(path: string, position: LspPosition): Promise<LspHover | null> {
    return this.at("textDocument/hover", path, position);
  }
  definition(path: string, position: LspPosition): Promise<LspLocation[] | LspLocation | null> {
    return this.at("textDocument/definition", path, position);
  }
  references(path: string, position: LspPosition): Promise<LspLocation[] | null> {
    return this.at("textDocument/references", path, position, { context: { includeDeclaration: true } });
  }
  /// The range and current spelling of a renameable name at `position` (null: nothing to rename).
  prepareRename(path: string, position: LspPosition): Promise<{ range: LspRange; placeholder: string } | null> {
    return this.at("textDocument/prepareRename", path, position);
  }
  rename(path: string, position: LspPosition, newName: string): Promise<{ changes?: Record<string, LspTextEdit[]> } | null> {
    return this.at("textDocument/rename", path, position, { newName });
  }

  close(): void {
    this.stopped = true;
    this.transport.close();
  }
}
