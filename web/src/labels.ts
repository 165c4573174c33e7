/// Placing the robots' labels on the field so that no two overlap: each label tries a few spots
/// around its robot (below, above, right, left, then further below and above) and takes the
/// first that is free of the labels already placed and of every robot's disc; a label with no
/// free spot is left out (the team strip still names the role).

/// A label's box in canvas pixels (`x`, `y`: top left).
export interface LabelBox {
  x: number;
  y: number;
  w: number;
  h: number;
  text: string;
}

/// What to place: a robot at `cx`, `cy` with disc `radius`, and a label `w` x `h`.
export interface LabelRequest {
  cx: number;
  cy: number;
  radius: number;
  w: number;
  h: number;
  text: string;
}

const overlaps = (a: LabelBox, b: LabelBox): boolean => a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;

/// Whether box `a` touches the disc at `cx`, `cy` of radius `r`.
function hitsDisc(a: LabelBox, cx: number, cy: number, r: number): boolean {
  const nx = Math.max(a.x, Math.min(cx, a.x + a.w));
  const ny = Math.max(a.y, Math.min(cy, a.y + a.h));
  return (nx - cx) ** 2 + (ny - cy) ** 2 < r * r;
}

/// One box per request, in order, or null where no spot is free.
export function placeLabels(requests: readonly LabelRequest[], gap = 2): Array<LabelBox | null> {
  const placed: LabelBox[] = [];
  return requests.map((q) => {
    const below = q.cy + q.radius + gap;
    const above = q.cy - q.radius - gap - q.h;
    const middle = q.cy - q.h / 2;
    const spots: Array<[number, number]> = [
      [q.cx - q.w / 2, below],
      [q.cx - q.w / 2, above],
      [q.cx + q.radius + gap, middle],
      [q.cx - q.radius - gap - q.w, middle],
      [q.cx - q.w / 2, below + q.h + gap],
      [q.cx - q.w / 2, above - q.h - gap],
    ];
    for (const [x, y] of spots) {
      const box = { x, y, w: q.w, h: q.h, text: q.text };
      if (placed.some((p) => overlaps(p, box))) continue;
      if (requests.some((r) => hitsDisc(box, r.cx, r.cy, r.radius))) continue;
      placed.push(box);
      return box;
    }
    return null;
  });
}
