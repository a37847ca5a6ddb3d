// `applyLayout`: every block and wire takes the geometry of a laid-out copy of the document, in
// one command (one undo step), without going through a move per block.
import type { EditorDoc, Point } from '../../../doc';
import { layoutWire } from '../../layout/SfcLayouter';
import { connectionsOf, shapesOf, type Service, type SfcConnection, type SfcElement, type SfcShape } from '../../model';

interface Bounds {
  x: number;
  y: number;
  width: number;
  height: number;
}

export interface ApplyLayoutContext {
  laidOut: EditorDoc;
  oldBounds?: Map<SfcShape, Bounds>;
  oldWaypoints?: Map<SfcConnection, Point[]>;
}

export class ApplyLayoutHandler {
  static $inject = ['elementRegistry'];

  constructor(private elementRegistry: Service) {}

  execute(ctx: ApplyLayoutContext): SfcElement[] {
    const changed: SfcElement[] = [];
    ctx.oldBounds = new Map();
    ctx.oldWaypoints = new Map();
    const byId = new Map(ctx.laidOut.elements.map((e) => [e.id, e]));
    for (const s of shapesOf(this.elementRegistry)) {
      const e = byId.get(s.id);
      if (!e) continue;
      ctx.oldBounds.set(s, { x: s.x, y: s.y, width: s.width, height: s.height });
      s.x = e.x;
      s.y = e.y;
      s.width = e.w;
      s.height = e.h;
      changed.push(s);
    }
    const wires = new Map(ctx.laidOut.connections.map((c) => [c.id, c]));
    for (const c of connectionsOf(this.elementRegistry)) {
      ctx.oldWaypoints.set(c, c.waypoints);
      const given = wires.get(c.id)?.waypoints;
      c.waypoints = given && given.length >= 2 ? given.map((p) => ({ x: p.x, y: p.y })) : layoutWire(c, { connectionStart: true, connectionEnd: true });
      changed.push(c);
    }
    return changed;
  }

  revert(ctx: ApplyLayoutContext): SfcElement[] {
    const changed: SfcElement[] = [];
    for (const [s, b] of ctx.oldBounds ?? []) {
      Object.assign(s, b);
      changed.push(s);
    }
    for (const [c, w] of ctx.oldWaypoints ?? []) {
      c.waypoints = w;
      changed.push(c);
    }
    return changed;
  }
}
