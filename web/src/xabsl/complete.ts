/// Completion for XABSL from the behavior description (the IR JSON of `hello`), passed in as
/// data as lang-sql takes its schema: the extension never fetches anything.
///
/// What is offered depends on the text before the cursor (xabsl-language.md §1.3, §1.4):
/// * after `goto`: the states of the option being edited (declared in the IR or typed in the file);
/// * a word starting with `@`: the option's parameters;
/// * an argument name inside `callee(`: the parameters of the option, basic behavior or input
///   function called, as `name = `;
/// * after `enumSymbol ==`/`!=`, `enumOutput =` or `enumParam =` in a call: the enumeration's
///   elements first (enum literals resolve only there);
/// * anywhere else: input, output and internal symbols, constants, options, basic behaviors,
///   value keywords (`state_time`, ...) and keywords.
/// Inside comments and strings nothing is offered.
import type { Completion, CompletionContext, CompletionResult, CompletionSource } from "@codemirror/autocomplete";
import type { Extension } from "@codemirror/state";
import {
  type BehaviorDescription,
  type Parameter,
  type ValueType,
  indexDescription,
  rangeText,
  type DescriptionIndex,
} from "../description";
import { KEYWORDS, VALUE_KEYWORDS, xabslLanguage } from "./language";

const WORD = /[@A-Za-z_][A-Za-z0-9_.]*$/;
const VALID_FOR = /^[@A-Za-z_][A-Za-z0-9_.]*$/;
const IDENT = "[A-Za-z_][A-Za-z0-9_.]*";

function info(doc: string | null, ...facts: Array<string | null | undefined>): string | undefined {
  const head = facts.filter((f) => f).join(" · ");
  const text = [head, doc ?? ""].filter((x) => x).join("\n");
  return text || undefined;
}

function typeText(type: ValueType, enumName: string | null): string {
  return type === "enum" ? `enum ${enumName ?? ""}` : type === "boolean" ? "bool" : "float";
}

/// The name of the option declared in `text` (an option file holds one), if any.
export function currentOptionName(text: string): string | null {
  const m = text.match(new RegExp(`\\boption\\s+(${IDENT})\\s*\\{`));
  return m ? (m[1] ?? null) : null;
}

/// Whether `pos` is inside a comment or a string of `text` (scanning from the start).
export function inCommentOrString(text: string, pos: number): boolean {
  let i = 0;
  while (i < pos) {
    const c = text[i];
    if (c === "/" && text[i + 1] === "/") {
      const end = text.indexOf("\n", i);
      if (end === -1 || end >= pos) return true;
      i = end + 1;
    } else if (c === "/" && text[i + 1] === "*") {
      const end = text.indexOf("*/", i + 2);
      if (end === -1 || end + 2 > pos) return true;
      i = end + 2;
    } else if (c === '"') {
      const end = text.indexOf('"', i + 1);
      if (end === -1 || end >= pos) return true;
      i = end + 1;
    } else {
      i++;
    }
  }
  return false;
}

/// The callee and the argument text typed so far when `before` ends inside a call's parentheses.
export function openCall(before: string): { callee: string; argText: string } | null {
  let depth = 0;
  for (let i = before.length - 1; i >= 0; i--) {
    const c = before[i];
    if (c === ")") depth++;
    else if (c === "(") {
      if (depth === 0) {
        const head = before.slice(0, i).match(new RegExp(`(${IDENT})\\s*(?:\\b(?:option|behavior)\\s*)?$`));
        if (!head || !head[1]) return null;
        let callee = head[1];
        if (callee === "option" || callee === "behavior") {
          const again = before.slice(0, i).match(new RegExp(`(${IDENT})\\s+(?:option|behavior)\\s*$`));
          if (!again || !again[1]) return null;
          callee = again[1];
        }
        return { callee, argText: before.slice(i + 1) };
      }
      depth--;
    } else if (c === ";" || c === "{" || c === "}") {
      return null;
    }
  }
  return null;
}

class Completer {
  readonly index: DescriptionIndex | null;

  constructor(description: BehaviorDescription | null) {
    this.index = description ? indexDescription(description) : null;
  }

  states(text: string): Completion[] {
    const name = currentOptionName(text);
    const seen = new Map<string, Completion>();
    const option = name ? this.index?.optionByName.get(name) : undefined;
    for (const s of option?.states ?? []) {
      seen.set(s.name, { label: s.name, type: "state", detail: s.initial ? "initial state" : "state", info: info(s.doc), boost: 2 });
    }
    for (const m of text.matchAll(new RegExp(`\\bstate\\s+(${IDENT})`, "g"))) {
      const label = m[1];
      if (label && !seen.has(label)) seen.set(label, { label, type: "state", detail: "state" });
    }
    return [...seen.values()];
  }

  optionParams(text: string): Completion[] {
    const name = currentOptionName(text);
    const seen = new Map<string, Completion>();
    const option = name ? this.index?.optionByName.get(name) : undefined;
    for (const p of option?.params ?? []) {
      seen.set("@" + p.short_name, {
        label: "@" + p.short_name,
        type: "variable",
        detail: typeText(p.type, p.enum),
        info: info(p.doc, rangeText(p.range, p.unit)),
        boost: 2,
      });
    }
    for (const m of text.matchAll(/@([A-Za-z_][A-Za-z0-9_.]*)/g)) {
      const label = "@" + m[1];
      if (!seen.has(label)) seen.set(label, { label, type: "variable", detail: "parameter" });
    }
    return [...seen.values()];
  }

  calleeParams(callee: string): Parameter[] | null {
    const index = this.index;
    if (!index) return null;
    return (
      index.optionByName.get(callee)?.params ??
      index.behaviorByName.get(callee)?.params ??
      index.inputByName.get(callee)?.params ??
      null
    );
  }

  paramNames(callee: string, typed: string): Completion[] {
    const params = this.calleeParams(callee) ?? [];
    const already = new Set([...typed.matchAll(new RegExp(`(${IDENT})\\s*=`, "g"))].map((m) => m[1]));
    return params
      .filter((p) => !already.has(p.short_name))
      .map((p) => ({
        label: p.short_name,
        apply: `${p.short_name} = `,
        type: "property",
        detail: typeText(p.type, p.enum),
        info: info(p.doc, rangeText(p.range, p.unit)),
        boost: 3,
      }));
  }

  enumElements(enumName: string): Completion[] {
    const e = this.index?.enumByName.get(enumName);
    return (e?.elements ?? []).map((el) => ({
      label: el.startsWith(`${enumName}.`) ? el.slice(enumName.length + 1) : el,
      type: "enum",
      detail: `${enumName}`,
      info: info(e?.doc ?? null),
      boost: 5,
    }));
  }

  /// The enumeration of an expression head (`sym`, `@param`) when it is enum-typed.
  enumOf(name: string, text: string): string | null {
    const index = this.index;
    if (!index) return null;
    if (name.startsWith("@")) {
      const option = index.optionByName.get(currentOptionName(text) ?? "");
      return option?.params.find((p) => p.short_name === name.slice(1))?.enum ?? null;
    }
    return index.inputByName.get(name)?.enum ?? index.outputByName.get(name)?.enum ?? null;
  }

  general(): Completion[] {
    const index = this.index;
    const out: Completion[] = [];
    if (index) {
      for (const s of index.description.inputs) {
        out.push({
          label: s.name,
          type: s.params.length ? "function" : "variable",
          detail: `input ${typeText(s.type, s.enum)}`,
          info: info(s.doc, rangeText(s.range, s.unit)),
          ...(s.params.length ? { apply: `${s.name}(` } : {}),
        });
      }
      for (const s of index.description.outputs) {
        out.push({
          label: s.name,
          type: "variable",
          detail: `${s.internal ? "internal" : "output"} ${typeText(s.type, s.enum)}`,
          info: info(s.doc, rangeText(s.range, s.unit)),
        });
      }
      for (const c of index.description.constants) {
        out.push({ label: c.name, type: "constant", detail: `const = ${c.text}`, info: info(c.doc, c.unit) });
      }
      for (const o of index.description.options) {
        out.push({ label: o.name, type: "class", detail: "option", info: info(o.doc), apply: `${o.name}(` });
      }
      for (const b of index.description.behaviors) {
        out.push({ label: b.name, type: "function", detail: "basic behavior", info: info(b.doc), apply: `${b.name}(` });
      }
    }
    for (const k of VALUE_KEYWORDS) out.push({ label: k, type: "keyword", detail: "value", boost: -1 });
    for (const k of KEYWORDS) {
      if (!VALUE_KEYWORDS.includes(k)) out.push({ label: k, type: "keyword", boost: -2 });
    }
    return out;
  }

  complete(context: CompletionContext): CompletionResult | null {
    const word = context.matchBefore(WORD);
    if (!word && !context.explicit) return null;
    const from = word ? word.from : context.pos;
    const doc = context.state.doc;
    const text = doc.toString();
    if (inCommentOrString(text, from)) return null;
    const before = text.slice(Math.max(0, from - 4000), from);
    const typed = word?.text ?? "";
    const result = (options: Completion[]): CompletionResult | null =>
      options.length ? { from, options, validFor: VALID_FOR } : null;

    if (/\bgoto\s+$/.test(before)) return result(this.states(text));
    if (typed.startsWith("@")) return result(this.optionParams(text));

    const call = openCall(before);
    if (call && this.calleeParams(call.callee)) {
      const argPart = call.argText.split(",").pop() ?? "";
      if (/^\s*$/.test(argPart)) return result(this.paramNames(call.callee, call.argText));
      const value = argPart.match(new RegExp(`^\\s*(${IDENT})\\s*=\\s*$`));
      if (value && value[1]) {
        const param = this.calleeParams(call.callee)?.find((p) => p.short_name === value[1]);
        if (param?.enum) return result([...this.enumElements(param.enum), ...this.general()]);
      }
    }
    const comparison = before.match(new RegExp(`(@?${IDENT})\\s*(?:==|!=)\\s*$`));
    const assignment = before.match(new RegExp(`(?:^|[;{}])\\s*(${IDENT})\\s*=\\s*$`));
    const head = comparison?.[1] ?? assignment?.[1];
    if (head) {
      const enumName = this.enumOf(head, text);
      if (enumName) return result([...this.enumElements(enumName), ...this.general()]);
    }
    return result(this.general());
  }
}

/// A completion source over `description` (null: keywords only, before the first hello).
export function xabslCompletionSource(description: BehaviorDescription | null): CompletionSource {
  const completer = new Completer(description);
  return (context) => completer.complete(context);
}

/// The completion extension: language data, so it serves XABSL documents only. Put it in a
/// `Compartment` and reconfigure it with the new description on every hello.
export function xabslCompletion(description: BehaviorDescription | null): Extension {
  return xabslLanguage.data.of({ autocomplete: xabslCompletionSource(description) });
}
