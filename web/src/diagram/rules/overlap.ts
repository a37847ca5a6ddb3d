// A move may not put a block onto another (issue 36): the moved blocks' rectangles, shifted by
// the move, may touch other blocks' edges but not overlap them. Text labels are notes and may
// lie anywhere; wires are not blocks.
import type { ElementKind } from '../../doc';

export interface Box {
  id: string;
  x: number;
  y: number;
  width: number;
  height: number;
  kind?: ElementKind;
  /** An action block's step: it moves with its step. */
  step?: string;
}

const solid = (b: Box) => !!b.kind && b.kind !== 'text';

/** Whether two boxes overlap (sharing an edge is not overlapping). */
export function overlap(a: Box, b: Box): boolean {
  return a.x < b.x + b.width && b.x < a.x + a.width && a.y < b.y + b.height && b.y < a.y + a.height;
}

/** Whether moving `moved` by `delta` puts one of them onto a block of `all` that does not move. */
export function movesOntoAnother(moved: Box[], delta: { x: number; y: number }, all: Box[]): boolean {
  const ids = new Set(moved.map((m) => m.id));
  const along = all.filter((b) => !ids.has(b.id) && !!b.step && ids.has(b.step));
  for (const b of along) ids.add(b.id);
  const others = all.filter((b) => solid(b) && !ids.has(b.id));
  return [...moved, ...along].filter(solid).some((m) => {
    const at = { ...m, x: m.x + delta.x, y: m.y + delta.y };
    return others.some((o) => overlap(at, o));
  });
}
