/// Completion for XABSL from the language server (`textDocument/completion`): what is offered,
/// and where, is decided by the compiler's view of the behavior set (lsp/server.py), not here.
///
/// This module only maps positions and items between CodeMirror and the protocol.
import type { Completion, CompletionContext, CompletionResult, CompletionSource } from "@codemirror/autocomplete";
import type { Extension, Text } from "@codemirror/state";
import { xabslLanguage } from "./language";
import type { LspClient, LspCompletionItem, LspPosition } from "./lsp";

/// The protocol position of a document offset (CodeMirror and LSP both count UTF-16 units).
export function toPosition(doc: Text, pos: number): LspPosition {
  const line = doc.lineAt(Math.max(0, Math.min(pos, doc.length)));
  return { line: line.number - 1, character: pos - line.from };
}

/// The document offset of a protocol position, clamped into `doc`.
export function fromPosition(doc: Text, p: LspPosition): number {
  if (p.line < 0) return 0;
  if (p.line >= doc.lines) return doc.length;
  const line = doc.line(p.line + 1);
  return Math.min(line.to, line.from + Math.max(0, p.character));
}

// CompletionItemKind (LSP) -> CodeMirror's completion type (its icon).
const KIND: Record<number, string> = {
  3: "function",
  5: "property",
  6: "variable",
  7: "class",
  10: "property",
  13: "enum",
  14: "keyword",
  20: "enum",
  21: "constant",
};

function documentation(item: LspCompletionItem): string | undefined {
  const doc = item.documentation;
  if (!doc) return undefined;
  return (typeof doc === "string" ? doc : doc.value).replace(/\*\*|`/g, "");
}

/// LSP completion items -> a CodeMirror result (`from` is where the server's edit starts).
/// An item without documentation gets it from `resolve` when shown (long lists come bare).
export function toCompletionResult(
  doc: Text,
  pos: number,
  items: readonly LspCompletionItem[],
  resolve?: (item: LspCompletionItem) => Promise<LspCompletionItem>,
): CompletionResult | null {
  if (!items.length) return null;
  let from = pos;
  const options: Completion[] = items.map((item, index) => {
    const edit = item.textEdit;
    if (edit) from = Math.min(from, fromPosition(doc, edit.range.start));
    const info: Completion["info"] =
      documentation(item) ??
      (resolve && item.data
        ? async () => {
            const text = documentation(await resolve(item));
            if (!text) return null;
            const dom = document.createElement("div");
            dom.style.whiteSpace = "pre-wrap";
            dom.textContent = text;
            return dom;
          }
        : undefined);
    return {
      label: item.label,
      ...(edit && edit.newText !== item.label ? { apply: edit.newText } : {}),
      ...(item.insertText && !edit ? { apply: item.insertText } : {}),
      type: KIND[item.kind ?? 0] ?? "text",
      ...(item.detail ? { detail: item.detail } : {}),
      ...(info ? { info } : {}),
      // keep the server's order (its sortText): enum elements before symbols, keywords last
      boost: Math.max(-99, 99 - index),
    };
  });
  return { from, options, validFor: /^[@A-Za-z_][A-Za-z0-9_.]*$/ };
}

/// A completion source asking `client` about the document at `path()`.
export function lspCompletionSource(client: LspClient, path: () => string | null): CompletionSource {
  return async (context: CompletionContext) => {
    const p = path();
    const word = context.matchBefore(/@?[A-Za-z0-9_.]*$/);
    if (!p || (!context.explicit && !word?.text && !/[(,=\s]$/.test(context.state.sliceDoc(context.pos - 1, context.pos)))) return null;
    // A number being typed names nothing to complete (`< 105`): no popup unless asked for.
    if (!context.explicit && word && /^[0-9]/.test(word.text)) return null;
    const doc = context.state.doc;
    try {
      await client.sync(p, doc.toString());
      const result = await client.completion(p, toPosition(doc, context.pos));
      const items = Array.isArray(result) ? result : (result?.items ?? []);
      if (context.aborted) return null;
      return toCompletionResult(doc, context.pos, items, (item) => client.resolveCompletion(item));
    } catch {
      return null;
    }
  };
}

/// The completion extension (language data: it serves XABSL documents only).
export function xabslCompletion(client: LspClient, path: () => string | null): Extension {
  return xabslLanguage.data.of({ autocomplete: lspCompletionSource(client, path) });
}
