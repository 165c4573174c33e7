/// Checking what a person typed into a parameter or override field against its declaration
/// (type and declared range), so that the form can say what is wrong before anything is sent.
import { parseRange } from "./description";

/// A checked number, or why the text is not one the declaration accepts.
export type Checked = { ok: true; value: number } | { ok: false; error: string };

/// Check `text` against a declared `range` ("lo..hi", either side may be empty).
export function checkNumber(text: string, range: string | null): Checked {
  const trimmed = text.trim();
  if (trimmed === "") return { ok: false, error: "a number is required" };
  const value = Number(trimmed);
  if (!Number.isFinite(value)) return { ok: false, error: `${trimmed} is not a number` };
  const { min, max } = parseRange(range);
  if ((min !== undefined && value < min) || (max !== undefined && value > max)) {
    const lo = min === undefined ? "" : String(min);
    const hi = max === undefined ? "" : String(max);
    return { ok: false, error: `${trimmed} is outside the declared range ${lo}..${hi}` };
  }
  return { ok: true, value };
}
