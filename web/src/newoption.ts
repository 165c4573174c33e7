/// A new option file: its source from a name, parameters and a doc line, where its include line
/// goes in the agents file, and the diff of that change (what the New option dialog shows before
/// anything is written). Pure functions; the dialog is panels/newoption.ts.

export type ParamType = "float" | "bool" | string; // a string other than float/bool: an enum's name

export interface NewParam {
  name: string;
  type: ParamType;
  /// decimal parameters only: a range (both or neither) and a unit
  min?: number | null;
  max?: number | null;
  unit?: string;
  doc?: string;
}

export interface NewOption {
  name: string;
  doc: string;
  params: NewParam[];
}

const NAME = /^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$/;
const KEYWORDS = new Set(["option", "state", "initial", "target", "decision", "action", "if", "else", "goto", "stay", "true", "false", "float", "bool", "enum", "input", "output", "internal", "namespace", "include", "agent", "const", "behavior", "common", "state_time", "option_time", "action_done"]);

/// What is wrong with the dialog's values, one message per problem (empty: fine).
export function problems(option: NewOption, existingOptions: readonly string[], enums: readonly string[]): string[] {
  const out: string[] = [];
  if (!NAME.test(option.name)) out.push("name: starts with a letter or _, then letters, digits, _ (and . between parts)");
  else if (KEYWORDS.has(option.name)) out.push(`name: '${option.name}' is an XABSL keyword`);
  else if (existingOptions.includes(option.name)) out.push(`name: an option '${option.name}' exists already`);
  const seen = new Set<string>();
  option.params.forEach((p, i) => {
    const where = `parameter ${i + 1}`;
    if (!/^[A-Za-z_][A-Za-z0-9_]*$/.test(p.name)) out.push(`${where}: a name of letters, digits and _`);
    else if (seen.has(p.name)) out.push(`${where}: '${p.name}' is there twice`);
    seen.add(p.name);
    if (p.type !== "float" && p.type !== "bool" && !enums.includes(p.type)) out.push(`${where}: unknown type '${p.type}'`);
    const hasMin = p.min !== null && p.min !== undefined;
    const hasMax = p.max !== null && p.max !== undefined;
    if (p.type === "float") {
      if (hasMin !== hasMax) out.push(`${where}: a range needs both ends`);
      if (hasMin && hasMax && !(Number.isFinite(p.min) && Number.isFinite(p.max))) out.push(`${where}: range ends must be finite numbers`);
      else if (hasMin && hasMax && (p.min as number) > (p.max as number)) out.push(`${where}: the range ${p.min}..${p.max} is empty`);
      if (p.unit && /["\n]/.test(p.unit)) out.push(`${where}: a unit without quotes or line breaks`);
    } else if (hasMin || hasMax || p.unit) out.push(`${where}: only decimal (float) parameters have a range or unit`);
  });
  if (/\*\//.test(option.doc)) out.push("doc: no */ inside the doc comment");
  return out;
}

function number(value: number): string {
  return String(value);
}

/// The source of the new option file.
export function optionSource(option: NewOption): string {
  const lines = [`/** ${option.doc.trim() || `${option.name}: what this option decides, in one sentence.`} */`, `option ${option.name} {`];
  for (const p of option.params) {
    if (p.doc?.trim()) lines.push(`  /** ${p.doc.trim()} */`);
    const type = p.type === "float" || p.type === "bool" ? p.type : `enum ${p.type}`;
    let decl = `  ${type} @${p.name}`;
    if (p.type === "float") {
      if (p.min !== null && p.min !== undefined && p.max !== null && p.max !== undefined) decl += ` [${number(p.min)}..${number(p.max)}]`;
      if (p.unit) decl += ` "${p.unit}"`;
    }
    lines.push(`${decl};`);
  }
  if (option.params.length) lines.push("");
  lines.push("  initial state start {", "    decision {", "      stay;", "    }", "    action {", "    }", "  }", "}", "");
  return lines.join("\n");
}

/// `to` (a path relative to the example folder) relative to the folder of `from`.
export function relativePath(from: string, to: string): string {
  const base = from.split("/").slice(0, -1);
  const target = to.split("/");
  let common = 0;
  while (common < base.length && common < target.length - 1 && base[common] === target[common]) common++;
  return [...base.slice(common).map(() => ".."), ...target.slice(common)].join("/");
}

/// The agents file's text with the include line of `optionPath` added: after the last include of
/// an option file in the same folder, else after the last include, else at the top.
export function addInclude(agentsText: string, agentsPath: string, optionPath: string): { text: string; line: number; include: string } {
  const include = `include "${relativePath(agentsPath, optionPath)}";`;
  const lines = agentsText.split("\n");
  const folder = relativePath(agentsPath, optionPath).split("/").slice(0, -1).join("/");
  let last = -1;
  let lastSameFolder = -1;
  lines.forEach((line, i) => {
    const m = /^\s*include\s+"([^"]*)"\s*;/.exec(line);
    if (!m) return;
    last = i;
    if ((m[1] as string).split("/").slice(0, -1).join("/") === folder) lastSameFolder = i;
  });
  const at = (lastSameFolder >= 0 ? lastSameFolder : last) + 1;
  lines.splice(at, 0, include);
  return { text: lines.join("\n"), line: at + 1, include };
}

/// A unified-style diff of one inserted line with up to `context` lines around it.
export function insertionDiff(before: string, after: string, context = 2): Array<{ kind: " " | "+" | "-"; line: number; text: string }> {
  const a = before.split("\n");
  const b = after.split("\n");
  let i = 0;
  while (i < a.length && i < b.length && a[i] === b[i]) i++;
  let ja = a.length - 1;
  let jb = b.length - 1;
  while (ja >= i && jb >= i && a[ja] === b[jb]) {
    ja--;
    jb--;
  }
  const out: Array<{ kind: " " | "+" | "-"; line: number; text: string }> = [];
  for (let k = Math.max(0, i - context); k < i; k++) out.push({ kind: " ", line: k + 1, text: a[k] as string });
  for (let k = i; k <= ja; k++) out.push({ kind: "-", line: k + 1, text: a[k] as string });
  for (let k = i; k <= jb; k++) out.push({ kind: "+", line: k + 1, text: b[k] as string });
  for (let k = jb + 1; k < Math.min(b.length, jb + 1 + context); k++) out.push({ kind: " ", line: k + 1, text: b[k] as string });
  return out;
}
