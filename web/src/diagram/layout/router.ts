// Orthogonal wire routing around blocks and labels, the same router as sfc-doc's route.rs
// (shared cases: crates/sfc-doc/tests/routes.json): straight down when the pins are aligned and
// nothing is in the way; else one horizontal run between the pins at the middle height or the
// nearest free one; else a vertical lane beside the obstacles. Going down, no run goes back
// up, so a wire never overshoots and loops back; the first candidate that crosses no block or
// label wins (the one crossing fewest when none is free).
import type { Point } from '../../doc';

export const STUB = 10;
const GRID = 10;

export interface Rect {
  x: number;
  y: number;
  width: number;
  height: number;
}

/** Whether segment a–b (horizontal or vertical) runs through the interior of `r`. */
export function crosses(a: Point, b: Point, r: Rect): boolean {
  const E = 0.5;
  if (Math.abs(a.y - b.y) < 1e-9) {
    const x1 = Math.min(a.x, b.x);
    const x2 = Math.max(a.x, b.x);
    return a.y > r.y + E && a.y < r.y + r.height - E && x1 < r.x + r.width - E && x2 > r.x + E;
  }
  const y1 = Math.min(a.y, b.y);
  const y2 = Math.max(a.y, b.y);
  return a.x > r.x + E && a.x < r.x + r.width - E && y1 < r.y + r.height - E && y2 > r.y + E;
}

/** How many obstacles a polyline runs through. */
export function hits(points: Point[], obstacles: Rect[]): number {
  let n = 0;
  for (const r of obstacles) {
    for (let i = 1; i < points.length; i++) {
      if (crosses(points[i - 1], points[i], r)) {
        n++;
        break;
      }
    }
  }
  return n;
}

function length(points: Point[]): number {
  let l = 0;
  for (let i = 1; i < points.length; i++) l += Math.abs(points[i].x - points[i - 1].x) + Math.abs(points[i].y - points[i - 1].y);
  return l;
}

/** Drops repeated points and points in the middle of a straight run. */
export function simplify(points: Point[]): Point[] {
  const out: Point[] = [];
  for (const q of points) {
    const l = out[out.length - 1];
    if (l && Math.abs(l.x - q.x) < 1e-9 && Math.abs(l.y - q.y) < 1e-9) continue;
    if (out.length >= 2) {
      const a = out[out.length - 2];
      const b = out[out.length - 1];
      const straight = (Math.abs(a.x - b.x) < 1e-9 && Math.abs(b.x - q.x) < 1e-9) || (Math.abs(a.y - b.y) < 1e-9 && Math.abs(b.y - q.y) < 1e-9);
      if (straight) out.pop();
    }
    out.push({ x: q.x, y: q.y });
  }
  return out;
}

const snap = (v: number) => Math.round(v / GRID) * GRID;

/** The Z-shaped candidates (down, across, down), from the middle height outwards. */
function zRoutes(s: Point, e: Point): Point[][] {
  const out: Point[][] = [];
  if (e.y <= s.y) return out;
  // Pins closer than two stubs: the run halfway.
  const stub = Math.min(STUB, (e.y - s.y) / 2);
  const lo = s.y + stub;
  const hi = e.y - stub;
  const mid = hi - lo < GRID ? (lo + hi) / 2 : Math.min(hi, Math.max(lo, snap((lo + hi) / 2)));
  const ys = [mid];
  for (let k = 1; mid - k * GRID >= lo || mid + k * GRID <= hi; k++) {
    if (mid - k * GRID >= lo) ys.push(mid - k * GRID);
    if (mid + k * GRID <= hi) ys.push(mid + k * GRID);
  }
  for (const y of [lo, hi]) if (!ys.includes(y)) ys.push(y);
  for (const y of ys.slice(0, 64)) out.push([s, { x: s.x, y }, { x: e.x, y }, e]);
  return out;
}

/** The lane candidates: down a stub, across to a vertical lane beside an obstacle (or the
 *  hint), along it, across above the end, down into it; the hint first, then shortest first. */
function laneRoutes(s: Point, e: Point, obstacles: Rect[], laneHint?: number): Point[][] {
  const below = e.y > s.y;
  const top = Math.min(s.y, e.y) - STUB;
  const bottom = Math.max(s.y, e.y) + STUB;
  const lanes: number[] = [];
  if (laneHint !== undefined) lanes.push(snap(laneHint));
  for (const r of obstacles) {
    if (r.y < bottom + 40 && r.y + r.height > top - 40) {
      lanes.push(snap(r.x) - GRID);
      lanes.push(snap(r.x + r.width) + GRID);
    }
  }
  lanes.push(Math.max(s.x, e.x) + 2 * GRID);
  lanes.push(Math.min(s.x, e.x) - 2 * GRID);
  const sorted = [...new Set(lanes)].sort((a, b) => a - b);
  const hint = laneHint === undefined ? undefined : snap(laneHint);
  const starts = [s.y + STUB, s.y + 2 * STUB, s.y + 3 * STUB];
  const ends = [e.y - STUB, e.y - 2 * STUB, e.y - 3 * STUB];
  const routes: { hinted: boolean; len: number; r: Point[] }[] = [];
  for (const x of sorted) {
    for (const y1 of starts) {
      for (const y2 of ends) {
        if (below && y2 < y1) continue;
        const r = [s, { x: s.x, y: y1 }, { x, y: y1 }, { x, y: y2 }, { x: e.x, y: y2 }, e];
        routes.push({ hinted: hint === x, len: length(r), r });
      }
    }
  }
  routes.sort((a, b) => Number(b.hinted) - Number(a.hinted) || a.len - b.len);
  return routes.map((l) => l.r);
}

/** The route from output pin `s` to input pin `e` around `obstacles`: the whole polyline with
 *  both pins (two points for a straight wire). `laneHint`: a vertical run the user asked for. */
export function route(s: Point, e: Point, obstacles: Rect[], laneHint?: number): Point[] {
  let best: { n: number; c: Point[] } | undefined;
  // Cheapest first: straight, then one horizontal run, then lanes (built only when needed).
  const stages: (() => Point[][])[] = [
    () => (Math.abs(s.x - e.x) < 0.5 && e.y > s.y ? [[s, e]] : []),
    () => zRoutes(s, e),
    () => laneRoutes(s, e, obstacles, laneHint),
  ];
  if (laneHint !== undefined) stages.splice(1, 0, () => laneRoutes(s, e, obstacles, laneHint).slice(0, 9));
  for (const stage of stages) {
    for (const c of stage()) {
      const n = hits(c, obstacles);
      if (n === 0) return simplify(c);
      if (!best || n < best.n) best = { n, c };
    }
  }
  return simplify(best?.c ?? [s, e]);
}
