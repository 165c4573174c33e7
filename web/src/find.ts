/// Find by name across a behavior set: options and the states of every option, ranked so that
/// what a person typed whole comes first (exact, then prefix, then word start, then anywhere).
/// Pure: the graph panel's search box lists these and jumps to the one chosen.
import type { Option } from "./description";

export interface Found {
  kind: "option" | "state";
  /// the option's id (for a state: the option it belongs to)
  option: number;
  /// the state's id within its option (states only)
  state?: number;
  /// what is shown: the option's name, or `state` with its option beside it
  name: string;
  optionName: string;
  /// smaller is better
  rank: number;
}

/// How well `name` matches the lower-cased query `q`: 0 exact, 1 prefix, 2 a word of it starts
/// so (words split at `_`, `.` and case changes), 3 anywhere; null: no match.
export function matchRank(name: string, q: string): number | null {
  const lower = name.toLowerCase();
  if (!q) return null;
  if (lower === q) return 0;
  if (lower.startsWith(q)) return 1;
  const words = name.split(/[_.\s]+|(?<=[a-z0-9])(?=[A-Z])/).map((w) => w.toLowerCase());
  let at = 0;
  for (const w of words) {
    at = lower.indexOf(w, at);
    if (w && lower.startsWith(q, at)) return 2;
    at += w.length;
  }
  return lower.includes(q) ? 3 : null;
}

/// Options and states whose names match `query`, best first (options before states of equal
/// rank, then by name), at most `limit`.
export function find(options: readonly Option[], query: string, limit = 50): Found[] {
  const q = query.trim().toLowerCase();
  if (!q) return [];
  const out: Found[] = [];
  for (const o of options) {
    const r = matchRank(o.name, q);
    if (r !== null) out.push({ kind: "option", option: o.id, name: o.name, optionName: o.name, rank: r * 2 });
    for (const st of o.states) {
      const rs = matchRank(st.name, q);
      if (rs !== null) out.push({ kind: "state", option: o.id, state: st.id, name: st.name, optionName: o.name, rank: rs * 2 + 1 });
    }
  }
  out.sort((a, b) => a.rank - b.rank || a.name.localeCompare(b.name) || a.optionName.localeCompare(b.optionName));
  return out.slice(0, limit);
}
