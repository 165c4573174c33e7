/// Go to definition and find references for XABSL names.
///
/// Names are global strings with dots (§1.1, §1.4), so a "word" is a maximal run of identifier
/// characters including dots and a leading `@`. Definitions come from the description's spans
/// (symbols, options, basic behaviors, enumerations, constants, agents); states and option
/// parameters are looked up in the option being edited, whose text may be newer than the IR.
import type { DescriptionIndex, Span } from "../description";
import { currentOptionName } from "./complete";

const IDENT_CHAR = /[A-Za-z0-9_.@]/;

/// The word at `pos` of `text` (or touching it from the left), with its offsets.
export function wordAt(text: string, pos: number): { word: string; from: number; to: number } | null {
  let from = pos;
  let to = pos;
  while (from > 0 && IDENT_CHAR.test(text[from - 1] as string)) from--;
  while (to < text.length && IDENT_CHAR.test(text[to] as string)) to++;
  let word = text.slice(from, to);
  // A trailing dot ends a sentence in a comment, not a name.
  while (word.endsWith(".")) {
    word = word.slice(0, -1);
    to--;
  }
  if (!word || !/^@?[A-Za-z_]/.test(word)) return null;
  return { word, from, to };
}

export type Definition = { kind: "span"; span: Span; what: string } | { kind: "local"; from: number; to: number; what: string };

function escape(text: string): string {
  return text.replace(/[.*+?^${}()|[\]\\]/g, "\\$&");
}

/// Where `word` is defined: a span of some file, or an offset range of `text` itself.
export function definitionOf(word: string, text: string, index: DescriptionIndex | null): Definition | null {
  const option = currentOptionName(text);
  if (word.startsWith("@")) {
    const m = new RegExp(`(?:^|[;{\\s])(?:bool|float|enum\\s+[A-Za-z_][\\w.]*)?\\s*(${escape(word)})(?![\\w.])`, "m").exec(text);
    if (m && m[1]) {
      const from = m.index + m[0].length - m[1].length;
      return { kind: "local", from, to: from + word.length, what: `parameter ${word}` };
    }
    const p = index?.optionByName.get(option ?? "")?.params.find((x) => `@${x.short_name}` === word);
    return p?.span ? { kind: "span", span: p.span, what: `parameter ${word}` } : null;
  }
  const state = new RegExp(`\\bstate\\s+(${escape(word)})(?![\\w.])`).exec(text);
  if (state && state[1] && option) {
    const from = state.index + state[0].length - state[1].length;
    return { kind: "local", from, to: from + word.length, what: `state ${word}` };
  }
  if (!index) return null;
  const found =
    (index.optionByName.get(word) && { span: index.optionByName.get(word)?.span, what: `option ${word}` }) ||
    (index.behaviorByName.get(word) && { span: index.behaviorByName.get(word)?.span, what: `basic behavior ${word}` }) ||
    (index.inputByName.get(word) && { span: index.inputByName.get(word)?.span, what: `input symbol ${word}` }) ||
    (index.outputByName.get(word) && { span: index.outputByName.get(word)?.span, what: `${index.outputByName.get(word)?.internal ? "internal" : "output"} symbol ${word}` }) ||
    (index.constantByName.get(word) && { span: index.constantByName.get(word)?.span, what: `constant ${word}` }) ||
    (index.enumByName.get(word) && { span: index.enumByName.get(word)?.span, what: `enumeration ${word}` }) ||
    null;
  if (found?.span) return { kind: "span", span: found.span, what: found.what };
  for (const e of index.description.enums) {
    if (e.elements.includes(word) && e.span) return { kind: "span", span: e.span, what: `element ${word} of ${e.name}` };
  }
  const agent = index.description.agents.find((a) => a.name === word);
  if (agent?.span) return { kind: "span", span: agent.span, what: `agent ${word}` };
  return null;
}

export interface Reference {
  path: string;
  line: number;
  col: number;
  from: number;
  to: number;
  lineText: string;
}

/// Every whole-word occurrence of `word` in `files` (path -> text), outside comments' `//` tails.
export function findReferences(word: string, files: ReadonlyMap<string, string>): Reference[] {
  const out: Reference[] = [];
  const re = new RegExp(`(?<![A-Za-z0-9_.@])${escape(word)}(?![A-Za-z0-9_.])`, "g");
  for (const [path, text] of files) {
    const lines = text.split("\n");
    let offset = 0;
    lines.forEach((lineText, i) => {
      const code = lineText.split("//")[0] ?? "";
      for (const m of code.matchAll(re)) {
        const col = m.index ?? 0;
        out.push({ path, line: i + 1, col: col + 1, from: offset + col, to: offset + col + word.length, lineText: lineText.trim() });
      }
      offset += lineText.length + 1;
    });
  }
  return out.sort((a, b) => a.path.localeCompare(b.path) || a.from - b.from);
}
