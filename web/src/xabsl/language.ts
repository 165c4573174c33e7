/// XABSL 2 for CodeMirror 6: a stream tokenizer following xabsl-language.md §1.2, highlight tags,
/// comment tokens, indentation by braces and bracket closing.
///
/// Lexical facts are tables (`KEYWORDS`, `TYPE_KEYWORDS`, `DEFINERS`), as the Python tokenizer
/// keeps them, so completion and tests read the same data. The keyword-run rule of §1.2 is kept:
/// a maximal run `[A-Za-z_][A-Za-z0-9_.-]*` is a keyword only when the whole run is one, so
/// `state_time-500` highlights as an identifier, exactly as the compiler reads it.
import { LanguageSupport, StreamLanguage, StringStream } from "@codemirror/language";
import { tags as t } from "@lezer/highlight";

/// Every keyword of the language (§1.2).
export const KEYWORDS: readonly string[] = [
  "true", "false", "option", "action", "initial", "target", "state", "common", "decision", "stay",
  "goto", "if", "else", "state_time", "option_time", "action_done", "agent", "function", "enum",
  "input", "output", "bool", "float", "const", "namespace", "behavior", "include", "internal",
  "capacity", "synchronized", "conflict",
];

/// Keywords that name a type.
export const TYPE_KEYWORDS: readonly string[] = ["bool", "float", "enum"];

/// Keywords whose value is read in expressions (they complete like symbols).
export const VALUE_KEYWORDS: readonly string[] = [
  "true", "false", "state_time", "option_time", "action_done", "conflict",
];

/// Keywords after which the next identifier is being defined.
export const DEFINERS: readonly string[] = ["option", "state", "agent", "namespace", "behavior", "enum"];

const KEYWORD_SET = new Set(KEYWORDS);
const TYPE_SET = new Set(TYPE_KEYWORDS);
const VALUE_SET = new Set(VALUE_KEYWORDS);
const DEFINER_SET = new Set(DEFINERS);
const CONTROL = new Set(["if", "else", "goto", "stay"]);

/// Tokenizer state: inside a block comment (and which kind), and whether the last word defines.
export interface XabslState {
  comment: null | "doc" | "block";
  defining: boolean;
}

function blockComment(stream: StringStream, state: XabslState): string {
  while (!stream.eol()) {
    if (stream.match("*/")) {
      const kind = state.comment;
      state.comment = null;
      return kind === "doc" ? "docComment" : "blockComment";
    }
    stream.next();
  }
  return state.comment === "doc" ? "docComment" : "blockComment";
}

/// The stream parser (exported for tests that tokenize without an editor).
export const xabslStreamParser = {
  name: "xabsl",
  startState: (): XabslState => ({ comment: null, defining: false }),
  copyState: (s: XabslState): XabslState => ({ ...s }),
  token(stream: StringStream, state: XabslState): string | null {
    if (state.comment) return blockComment(stream, state);
    if (stream.eatSpace()) return null;
    if (stream.match("//")) {
      stream.skipToEnd();
      return "lineComment";
    }
    if (stream.match("/**")) {
      // `/***` opens the title comment and `/**` a doc comment; both are documentation.
      state.comment = "doc";
      return blockComment(stream, state);
    }
    if (stream.match("/*")) {
      state.comment = "block";
      return blockComment(stream, state);
    }
    if (stream.match(/^"[^"]*"?/)) return "string";
    if (stream.match(/^\[[^\]]*\]?/)) return "unit";
    if (stream.match(/^[0-9]+(\.[0-9]*)?/)) return "number";
    if (stream.match(/^@[A-Za-z_][A-Za-z0-9_.]*/)) return "parameter";
    const run = stream.match(/^[A-Za-z_][A-Za-z0-9_.-]*/, false) as RegExpMatchArray | null;
    if (run) {
      const word = run[0];
      if (KEYWORD_SET.has(word)) {
        stream.pos += word.length;
        state.defining = DEFINER_SET.has(word);
        if (TYPE_SET.has(word)) return "typeName";
        if (VALUE_SET.has(word)) return word === "true" || word === "false" ? "bool" : "atom";
        return CONTROL.has(word) ? "controlKeyword" : "keyword";
      }
      stream.match(/^[A-Za-z_][A-Za-z0-9_.]*/);
      if (state.defining) {
        state.defining = false;
        return "definition";
      }
      return "variableName";
    }
    state.defining = false;
    if (stream.match(/^(<=|>=|==|!=|&&|\|\|)/)) return "operator";
    const ch = stream.next();
    if (ch === undefined) return null;
    if ("{}()".includes(ch)) return "bracket";
    if (";,".includes(ch)) return "separator";
    if ("%!<>+-*/=?:|".includes(ch)) return "operator";
    return "invalid";
  },
  languageData: {
    commentTokens: { line: "//", block: { open: "/*", close: "*/" } },
    closeBrackets: { brackets: ["(", "{", '"'] },
    indentOnInput: /^\s*\}$/,
  },
  tokenTable: {
    docComment: t.docComment,
    blockComment: t.blockComment,
    lineComment: t.lineComment,
    string: t.string,
    unit: t.unit,
    number: t.number,
    parameter: t.special(t.variableName),
    typeName: t.typeName,
    bool: t.bool,
    atom: t.atom,
    controlKeyword: t.controlKeyword,
    keyword: t.keyword,
    definition: t.definition(t.variableName),
    variableName: t.variableName,
    operator: t.operator,
    bracket: t.bracket,
    separator: t.separator,
    invalid: t.invalid,
  },
};

/// The XABSL language (a `StreamLanguage`).
export const xabslLanguage = StreamLanguage.define<XabslState>(xabslStreamParser);

/// XABSL support for an editor: the language with its highlighting data.
export function xabsl(): LanguageSupport {
  return new LanguageSupport(xabslLanguage);
}

/// Tokenize `text` into [style, text] pairs (tests, and plain-text rendering of conditions).
export function tokenize(text: string): Array<[string | null, string]> {
  const state = xabslStreamParser.startState();
  const out: Array<[string | null, string]> = [];
  for (const line of text.split("\n")) {
    const stream = new StringStream(line, 4, 2);
    while (!stream.eol()) {
      const start = stream.pos;
      const style = xabslStreamParser.token(stream, state);
      if (stream.pos === start) stream.pos++;
      out.push([style, line.slice(start, stream.pos)]);
    }
  }
  return out.filter(([style, s]) => style !== null || s.trim() !== "");
}
