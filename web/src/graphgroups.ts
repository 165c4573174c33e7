/// The option groups of a grouped option graph (`/api/graph-groups`, engine/emit/groups.py) and
/// how the live activation path maps onto what is drawn: an option of a collapsed group is drawn
/// as its group's node `group_<n>`, a call touching a collapsed group as `gcall_<from>_<to>`, a
/// call between two drawn nodes keeps the plain graph's `call_<i>_<o|b><j>`. Pure.

import type { OptionGroupJson } from "./messages.gen";

/// One group of an option graph (`/api/graph-groups`; defined in server/protocol/rest.py).
export type OptionGroup = OptionGroupJson;

/// Above this many options an option graph opens as its overview (every group collapsed).
export const OVERVIEW_ABOVE = 40;

/// The separator of group keys in the `collapse` query parameter (server/api/app.py).
export const COLLAPSE_SEPARATOR = "|";

export class GroupMap {
  private readonly optionGroup = new Map<number, number>();
  private readonly behaviorGroup = new Map<number, number>();

  constructor(
    readonly groups: readonly OptionGroup[],
    /// keys of the collapsed groups
    readonly collapsed: ReadonlySet<string>,
  ) {
    groups.forEach((g, n) => {
      for (const o of g.options) this.optionGroup.set(o, n);
      for (const b of g.behaviors) this.behaviorGroup.set(b, n);
    });
  }

  /// The group (its position) of an option or a behavior; undefined: in no group.
  groupOf(kind: "option" | "behavior", id: number): number | undefined {
    return (kind === "option" ? this.optionGroup : this.behaviorGroup).get(id);
  }

  isCollapsed(n: number | undefined): boolean {
    const g = n === undefined ? undefined : this.groups[n];
    return g !== undefined && this.collapsed.has(g.key);
  }

  /// The short name of what draws option/behavior `id`: `g<n>` for a collapsed group, else `o<id>`/`b<id>`.
  private drawn(kind: "option" | "behavior", id: number): string {
    const n = this.groupOf(kind, id);
    return this.isCollapsed(n) ? `g${n}` : `${kind === "option" ? "o" : "b"}${id}`;
  }

  /// The element id that draws option/behavior `id`.
  nodeId(kind: "option" | "behavior", id: number): string {
    const d = this.drawn(kind, id);
    return d[0] === "g" ? `group_${d.slice(1)}` : `${kind}_${id}`;
  }

  /// The element id of the call from option `caller` to option/behavior `callee` (null: inside
  /// one collapsed group, not drawn).
  callId(caller: number, kind: "option" | "behavior", callee: number): string | null {
    const from = this.drawn("option", caller);
    const to = this.drawn(kind, callee);
    if (from === to) return null;
    if (from[0] !== "g" && to[0] !== "g") return `call_${caller}_${to}`;
    return `gcall_${from}_${to}`;
  }

  /// The `collapse` query value for these collapsed groups.
  query(): string {
    return [...this.collapsed].join(COLLAPSE_SEPARATOR);
  }
}
