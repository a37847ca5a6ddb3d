// Geometry of SFC blocks on the canvas: default sizes, resize limits, pin positions and the
// orthogonal routing of wires between pins. Pins sit on the top (inputs) and bottom (outputs)
// edges, numbered left to right (crates/sfc-doc module doc).
import { connectPoints, withoutRedundantPoints } from 'diagram-js/lib/layout/ManhattanLayout';
import { pinCounts, type Element, type ElementKind, type Point } from '../doc';

/** The grid step in canvas units; moves, creation and resizing snap to it. */
export const GRID = 10;
/** Length of the vertical wire piece leaving an output pin or entering an input pin. */
export const STUB = 10;
/** Distance from a bar's end to its outermost pin. */
export const BAR_PAD = 10;
/** Smallest distance between two pins of a bar. */
export const PIN_GAP = 20;
/** A dragged wire end snaps to a free valid pin this close (canvas units). */
export const PIN_SNAP = 15;

export interface Size {
  w: number;
  h: number;
}

export interface Limits {
  min: Size;
  max: Size;
  /** Which sides can be dragged: 'all', 'width' (bars) or 'none' (transitions). */
  resize: 'all' | 'width' | 'none';
}

export function isBar(kind: ElementKind): boolean {
  return (
    kind === 'selectionDivergence' ||
    kind === 'selectionConvergence' ||
    kind === 'simultaneousDivergence' ||
    kind === 'simultaneousConvergence'
  );
}

/** The size of a new block of `kind`. */
export function defaultSize(kind: ElementKind): Size {
  switch (kind) {
    case 'step':
      return { w: 80, h: 40 };
    case 'transition':
      return { w: 40, h: 20 };
    case 'jump':
      return { w: 20, h: 20 };
    case 'text':
      return { w: 140, h: 40 };
    case 'actionBlock':
      return { w: 180, h: 20 };
    default:
      return { w: 120, h: 10 };
  }
}

/** Resize limits of a block; bars get wider minimums with more pins. */
export function limits(e: Pick<Element, 'kind' | 'pins' | 'associations'>): Limits {
  switch (e.kind) {
    case 'step':
      return { min: { w: 40, h: 30 }, max: { w: 400, h: 200 }, resize: 'all' };
    case 'transition':
      return { min: { w: 40, h: 20 }, max: { w: 40, h: 20 }, resize: 'none' };
    case 'jump':
      return { min: { w: 20, h: 20 }, max: { w: 60, h: 60 }, resize: 'all' };
    case 'text':
      return { min: { w: 20, h: 20 }, max: { w: 2000, h: 1000 }, resize: 'all' };
    case 'actionBlock': {
      const rows = Math.max(1, e.associations?.length ?? 0);
      return { min: { w: 60, h: 16 * rows }, max: { w: 1000, h: 60 * rows }, resize: 'all' };
    }
    default:
      return { min: { w: minBarWidth(e.pins), h: 10 }, max: { w: 2000, h: 10 }, resize: 'width' };
  }
}

/** The narrowest bar that still holds `pins` branch pins `PIN_GAP` apart. */
export function minBarWidth(pins: number | undefined): number {
  const n = Math.max(2, pins ?? 2);
  return Math.max(40, 2 * BAR_PAD + (n - 1) * PIN_GAP);
}

/** The most branch pins a bar of width `w` holds. */
export function maxPinsForWidth(w: number): number {
  return Math.max(2, Math.floor((w - 2 * BAR_PAD) / PIN_GAP) + 1);
}

export interface Box {
  x: number;
  y: number;
  width: number;
  height: number;
}

/** The x of pin `i` of `count` pins along a block's edge: one pin sits in the middle, several
 *  are equidistant between the bar's ends, each offset rounded to the grid so branch wires run
 *  on grid lines. */
export function pinX(box: Box, count: number, i: number): number {
  if (count <= 1) return box.x + box.width / 2;
  const span = box.width - 2 * BAR_PAD;
  const off = BAR_PAD + (span * i) / (count - 1);
  const snapped = Math.round(off / GRID) * GRID;
  // Rounding must never push a pin off the bar or onto its neighbour.
  const clamped = Math.min(box.width - BAR_PAD, Math.max(BAR_PAD, snapped));
  return box.x + clamped;
}

/** Position of input pin `i` (top edge). */
export function inputPin(e: Pick<Element, 'kind' | 'pins'>, box: Box, i: number): Point {
  return { x: pinX(box, pinCounts(e).inputs, i), y: box.y };
}

/** Position of output pin `i` (bottom edge). */
export function outputPin(e: Pick<Element, 'kind' | 'pins'>, box: Box, i: number): Point {
  return { x: pinX(box, pinCounts(e).outputs, i), y: box.y + box.height };
}

function pt(p: Point): Point {
  return { x: p.x, y: p.y };
}

function aligned(a: Point, b: Point): boolean {
  return a.x === b.x || a.y === b.y;
}

/**
 * Makes a polyline a valid wire from `start` (an output pin) to `end` (an input pin): ends
 * exactly on the pins, the first segment leaving downwards and the last entering from above,
 * every segment horizontal or vertical, no redundant points. With `keepMovedEnds` (the user
 * dragged the first or last segment away from its pin) a moved end stays as a bend, a stub
 * away from the pin, instead of snapping back.
 */
export function normalizeWire(points: Point[], start: Point, end: Point, keepMovedEnds = false): Point[] {
  const inner = points.slice(1, -1).map(pt);
  if (keepMovedEnds && points.length >= 2) {
    const a = points[0];
    const b = points[points.length - 1];
    if (a.x !== start.x || a.y !== start.y) inner.unshift({ x: a.x, y: Math.max(a.y, start.y + STUB) });
    if (b.x !== end.x || b.y !== end.y) inner.push({ x: b.x, y: Math.min(b.y, end.y - STUB) });
  }
  const out: Point[] = [pt(start)];
  // Leave the output pin downwards.
  const first = inner[0] ?? end;
  if (!(first.x === start.x && first.y > start.y)) {
    const stub = { x: start.x, y: start.y + STUB };
    if (inner.length === 0 && end.y >= stub.y + STUB) {
      return withoutRedundantPoints(connectPoints(pt(start), pt(end), 'v:v'));
    }
    out.push(stub);
  }
  for (const p of inner) push(out, p);
  // Enter the input pin from above.
  const last = out[out.length - 1];
  if (!(last.x === end.x && last.y < end.y)) {
    push(out, { x: end.x, y: end.y - STUB });
  }
  push(out, pt(end));
  return withoutRedundantPoints(dedupe(out));
}

/** Appends `p`, inserting a corner when the last segment would be diagonal; the corner turns
 *  so that the path alternates between vertical and horizontal runs. */
function push(out: Point[], p: Point) {
  const a = out[out.length - 1];
  if (!aligned(a, p)) {
    const before = out[out.length - 2];
    const lastVertical = before ? before.x === a.x : true;
    out.push(lastVertical ? { x: p.x, y: a.y } : { x: a.x, y: p.y });
  }
  out.push(p);
}

function dedupe(points: Point[]): Point[] {
  return points.filter((p, i) => i === 0 || p.x !== points[i - 1].x || p.y !== points[i - 1].y);
}
