/// A unified diff of two texts by lines, for the editor's "changed on disk" choice: what taking
/// the file's version would do to the buffer ("-" lines are the buffer's, "+" the file's).
///
/// The common head and tail are cut first (an edit is usually a few lines of a file), then the
/// middle is compared by a longest common subsequence; a middle too large for that (over
/// MAX_CELLS line pairs) is shown as removed and added whole, which is still a true diff.

const MAX_CELLS = 4_000_000;

export type DiffLine = { kind: " " | "-" | "+"; text: string };

function middle(a: readonly string[], b: readonly string[]): DiffLine[] {
  const n = a.length;
  const m = b.length;
  if (n * m > MAX_CELLS) return [...a.map((text) => ({ kind: "-" as const, text })), ...b.map((text) => ({ kind: "+" as const, text }))];
  // lcs[i][j]: the longest common subsequence of a[i..] and b[j..]
  const lcs: Uint32Array[] = Array.from({ length: n + 1 }, () => new Uint32Array(m + 1));
  for (let i = n - 1; i >= 0; i--) {
    const row = lcs[i] as Uint32Array;
    const below = lcs[i + 1] as Uint32Array;
    for (let j = m - 1; j >= 0; j--) row[j] = a[i] === b[j] ? (below[j + 1] as number) + 1 : Math.max(below[j] as number, row[j + 1] as number);
  }
  const out: DiffLine[] = [];
  let i = 0;
  let j = 0;
  while (i < n || j < m) {
    if (i < n && j < m && a[i] === b[j]) {
      out.push({ kind: " ", text: a[i] as string });
      i++;
      j++;
    } else if (i < n && (j === m || ((lcs[i + 1] as Uint32Array)[j] as number) >= ((lcs[i] as Uint32Array)[j + 1] as number))) {
      out.push({ kind: "-", text: a[i] as string }); // removals before additions, as diff prints them
      i++;
    } else {
      out.push({ kind: "+", text: b[j] as string });
      j++;
    }
  }
  return out;
}

/// The changed lines of `before` → `after` with `context` unchanged lines around each change;
/// "…" stands for the lines left out between two changes. Empty when the texts are equal.
export function lineDiff(before: string, after: string, context = 2): DiffLine[] {
  const a = before.split(/\r\n|\r|\n/);
  const b = after.split(/\r\n|\r|\n/);
  let head = 0;
  while (head < a.length && head < b.length && a[head] === b[head]) head++;
  let tail = 0;
  while (tail < a.length - head && tail < b.length - head && a[a.length - 1 - tail] === b[b.length - 1 - tail]) tail++;
  const all: DiffLine[] = [
    ...a.slice(0, head).map((text) => ({ kind: " " as const, text })),
    ...middle(a.slice(head, a.length - tail), b.slice(head, b.length - tail)),
    ...a.slice(a.length - tail).map((text) => ({ kind: " " as const, text })),
  ];
  const keep = all.map(() => false);
  all.forEach((line, k) => {
    if (line.kind === " ") return;
    for (let c = Math.max(0, k - context); c <= Math.min(all.length - 1, k + context); c++) keep[c] = true;
  });
  const out: DiffLine[] = [];
  let skipped = false;
  all.forEach((line, k) => {
    if (keep[k]) {
      if (skipped && out.length) out.push({ kind: " ", text: "…" });
      skipped = false;
      out.push(line);
    } else skipped = true;
  });
  return out;
}
