/// Go to definition, find references, rename and hover for XABSL, answered by the language
/// server (`textDocument/definition`, `references`, `rename`, `hover`) — the compiler resolves
/// the names, so a state, a parameter and a symbol of the same spelling are told apart.
import type { EditorState, Extension, Text } from "@codemirror/state";
import { type EditorView, hoverTooltip } from "@codemirror/view";
import { fromPosition, toPosition } from "./complete";
import type { LspClient, LspLocation, LspTextEdit } from "./lsp";

/// A place in a behavior file: its path, 1-based line and column (for the editor's `open`).
export interface Place {
  path: string;
  line: number;
  col: number;
}

function place(client: LspClient, location: LspLocation): Place | null {
  const path = client.pathOf(location.uri);
  if (path === null) return null;
  return { path, line: location.range.start.line + 1, col: location.range.start.character + 1 };
}

/// Where the name at `pos` is defined (null: nothing there, or nothing defines it).
export async function definitionAt(client: LspClient, path: string, state: EditorState, pos: number): Promise<Place | null> {
  await client.sync(path, state.doc.toString());
  const found = await client.definition(path, toPosition(state.doc, pos));
  const first = Array.isArray(found) ? found[0] : found;
  return first ? place(client, first) : null;
}

/// Every occurrence of the name at `pos` in the behavior set (its declaration included).
export async function referencesAt(client: LspClient, path: string, state: EditorState, pos: number): Promise<Place[]> {
  await client.sync(path, state.doc.toString());
  const found = (await client.references(path, toPosition(state.doc, pos))) ?? [];
  return found.map((l) => place(client, l)).filter((p): p is Place => p !== null);
}

/// The edits renaming the name at `pos` to `newName`, by path (the server refuses invalid names).
export async function renameAt(
  client: LspClient,
  path: string,
  state: EditorState,
  pos: number,
  newName: string,
): Promise<Map<string, LspTextEdit[]>> {
  await client.sync(path, state.doc.toString());
  const edit = await client.rename(path, toPosition(state.doc, pos), newName);
  const out = new Map<string, LspTextEdit[]>();
  for (const [uri, edits] of Object.entries(edit?.changes ?? {})) {
    const p = client.pathOf(uri);
    if (p !== null) out.set(p, edits);
  }
  return out;
}

/// The text edits of the protocol as CodeMirror changes of `doc`.
export function toChanges(doc: Text, edits: readonly LspTextEdit[]): Array<{ from: number; to: number; insert: string }> {
  return edits.map((e) => ({ from: fromPosition(doc, e.range.start), to: fromPosition(doc, e.range.end), insert: e.newText }));
}

/// Hover: the server's description (type, range, unit, doc comment; for an option its
/// parameters and states) in a tooltip.
export function lspHover(client: LspClient, path: () => string | null): Extension {
  return hoverTooltip(async (view: EditorView, pos: number) => {
    const p = path();
    if (!p) return null;
    try {
      await client.sync(p, view.state.doc.toString());
      const hover = await client.hover(p, toPosition(view.state.doc, pos));
      if (!hover) return null;
      const text = typeof hover.contents === "string" ? hover.contents : hover.contents.value;
      const from = hover.range ? fromPosition(view.state.doc, hover.range.start) : pos;
      const to = hover.range ? fromPosition(view.state.doc, hover.range.end) : pos;
      return {
        pos: from,
        end: to,
        above: true,
        create: () => {
          const dom = document.createElement("div");
          dom.className = "cm-xabsl-hover";
          dom.style.whiteSpace = "pre-wrap";
          dom.style.maxWidth = "40em";
          dom.style.padding = "4px 8px";
          dom.textContent = text.replace(/\*\*|`/g, "");
          return { dom };
        },
      };
    } catch {
      return null;
    }
  });
}
