/// The behavior description: the JSON document of `xabsl compile --json` (engine/emit/json.py,
/// schema version 1), sent by the server in `hello` and again after every hot reload.
///
/// Ids are the IR's indices: an option's `id` is its IC index, a state's `id` its index in the
/// option, a symbol's `id` its index among the inputs or the outputs. `indexDescription` builds
/// the lookup tables every panel needs once per hello, so no panel searches lists on a tick.

export interface Span {
  file: string;
  line: number;
  col: number;
  end_line: number;
  end_col: number;
  start: number;
  end: number;
}

export type ValueType = "decimal" | "boolean" | "enum";

export interface Parameter {
  name: string;
  short_name: string;
  type: ValueType;
  enum: string | null;
  range: string | null;
  unit: string | null;
  doc: string | null;
  span: Span | null;
}

export interface Argument {
  param: string;
  type: ValueType;
  value: string;
}

export type Action =
  | { type: "option"; name: string; args: Argument[]; span: Span | null }
  | { type: "behavior"; name: string; args: Argument[]; span: Span | null }
  | { type: "assign"; symbol: string; value: string; span: Span | null };

export interface Leaf {
  to: string | null;
  stay: boolean;
  leaf: number;
  span: Span | null;
}

export interface IfNode {
  if: string;
  doc: string | null;
  span: Span | null;
  then: DecisionTree;
  else: DecisionTree;
}

export type DecisionTree = Leaf | IfNode;

export interface Transition {
  from: string;
  to: string | null;
  leaf: number;
  stay: boolean;
  span: Span | null;
}

export interface State {
  id: number;
  name: string;
  initial: boolean;
  target: boolean;
  coop: string;
  coop_count: number;
  doc: string | null;
  span: Span | null;
  actions: Action[];
  decision: DecisionTree;
}

export interface Call {
  state: string;
  type: "option" | "behavior";
  name: string;
}

export interface Option {
  id: number;
  name: string;
  file: string;
  doc: string | null;
  span: Span | null;
  params: Parameter[];
  initial_state: string;
  states: State[];
  transitions: Transition[];
  calls: Call[];
  common_decision: Array<{ if: string; doc: string | null; then: DecisionTree }>;
  common_action: Action[];
}

export interface BasicBehavior {
  id: number;
  name: string;
  doc: string | null;
  namespace: string;
  params: Parameter[];
  span: Span | null;
}

export interface SymbolBase {
  id: number;
  name: string;
  type: ValueType;
  enum: string | null;
  range: string | null;
  unit: string | null;
  doc: string | null;
  namespace: string;
  span: Span | null;
}

export interface InputSymbol extends SymbolBase {
  params: Parameter[];
}

export interface OutputSymbol extends SymbolBase {
  internal: boolean;
}

export interface Enumeration {
  name: string;
  elements: string[];
  internal: boolean;
  doc: string | null;
  span: Span | null;
}

export interface Constant {
  name: string;
  value: number;
  text: string;
  unit: string | null;
  doc: string | null;
  span: Span | null;
}

export interface AgentDeclaration {
  name: string;
  title: string;
  root: string;
  doc: string | null;
  span: Span | null;
}

export interface BehaviorDescription {
  version: number;
  title: string | null;
  platform: string | null;
  software_environment: string | null;
  files: string[];
  agents: AgentDeclaration[];
  options: Option[];
  behaviors: BasicBehavior[];
  inputs: InputSymbol[];
  outputs: OutputSymbol[];
  enums: Enumeration[];
  constants: Constant[];
}

/// Lookup tables over one description (built once per hello).
export interface DescriptionIndex {
  description: BehaviorDescription;
  optionById: Map<number, Option>;
  optionByName: Map<string, Option>;
  behaviorById: Map<number, BasicBehavior>;
  behaviorByName: Map<string, BasicBehavior>;
  inputByName: Map<string, InputSymbol>;
  outputByName: Map<string, OutputSymbol>;
  enumByName: Map<string, Enumeration>;
  constantByName: Map<string, Constant>;
  /// Per option id: leaf id -> transition (including `stay` leaves).
  transitions: Map<number, Map<string, Transition>>;
}

export function isLeaf(tree: DecisionTree): tree is Leaf {
  return (tree as Leaf).leaf !== undefined;
}

/// The order of a packed span's numbers after the file index (server/protocol/packing.py).
const SPAN_FIELDS = ["line", "col", "end_line", "end_col", "start", "end"] as const;

/// A description as the studio sends it, spans packed (`span_files` and
/// `[file index, line, col, end_line, end_col, start, end]`, server/protocol/packing.py), with
/// its spans as objects again; a description without `span_files` is returned as it is.
export function unpackDescription(packed: BehaviorDescription & { span_files?: string[] }): BehaviorDescription {
  const files = packed.span_files;
  if (!files) return packed;
  const unpack = (value: unknown): unknown => {
    if (Array.isArray(value)) return value.map(unpack);
    if (value === null || typeof value !== "object") return value;
    const out: Record<string, unknown> = {};
    for (const [key, item] of Object.entries(value)) {
      if (key === "span_files" || key === "derived") continue;
      if (key === "span" && Array.isArray(item)) {
        const span: Record<string, unknown> = { file: files[item[0] as number] };
        SPAN_FIELDS.forEach((field, i) => (span[field] = item[i + 1]));
        out[key] = span;
      } else out[key] = unpack(item);
    }
    return out;
  };
  const plain = unpack(packed) as BehaviorDescription;
  // derived data left off the wire (server/protocol/packing.py): rebuilt exactly as the server derives it
  const derived = (packed as { derived?: string[] }).derived ?? [];
  for (const option of plain.options) {
    if (derived.includes("transitions")) option.transitions = derivedTransitions(option);
    if (derived.includes("calls")) option.calls = derivedCalls(option);
  }
  return plain;
}

/// An option's transitions: each state's decision leaves in pre-order (then before else).
function derivedTransitions(option: Option): Transition[] {
  const out: Transition[] = [];
  for (const state of option.states) {
    const stack: Array<DecisionTree | null | undefined> = [state.decision];
    while (stack.length) {
      // no recursion: an else-if chain of a thousand links is a tree that deep
      const node = stack.pop();
      if (!node) continue;
      if ("if" in node) stack.push(node.else, node.then);
      else out.push({ from: state.name, to: node.to, leaf: node.leaf, stay: node.stay, span: node.span });
    }
  }
  return out;
}

/// An option's option and basic-behavior calls, in state and action order.
function derivedCalls(option: Option): Call[] {
  const calls: Call[] = [];
  for (const state of option.states) {
    for (const action of state.actions) if (action.type !== "assign") calls.push({ state: state.name, type: action.type, name: action.name });
  }
  return calls;
}

/// Build the lookup tables of a description.
export function indexDescription(description: BehaviorDescription): DescriptionIndex {
  const transitions = new Map<number, Map<string, Transition>>();
  for (const option of description.options) {
    const byLeaf = new Map<string, Transition>();
    for (const tr of option.transitions) byLeaf.set(`${tr.from}/${tr.leaf}`, tr);
    transitions.set(option.id, byLeaf);
  }
  return {
    description,
    optionById: new Map(description.options.map((o) => [o.id, o])),
    optionByName: new Map(description.options.map((o) => [o.name, o])),
    behaviorById: new Map(description.behaviors.map((b) => [b.id, b])),
    behaviorByName: new Map(description.behaviors.map((b) => [b.name, b])),
    inputByName: new Map(description.inputs.map((s) => [s.name, s])),
    outputByName: new Map(description.outputs.map((s) => [s.name, s])),
    enumByName: new Map(description.enums.map((e) => [e.name, e])),
    constantByName: new Map(description.constants.map((c) => [c.name, c])),
    transitions,
  };
}

/// The transition an option took when state `decidedIn` chose leaf `leaf`.
export function transitionOf(index: DescriptionIndex, optionId: number, decidedIn: string, leaf: number): Transition | undefined {
  return index.transitions.get(optionId)?.get(`${decidedIn}/${leaf}`);
}

/// The decision-tree leaf with id `leaf` in `tree`, with the path of conditions to it.
export function leafPath(tree: DecisionTree, leaf: number): Array<{ node: IfNode; taken: boolean }> | null {
  if (isLeaf(tree)) return tree.leaf === leaf ? [] : null;
  const inThen = leafPath(tree.then, leaf);
  if (inThen) return [{ node: tree, taken: true }, ...inThen];
  const inElse = leafPath(tree.else, leaf);
  if (inElse) return [{ node: tree, taken: false }, ...inElse];
  return null;
}

/// A short human text for a declared range and unit: "0..10000 mm".
export function rangeText(range: string | null, unit: string | null): string {
  return [range, unit].filter((x) => x).join(" ");
}

/// Parse a declared range "lo..hi" (either side may be empty) into numbers.
export function parseRange(range: string | null): { min?: number; max?: number } {
  if (!range) return {};
  const m = range.match(/^\s*(-?[0-9.]*)\s*\.\.\s*(-?[0-9.]*)\s*$/);
  if (!m) return {};
  const out: { min?: number; max?: number } = {};
  if (m[1] !== undefined && m[1] !== "" && !Number.isNaN(Number(m[1]))) out.min = Number(m[1]);
  if (m[2] !== undefined && m[2] !== "" && !Number.isNaN(Number(m[2]))) out.max = Number(m[2]);
  return out;
}
