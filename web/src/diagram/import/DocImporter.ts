// Document ↔ canvas: `load` makes a shape per block (businessObject = a copy of the Element)
// and a connection per wire (businessObject = the Connection, pins included); `getDoc` builds
// the document back from the canvas in document order.
import { pinCounts, type Connection, type EditorDoc, type Element } from '../../doc';
import type { DocFields, DocState } from '../core/DocState';
import type { SfcElementFactory } from '../core/SfcElementFactory';
import { labelsOf } from '../drawing';
import { layoutWire, wireEnds } from '../layout/SfcLayouter';
import type { Rect } from '../layout/router';
import { clone, connectionsOf, shapesOf, type OrderCounter, type Service, type SfcConnection, type SfcShape } from '../model';

const KINDS = new Set([
  'step',
  'transition',
  'selectionDivergence',
  'selectionConvergence',
  'simultaneousDivergence',
  'simultaneousConvergence',
  'jump',
  'text',
  'actionBlock',
]);

export class DocImporter {
  static $inject = ['canvas', 'elementFactory', 'elementRegistry', 'commandStack', 'sfcDocState', 'sfcOrder', 'eventBus'];

  constructor(
    private canvas: Service,
    private elementFactory: SfcElementFactory & Service,
    private elementRegistry: Service,
    private commandStack: Service,
    private state: DocState,
    private order: OrderCounter,
    private eventBus: Service,
  ) {}

  load(doc: EditorDoc) {
    validate(doc);
    this.eventBus.fire('diagram.clear');
    this.elementFactory.reset();
    const root = this.canvas.getRootElement();
    const { elements, connections, ...fields } = doc;
    this.state.fields = clone(fields) as DocFields;

    // Build every object first and wire them up, so blocks are drawn once with their pins'
    // final state (an input pin with a wire is an arrow).
    const shapes = new Map<string, SfcShape>();
    elements.forEach((e, i) => {
      const shape = this.elementFactory.createShape({
        id: e.id,
        businessObject: clone(e),
        x: e.x,
        y: e.y,
        width: e.w,
        height: e.h,
        sfcOrder: i,
      });
      shapes.set(e.id, shape);
    });
    let obstacles: Rect[] | undefined;
    const wires: SfcConnection[] = connections.map((c, i) => {
      const wire: SfcConnection = this.elementFactory.createConnection({
        id: c.id,
        businessObject: clone(c),
        source: shapes.get(c.source),
        target: shapes.get(c.target),
        waypoints: c.waypoints && c.waypoints.length >= 2 ? c.waypoints.map((p) => ({ x: p.x, y: p.y })) : [],
        sfcOrder: elements.length + i,
      });
      // No polyline: a straight wire (the server checked that nothing is in its way), else
      // one to route here.
      if (wire.waypoints.length < 2) {
        const { start, end } = wireEnds(wire);
        wire.waypoints =
          start.x === end.x && end.y > start.y ? [start, end] : layoutWire(wire, {}, () => (obstacles ??= obstaclesOfDoc(elements)));
      }
      return wire;
    });
    for (const s of shapes.values()) this.canvas.addShape(s, root);
    for (const w of wires) this.canvas.addConnection(w, root);
    this.order.reset(elements.length + connections.length);
    this.commandStack.clear();
    this.eventBus.fire('sfc.loaded', { doc });
  }

  getDoc(): EditorDoc {
    const elements: Element[] = shapesOf(this.elementRegistry).map((s) => {
      const e = clone(s.businessObject);
      e.x = s.x;
      e.y = s.y;
      e.w = s.width;
      e.h = s.height;
      return e;
    });
    const connections: Connection[] = connectionsOf(this.elementRegistry).map((c) => {
      const out = clone(c.businessObject);
      out.source = c.source.id;
      out.target = c.target.id;
      out.waypoints = c.waypoints.map((p) => ({ x: p.x, y: p.y }));
      return out;
    });
    return { ...clone(this.state.fields), elements, connections };
  }
}

/** Rejects a document the canvas cannot show, naming the block or wire at fault. */
export function validate(doc: EditorDoc) {
  if (!doc || !Array.isArray(doc.elements) || !Array.isArray(doc.connections)) {
    throw new Error('load: the document needs "elements" and "connections" arrays');
  }
  const ids = new Map<string, Element>();
  doc.elements.forEach((e, i) => {
    const where = `load: element #${i}${e?.id ? ` "${e.id}"` : ''}`;
    if (!e || typeof e.id !== 'string' || e.id === '') throw new Error(`${where}: missing id`);
    if (!KINDS.has(e.kind)) throw new Error(`${where}: unknown kind "${String(e.kind)}"`);
    for (const k of ['x', 'y', 'w', 'h'] as const) {
      if (typeof e[k] !== 'number' || !Number.isFinite(e[k])) throw new Error(`${where}: "${k}" is not a number`);
    }
    if (e.w <= 0 || e.h <= 0) throw new Error(`${where}: size ${e.w}×${e.h} is not positive`);
    if (ids.has(e.id)) throw new Error(`${where}: duplicate id`);
    ids.set(e.id, e);
  });
  const seen = new Set<string>(ids.keys());
  const usedIn = new Set<string>();
  const usedOut = new Set<string>();
  doc.connections.forEach((c, i) => {
    const where = `load: connection #${i}${c?.id ? ` "${c.id}"` : ''}`;
    if (!c || typeof c.id !== 'string' || c.id === '') throw new Error(`${where}: missing id`);
    if (seen.has(c.id)) throw new Error(`${where}: id already used`);
    seen.add(c.id);
    const s = ids.get(c.source);
    const t = ids.get(c.target);
    if (!s) throw new Error(`${where}: no source block "${c.source}"`);
    if (!t) throw new Error(`${where}: no target block "${c.target}"`);
    if (!Number.isInteger(c.sourcePin) || c.sourcePin < 0 || c.sourcePin >= pinCounts(s).outputs) {
      throw new Error(`${where}: "${s.id}" has no output pin ${c.sourcePin}`);
    }
    if (!Number.isInteger(c.targetPin) || c.targetPin < 0 || c.targetPin >= pinCounts(t).inputs) {
      throw new Error(`${where}: "${t.id}" has no input pin ${c.targetPin}`);
    }
    const outKey = `${c.source}#${c.sourcePin}`;
    const inKey = `${c.target}#${c.targetPin}`;
    if (usedOut.has(outKey)) throw new Error(`${where}: output pin ${c.sourcePin} of "${c.source}" already has a wire`);
    if (usedIn.has(inKey)) throw new Error(`${where}: input pin ${c.targetPin} of "${c.target}" already has a wire`);
    usedOut.add(outKey);
    usedIn.add(inKey);
    if (c.waypoints) {
      for (const p of c.waypoints) {
        if (!p || !Number.isFinite(p.x) || !Number.isFinite(p.y)) throw new Error(`${where}: a waypoint is not a point`);
      }
    }
  });
}

/** The blocks and labels of a document, as the router avoids them. */
function obstaclesOfDoc(elements: Element[]): Rect[] {
  const out: Rect[] = [];
  for (const e of elements) {
    out.push({ x: e.x, y: e.y, width: e.w, height: e.h });
    for (const l of labelsOf(e, e.w, e.h)) out.push({ x: e.x + l.x, y: e.y + l.y, width: l.width, height: l.height });
  }
  return out;
}
