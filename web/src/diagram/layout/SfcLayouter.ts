// Routes wires between pins (diagram-js calls this after every move, resize and reconnect): a
// fresh wire, and every wire of a block that moved, is routed anew around the blocks and labels
// (./router.ts), so moving a block re-routes its own wires and no others, and no wire loops
// back or runs through a block; a wire whose ends stayed keeps its bends.
import BaseLayouter from 'diagram-js/lib/layout/BaseLayouter.js';
import { labelsOf } from '../drawing';
import { inputPin, normalizeWire, outputPin } from '../geometry';
import type { Point } from '../../doc';
import { isConnection, type Service, type SfcConnection } from '../model';
import { route, type Rect } from './router';

export class SfcLayouter extends BaseLayouter {
  static $inject = ['elementRegistry'];

  constructor(private elementRegistry: Service) {
    super();
  }

  layoutConnection(connection: Service, hints?: Service): Point[] {
    return layoutWire(connection as SfcConnection, hints ?? {}, () => obstaclesOf(this.elementRegistry));
  }
}

/** Every block and every label beside a block, as the router avoids them. */
export function obstaclesOf(elementRegistry: Service): Rect[] {
  const out: Rect[] = [];
  elementRegistry.forEach((e: Service) => {
    if (isConnection(e) || !e.businessObject || !e.parent) return;
    out.push({ x: e.x, y: e.y, width: e.width, height: e.height });
    for (const l of labelsOf(e.businessObject, e.width, e.height)) out.push({ x: e.x + l.x, y: e.y + l.y, width: l.width, height: l.height });
  });
  return out;
}

/** The pins a wire runs between. */
export function wireEnds(c: SfcConnection): { start: Point; end: Point } {
  return {
    start: outputPin(c.source.businessObject, c.source, c.businessObject.sourcePin),
    end: inputPin(c.target.businessObject, c.target, c.businessObject.targetPin),
  };
}

export function layoutWire(
  c: SfcConnection,
  hints: { connectionStart?: unknown; connectionEnd?: unknown; waypoints?: Point[] },
  obstacles: () => Rect[] = () => [],
): Point[] {
  const { start, end } = wireEnds(c);
  const current = hints.waypoints ?? c.waypoints;
  const moved = !!hints.connectionStart || !!hints.connectionEnd;
  if (!current || current.length < 2 || moved) return route(start, end, obstacles());
  return normalizeWire(current, start, end);
}
