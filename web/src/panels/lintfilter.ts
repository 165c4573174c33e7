/// Which warnings the editor hides, per behavior set, remembered in the browser (localStorage).
///
/// A team's set can carry a hundred lint warnings the original compiler never printed; the user
/// hides them per code ("unused-symbol"), or all lint at once: "as the original compiler", the
/// studio's twin of `xabsl compile --no-lint`, which leaves what the original prints. Errors are
/// never hidden. The choice is kept per behavior set (the example and the set's key), so another
/// set keeps its own.

/// The warnings the original compiler never prints (engine/lang/diagnostics.py `LINT_CODES`;
/// tests/lang/test_lint_codes.py keeps the two equal).
export const LINT_CODES: ReadonlySet<string> = new Set(["naming", "parameter-missing", "unreachable-option", "unreachable-state", "unused-symbol", "unused-behavior"]);

/// What one behavior set hides: codes, and whether all lint is (whatever codes appear later).
export interface Hidden {
  codes: Set<string>;
  allLint: boolean;
}

const PREFIX = "xabsl-studio.hidden-lint:";

/// A diagnostic as far as hiding goes.
export interface Filterable {
  severity?: string | number | undefined;
  code?: string | number | null | undefined;
}

function browserStorage(): Storage | null {
  try {
    return typeof localStorage === "undefined" ? null : localStorage;
  } catch {
    return null; // storage disabled: the choice lasts while the page does
  }
}

export class LintFilter {
  private readonly cache = new Map<string, Hidden>();

  constructor(private readonly storage: Storage | null = browserStorage()) {}

  /// The key of a behavior set: the example's name and the set's key (`behavior`).
  static setKey(example: string, program: string): string {
    return `${example}|${program}`;
  }

  hidden(set: string): Hidden {
    let found = this.cache.get(set);
    if (!found) {
      found = { codes: new Set(), allLint: false };
      try {
        const raw = this.storage?.getItem(PREFIX + set);
        const data = raw ? (JSON.parse(raw) as { codes?: unknown; allLint?: unknown }) : null;
        if (data && Array.isArray(data.codes)) found.codes = new Set(data.codes.filter((c): c is string => typeof c === "string"));
        if (data) found.allLint = data.allLint === true;
      } catch {
        // unreadable: nothing hidden
      }
      this.cache.set(set, found);
    }
    return found;
  }

  /// Whether `d` is hidden in `set` (an error never is).
  hides(set: string, d: Filterable): boolean {
    if (d.severity === "error" || d.severity === 1) return false;
    const code = String(d.code ?? "");
    const h = this.hidden(set);
    return h.codes.has(code) || (h.allLint && LINT_CODES.has(code));
  }

  setCode(set: string, code: string, hide: boolean): void {
    const h = this.hidden(set);
    if (hide) h.codes.add(code);
    else {
      h.codes.delete(code);
      if (LINT_CODES.has(code)) h.allLint = false;
    }
    this.save(set, h);
  }

  /// Hide every lint code (as the original compiler prints), or show everything again.
  setAllLint(set: string, hide: boolean): void {
    const h = this.hidden(set);
    h.allLint = hide;
    if (!hide) h.codes.clear();
    this.save(set, h);
  }

  private save(set: string, h: Hidden): void {
    try {
      if (!h.allLint && !h.codes.size) this.storage?.removeItem(PREFIX + set);
      else this.storage?.setItem(PREFIX + set, JSON.stringify({ codes: [...h.codes].sort(), allLint: h.allLint }));
    } catch {
      // full or disabled storage: the choice lasts while the page does
    }
  }
}
