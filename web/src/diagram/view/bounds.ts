// The extent of the chart as drawn, labels beside blocks included (for scrollbars, "fit" and
// the SVG export).
import { shapesOf, connectionsOf, type Service } from '../model';
import { textWidth } from '../render/svg';

export interface Rect {
  x: number;
  y: number;
  width: number;
  height: number;
}

export function chartBounds(elementRegistry: Service): Rect | undefined {
  let x0 = Infinity;
  let y0 = Infinity;
  let x1 = -Infinity;
  let y1 = -Infinity;
  const add = (x: number, y: number, r: number, b: number) => {
    x0 = Math.min(x0, x);
    y0 = Math.min(y0, y);
    x1 = Math.max(x1, r);
    y1 = Math.max(y1, b);
  };
  for (const s of shapesOf(elementRegistry)) {
    const e = s.businessObject;
    let right = s.x + s.width;
    if (e.kind === 'transition' && !e.hideLabel) {
      const lines = (e.condition ?? e.name ?? '').split('\n');
      const w = Math.max(0, ...lines.slice(0, 3).map((l) => textWidth(l.trim(), 12) * 1.15));
      right += 20 + Math.min(w, 330);
    } else if (e.kind === 'jump' && !e.hideLabel) {
      right += 8 + textWidth(e.target ?? '?', 12);
    }
    // Room for highlight frames, pin stubs and labels under blocks.
    add(s.x - 12, s.y - 12, right + 12, s.y + s.height + 20);
  }
  for (const c of connectionsOf(elementRegistry)) {
    for (const p of c.waypoints) add(p.x - 2, p.y - 2, p.x + 2, p.y + 2);
  }
  if (!Number.isFinite(x0)) return undefined;
  return { x: x0, y: y0, width: x1 - x0, height: y1 - y0 };
}
