// Read-only answers about what a canvas shows, in page (client) pixels: where a block and its
// pins are on screen. The browser tests (web/e2e) read them through `window.__sfc` to aim real
// mouse gestures; nothing here changes the chart.
import type { Point } from '../doc';
import { inputPin, outputPin } from './geometry';
import { diagramOf } from './index';
import { isConnection, type Service } from './model';
import type { CanvasHandle } from './types';

export interface ScreenBox {
  x: number;
  y: number;
  width: number;
  height: number;
}

/** The visible area in canvas units. */
export function viewOf(handle: CanvasHandle): { x: number; y: number; width: number; height: number; scale: number } {
  return diagramOf(handle).get('sfcView').view();
}

/** Canvas units → client pixels of the page. */
export function toScreen(handle: CanvasHandle, p: Point): Point {
  const diagram = diagramOf(handle);
  const view = diagram.get('sfcView').view();
  const rect = (diagram.get('canvas').getContainer() as HTMLElement).getBoundingClientRect();
  return { x: rect.left + (p.x - view.x) * view.scale, y: rect.top + (p.y - view.y) * view.scale };
}

function shape(handle: CanvasHandle, id: string): Service {
  const e = diagramOf(handle).get('elementRegistry').get(id);
  if (!e || isConnection(e) || !e.businessObject) throw new Error(`no block "${id}" on the canvas`);
  return e;
}

/** The block's box on screen. */
export function blockOnScreen(handle: CanvasHandle, id: string): ScreenBox {
  const s = shape(handle, id);
  const a = toScreen(handle, { x: s.x, y: s.y });
  const b = toScreen(handle, { x: s.x + s.width, y: s.y + s.height });
  return { x: a.x, y: a.y, width: b.x - a.x, height: b.y - a.y };
}

/** Input (`in`) or output (`out`) pin `k` of a block, on screen. */
export function pinOnScreen(handle: CanvasHandle, id: string, side: 'in' | 'out', k: number): Point {
  const s = shape(handle, id);
  const box = { x: s.x, y: s.y, width: s.width, height: s.height };
  return toScreen(handle, side === 'in' ? inputPin(s.businessObject, box, k) : outputPin(s.businessObject, box, k));
}

/** The mouse cursor the canvas shows now (diagram-js sets it on the document body). */
export function cursorOf(): string {
  return Array.from(document.body.classList).find((c) => c.startsWith('djs-cursor-'))?.slice('djs-cursor-'.length) ?? '';
}
