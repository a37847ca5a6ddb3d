// Routes wires between pins: fresh wires get an orthogonal route, wires whose block moved keep
// their bends where possible (diagram-js calls this after every move, resize and reconnect).
import BaseLayouter from 'diagram-js/lib/layout/BaseLayouter.js';
import { inputPin, normalizeWire, outputPin, repairWire, route } from '../geometry';
import type { Point } from '../../doc';
import type { Service, SfcConnection } from '../model';

export class SfcLayouter extends BaseLayouter {
  layoutConnection(connection: Service, hints?: Service): Point[] {
    return layoutWire(connection as SfcConnection, hints ?? {});
  }
}

/** The pins a wire runs between. */
export function wireEnds(c: SfcConnection): { start: Point; end: Point } {
  return {
    start: outputPin(c.source.businessObject, c.source, c.businessObject.sourcePin),
    end: inputPin(c.target.businessObject, c.target, c.businessObject.targetPin),
  };
}

export function layoutWire(c: SfcConnection, hints: { connectionStart?: unknown; connectionEnd?: unknown; waypoints?: Point[] }): Point[] {
  const { start, end } = wireEnds(c);
  const current = hints.waypoints ?? c.waypoints;
  if (!current || current.length < 2) return route(start, end, c.source, c.target);
  const startMoved = !!hints.connectionStart;
  const endMoved = !!hints.connectionEnd;
  if (startMoved && endMoved) return route(start, end, c.source, c.target);
  if (startMoved) return repairWire(current, start, end, true, c.source, c.target);
  if (endMoved) return repairWire(current, start, end, false, c.source, c.target);
  return normalizeWire(current, start, end);
}
