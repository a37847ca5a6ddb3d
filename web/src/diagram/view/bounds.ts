// The extent of the chart as drawn, labels beside blocks included (for scrollbars, "fit" and
// the SVG export).
import { shapesOf, connectionsOf, type Service } from '../model';
import { labelsOf } from '../drawing';

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
    // Room for highlight frames, pin stubs and labels under blocks.
    add(s.x - 12, s.y - 12, s.x + s.width + 12, s.y + s.height + 20);
    // Labels beside blocks, left ones included (a transition's name).
    for (const l of labelsOf(s.businessObject, s.width, s.height)) {
      add(s.x + l.x - 4, s.y + l.y - 4, s.x + l.x + l.width + 4, s.y + l.y + l.height + 4);
    }
  }
  for (const c of connectionsOf(elementRegistry)) {
    for (const p of c.waypoints) add(p.x - 2, p.y - 2, p.x + 2, p.y + 2);
  }
  if (!Number.isFinite(x0)) return undefined;
  return { x: x0, y: y0, width: x1 - x0, height: y1 - y0 };
}
