// The studio's LSP client and its CodeMirror adapters, against a fake server on a fake transport:
// the messages sent are checked as the protocol defines them, the answers mapped into CodeMirror.
import { CompletionContext, type CompletionResult, type CompletionSource } from "@codemirror/autocomplete";
import { EditorState, Text } from "@codemirror/state";
import { describe, expect, it, vi } from "vitest";
import { fromPosition, toCompletionResult, toPosition, xabslCompletion } from "../src/xabsl/complete";
import { xabsl } from "../src/xabsl/language";
import { lspToCodeMirror, toServerDiagnostics } from "../src/xabsl/lint";
import { LspClient, type Transport } from "../src/xabsl/lsp";
import { definitionAt, renameAt, toChanges } from "../src/xabsl/navigate";

type Message = { id?: number; method?: string; params?: any };

/// A transport to a scripted server: `answer(method, params)` gives each request's result.
function fakeServer(answer: (method: string, params: any) => unknown) {
  const sent: Message[] = [];
  let deliver: (text: string) => void = () => {};
  const transport: Transport = {
    send(text) {
      const m = JSON.parse(text) as Message;
      sent.push(m);
      if (m.id !== undefined && m.method) {
        const result = m.method === "xabsl/root" ? { uri: "file:///set" } : m.method === "initialize" ? { capabilities: {} } : answer(m.method, m.params);
        queueMicrotask(() => deliver(JSON.stringify({ jsonrpc: "2.0", id: m.id, result })));
      }
    },
    onMessage: (l) => (deliver = l),
    onClose: () => {},
    close: () => {},
  };
  return { transport, sent, push: (m: unknown) => deliver(JSON.stringify(m)) };
}

describe("positions", () => {
  it("maps offsets to LSP lines and UTF-16 characters and back", () => {
    const doc = Text.of(["option x {", "  // é😀", "}"]);
    expect(toPosition(doc, 0)).toEqual({ line: 0, character: 0 });
    // "é" is one UTF-16 unit, "😀" two
    expect(toPosition(doc, doc.line(2).to)).toEqual({ line: 1, character: 8 });
    expect(fromPosition(doc, { line: 1, character: 8 })).toBe(doc.line(2).to);
    expect(fromPosition(doc, { line: 9, character: 0 })).toBe(doc.length);
    expect(fromPosition(doc, { line: 0, character: 99 })).toBe(doc.line(1).to);
  });
});

describe("LspClient", () => {
  it("connects again after the server went away and opens its documents again", async () => {
    vi.useFakeTimers();
    try {
      const connections: Array<ReturnType<typeof fakeServer> & { close: () => void }> = [];
      const client = new LspClient(() => {
        const server = fakeServer(() => null);
        let closed: () => void = () => {};
        server.transport.onClose = (listener) => (closed = listener);
        connections.push({ ...server, close: () => closed() });
        return server.transport;
      });
      await client.sync("options/play.xabsl", "a");
      connections[0]?.close(); // the server stopped: no unhandled rejection, a text kept
      await client.sync("options/play.xabsl", "ab");
      expect(client.closed).toBe(true);
      await vi.advanceTimersByTimeAsync(1000);
      await client.ready;
      expect(connections).toHaveLength(2);
      const methods = connections[1]?.sent.map((m) => m.method);
      expect(methods).toEqual(["initialize", "initialized", "xabsl/root", "textDocument/didOpen"]);
      expect(connections[1]?.sent[3]?.params.textDocument).toMatchObject({ version: 1, text: "ab" });
      await client.sync("options/play.xabsl", "abc");
      expect(connections[1]?.sent[4]?.params).toMatchObject({ textDocument: { version: 2 }, contentChanges: [{ text: "abc" }] });
    } finally {
      vi.useRealTimers();
    }
  });

  it("opens, then changes a document, and knows paths by the server's root", async () => {
    const server = fakeServer(() => null);
    const client = new LspClient(server.transport);
    await client.sync("options/play.xabsl", "a");
    await client.sync("options/play.xabsl", "a");
    await client.sync("options/play.xabsl", "ab");
    const methods = server.sent.map((m) => m.method);
    expect(methods).toEqual(["initialize", "initialized", "xabsl/root", "textDocument/didOpen", "textDocument/didChange"]);
    expect(server.sent[3]?.params.textDocument).toMatchObject({ uri: "file:///set/options/play.xabsl", version: 1, text: "a" });
    expect(server.sent[4]?.params).toMatchObject({ textDocument: { version: 2 }, contentChanges: [{ text: "ab" }] });
    expect(client.pathOf("file:///set/options/my%20file.xabsl")).toBe("options/my file.xabsl");
    expect(client.pathOf("file:///elsewhere/x.xabsl")).toBeNull();
  });

  it("keeps published diagnostics by path and maps them with their quick fix", async () => {
    const server = fakeServer(() => null);
    const client = new LspClient(server.transport);
    await client.ready;
    const seen: string[] = [];
    client.onDiagnostics((p) => seen.push(p));
    const diagnostic = {
      range: { start: { line: 0, character: 5 }, end: { line: 0, character: 11 } },
      severity: 1,
      code: "unknown-state",
      message: "option 'x' has no state 'chasee' (did you mean 'chase'?)",
      data: { replacement: "chase", original_code: "X5552" },
    };
    server.push({ jsonrpc: "2.0", method: "textDocument/publishDiagnostics", params: { uri: "file:///set/a.xabsl", diagnostics: [diagnostic] } });
    expect(seen).toEqual(["a.xabsl"]);
    const doc = Text.of(["goto chasee;"]);
    const [d] = lspToCodeMirror(client.diagnostics.get("a.xabsl") ?? [], doc);
    expect(d).toMatchObject({ from: 5, to: 11, severity: "error", source: "unknown-state X5552" });
    expect(d?.actions?.[0]?.name).toBe("Change to 'chase'");
    expect(toServerDiagnostics("a.xabsl", [diagnostic])[0]).toMatchObject({ severity: "error", file: "a.xabsl", span: { line: 1, col: 6 } });
  });

  it("asks for completion at the cursor and keeps the server's edits and order", async () => {
    const server = fakeServer((method, params) => {
      expect(method).toBe("textDocument/completion");
      expect(params.position).toEqual({ line: 0, character: 17 });
      const range = { start: { line: 0, character: 16 }, end: { line: 0, character: 17 } };
      return {
        items: [
          { label: "speed", kind: 10, detail: "float [0..250] \"mm/s\"", textEdit: { range, newText: "speed = " }, documentation: { kind: "markdown", value: "**parameter** Forward speed." } },
          { label: "direction", kind: 10, textEdit: { range, newText: "direction = " } },
        ],
      };
    });
    const client = new LspClient(server.transport);
    const doc = "option x { walk(s";
    const state = EditorState.create({ doc, selection: { anchor: doc.length }, extensions: [xabsl(), xabslCompletion(client, () => "x.xabsl")] });
    const [source] = state.languageDataAt<CompletionSource>("autocomplete", doc.length);
    const result = (await (source as CompletionSource)(new CompletionContext(state, doc.length, false))) as CompletionResult;
    expect(result.from).toBe(16);
    expect(result.options.map((o) => o.label)).toEqual(["speed", "direction"]);
    expect(result.options[0]).toMatchObject({ apply: "speed = ", type: "property", info: "parameter Forward speed." });
    expect((result.options[0]?.boost ?? 0) > (result.options[1]?.boost ?? 0)).toBe(true);
    expect(server.sent.some((m) => m.method === "textDocument/didOpen" && m.params.textDocument.text === doc)).toBe(true);
    expect(toCompletionResult(state.doc, 3, [])).toBeNull();
  });

  it("goes to a definition in another file and turns a rename into changes", async () => {
    const server = fakeServer((method) => {
      if (method === "textDocument/definition") return [{ uri: "file:///set/symbols.xabsl", range: { start: { line: 5, character: 14 }, end: { line: 5, character: 27 } } }];
      return {
        changes: {
          "file:///set/a.xabsl": [{ range: { start: { line: 0, character: 0 }, end: { line: 0, character: 4 } }, newText: "ball.range" }],
          "file:///set/b.xabsl": [],
        },
      };
    });
    const client = new LspClient(server.transport);
    const state = EditorState.create({ doc: "ball < 3;" });
    expect(await definitionAt(client, "a.xabsl", state, 1)).toEqual({ path: "symbols.xabsl", line: 6, col: 15 });
    const edits = await renameAt(client, "a.xabsl", state, 1, "ball.range");
    expect([...edits.keys()]).toEqual(["a.xabsl", "b.xabsl"]);
    const changed = state.update({ changes: toChanges(state.doc, edits.get("a.xabsl") ?? []) }).state;
    expect(changed.doc.toString()).toBe("ball.range < 3;");
  });
});

describe("lazy documentation", () => {
  it("asks completionItem/resolve for the documentation of a bare item", async () => {
    const server = fakeServer((method, params) => {
      expect(method).toBe("completionItem/resolve");
      return { ...params, documentation: { kind: "markdown", value: "**input symbol** the ball's angle" } };
    });
    const client = new LspClient(server.transport);
    const result = toCompletionResult(Text.of(["x"]), 1, [{ label: "ball.angle", data: { key: ["input", "ball.angle"] } }], (item) => client.resolveCompletion(item));
    const info = result?.options[0]?.info;
    expect(typeof info).toBe("function");
    expect(server.sent.some((m) => m.method === "completionItem/resolve")).toBe(false);
    // shown: resolved then (a minimal DOM for the node test environment)
    (globalThis as any).document = { createElement: () => ({ style: {}, textContent: "" }) };
    try {
      const dom = (await (info as (c: unknown) => Promise<{ textContent: string } | null>)(result?.options[0])) ?? null;
      expect(dom?.textContent).toBe("input symbol the ball's angle");
    } finally {
      delete (globalThis as any).document;
    }
  });
});
