/// Which behavior set a behavior file belongs to, and which of the compiler's diagnostics an
/// editor of that file shows.
///
/// A file may be read by several behavior sets (the chase team includes the example team's
/// symbols and basic behaviors). Each set's lint speaks about its own use of the file ("'walk' is
/// never called" is true of chase, not of the team that owns the file), so the editor shows the
/// warnings of the file's home set only; errors of every set stay, since they stop that set from
/// reloading.
import type { ServerDiagnostic } from "./xabsl/lint";

/// A diagnostic as the server sends it for one behavior set (`program`: the set's key).
export type SetDiagnostic = ServerDiagnostic & { program?: string };

/// The home behavior set of `path` among `programs` (keys are folders relative to the example):
/// the one whose folder holds the file (the deepest, if folders nest), else null.
export function homeProgram(path: string, programs: readonly string[]): string | null {
  const clean = path.replace(/\\/g, "/").replace(/^\.\//, "");
  let best: string | null = null;
  for (const key of programs) {
    const folder = key.replace(/\\/g, "/").replace(/\/$/, "");
    if ((folder === "" || folder === "." || clean.startsWith(`${folder}/`)) && (best === null || folder.length > best.length)) best = key;
  }
  return best;
}

/// The diagnostics an editor of `path` shows: every error, and the warnings and hints of the
/// file's home set (all of them when the file has none); the same finding reported by two sets
/// is shown once. Within one set nothing is dropped, so the home set's count is what
/// `xabsl compile` prints for it.
export function diagnosticsFor(path: string, diagnostics: readonly SetDiagnostic[], programs: readonly string[]): SetDiagnostic[] {
  const home = homeProgram(path, programs);
  const seen = new Map<string, string | undefined>();
  const out: SetDiagnostic[] = [];
  for (const d of diagnostics) {
    if (d.severity !== "error" && home !== null && d.program !== undefined && d.program !== home) continue;
    const span = d.span;
    const key = `${d.severity}|${d.code}|${span?.file ?? d.file}|${span?.line}|${span?.col}|${d.message}`;
    if (seen.has(key) && seen.get(key) !== d.program) continue; // another set's report of it
    seen.set(key, d.program);
    out.push(d);
  }
  return out;
}
