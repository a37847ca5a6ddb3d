// `replace`: the whole document taken from another copy with the same blocks and wires (same
// ids, kinds and ends): every block's properties and geometry, every wire's properties and
// route, and the document-level fields, in one command (one undo step). A merge conflict
// resolved on the server comes back so (web/src/app/conflicts.ts).
import type { Connection, EditorDoc, Element, Point } from '../../../doc';
import type { DocFields, DocState } from '../../core/DocState';
import { layoutWire } from '../../layout/SfcLayouter';
import { clone, connectionsOf, shapesOf, type Service, type SfcConnection, type SfcElement, type SfcShape } from '../../model';

export interface ReplaceDocContext {
  doc: EditorDoc;
  oldFields?: DocFields;
  oldShapes?: Map<SfcShape, { bo: Element; x: number; y: number; width: number; height: number }>;
  oldWires?: Map<SfcConnection, { bo: Connection; waypoints: Point[] }>;
}

/** Whether `next` has the blocks and wires of `doc` (ids, kinds, ends and pins): then it can
 *  replace it in one command; otherwise only by loading it. */
export function sameStructure(doc: EditorDoc, next: EditorDoc): boolean {
  if (doc.elements.length !== next.elements.length || doc.connections.length !== next.connections.length) return false;
  const kinds = new Map(doc.elements.map((e) => [e.id, e.kind]));
  if (!next.elements.every((e) => kinds.get(e.id) === e.kind)) return false;
  const ends = (c: Connection) => `${c.source}#${c.sourcePin}>${c.target}#${c.targetPin}`;
  const wires = new Map(doc.connections.map((c) => [c.id, ends(c)]));
  return next.connections.every((c) => wires.get(c.id) === ends(c));
}

export class ReplaceDocHandler {
  static $inject = ['elementRegistry', 'sfcDocState'];

  constructor(
    private elementRegistry: Service,
    private state: DocState,
  ) {}

  execute(ctx: ReplaceDocContext): SfcElement[] {
    const changed: SfcElement[] = [];
    const { elements, connections, ...fields } = ctx.doc;
    ctx.oldFields = this.state.fields;
    this.state.fields = clone(fields) as DocFields;
    ctx.oldShapes = new Map();
    const byId = new Map(elements.map((e) => [e.id, e]));
    for (const s of shapesOf(this.elementRegistry)) {
      const e = byId.get(s.id);
      if (!e) continue;
      ctx.oldShapes.set(s, { bo: s.businessObject, x: s.x, y: s.y, width: s.width, height: s.height });
      s.businessObject = clone(e);
      s.x = e.x;
      s.y = e.y;
      s.width = e.w;
      s.height = e.h;
      changed.push(s);
    }
    ctx.oldWires = new Map();
    const wires = new Map(connections.map((c) => [c.id, c]));
    for (const c of connectionsOf(this.elementRegistry)) {
      const w = wires.get(c.id);
      if (!w) continue;
      ctx.oldWires.set(c, { bo: c.businessObject, waypoints: c.waypoints });
      c.businessObject = clone(w);
      c.waypoints =
        w.waypoints && w.waypoints.length >= 2 ? w.waypoints.map((p) => ({ x: p.x, y: p.y })) : layoutWire(c, { connectionStart: true, connectionEnd: true });
      changed.push(c);
    }
    return changed;
  }

  revert(ctx: ReplaceDocContext): SfcElement[] {
    const changed: SfcElement[] = [];
    if (ctx.oldFields) this.state.fields = ctx.oldFields;
    for (const [s, old] of ctx.oldShapes ?? []) {
      s.businessObject = old.bo;
      Object.assign(s, { x: old.x, y: old.y, width: old.width, height: old.height });
      changed.push(s);
    }
    for (const [c, old] of ctx.oldWires ?? []) {
      c.businessObject = old.bo;
      c.waypoints = old.waypoints;
      changed.push(c);
    }
    return changed;
  }
}
