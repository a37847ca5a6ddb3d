// Structured editing as in S7-GRAPH and CODESYS, each one command on the undo stack:
// - `sfc.structure.insert`: a step and a transition inserted into the sequence after (below)
//   or before (above) a selected step or transition, the wires reconnected, the blocks below
//   moved down to make room;
// - `sfc.structure.deleteStep`: a step between two transitions removed with the transition
//   after it, the transition before it wired to what followed;
// - `spliceDropped` (called within the palette's `elements.create`): a step or transition
//   dropped on a wire between a transition and a step goes into the sequence, with the block
//   of the other kind that keeps the chart alternating.
// Wires are re-routed by the layouter (layout/router.ts) as they are created or their blocks move.
import type { Element } from '../../../doc';
import { stepSize } from '../../drawing';
import { defaultSize, inputPin, outputPin } from '../../geometry';
import { freshName, isConnection, shapesOf, usedNames, type Service, type SfcConnection, type SfcShape } from '../../model';

/** Vertical room between two blocks of an inserted sequence (as the layouts of the examples). */
export const STRUCT_GAP = 30;

export type InsertWhere = 'after' | 'before';

const kindOf = (s: SfcShape | undefined) => s?.businessObject?.kind;

/** Whether a step or transition can get a step and transition inserted after or before it. */
export function canInsert(e: unknown): e is SfcShape {
  if (!e || isConnection(e)) return false;
  const k = kindOf(e as SfcShape);
  return k === 'step' || k === 'transition';
}

/** Whether `e` is a step in a sequence between two transitions (Delete then removes the
 *  transition after it too and reconnects). */
export function canDeleteStep(e: unknown): e is SfcShape {
  if (!e || isConnection(e)) return false;
  const s = e as SfcShape;
  if (kindOf(s) !== 'step' || s.incoming.length !== 1 || s.outgoing.length !== 1) return false;
  return kindOf(s.incoming[0].source) === 'transition' && kindOf(s.outgoing[0].target) === 'transition';
}

/** Everything a handler needs from diagram-js. */
interface Services {
  modeling: Service;
  elementFactory: Service;
  elementRegistry: Service;
  canvas: Service;
}

/** A new step (`StepN`) or transition (`TN`, condition TRUE) of default size, not yet on the canvas. */
function newBlock(s: Services, kind: 'step' | 'transition', used: Set<string>): SfcShape {
  const e: Partial<Element> & { kind: 'step' | 'transition' } =
    kind === 'step' ? { kind, name: freshName('Step', used) } : { kind, name: freshName('T', used), condition: 'TRUE' };
  const size = kind === 'step' ? stepSize(e) : defaultSize(kind);
  const bo = { id: '', x: 0, y: 0, w: size.w, h: size.h, ...e } as Element;
  return s.elementFactory.createShape({ businessObject: bo, width: size.w, height: size.h });
}

function connect(s: Services, source: SfcShape, sourcePin: number, target: SfcShape, targetPin: number): SfcConnection {
  const connection = s.elementFactory.createConnection({
    businessObject: { id: '', source: source.id, sourcePin, target: target.id, targetPin },
  });
  return s.modeling.createConnection(source, target, connection, s.canvas.getRootElement());
}

/**
 * Puts `chain` (blocks new or already on the canvas) into the sequence `source` → `target`
 * (either may be absent), replacing `oldWire`: the blocks centred on `axisX` one below the
 * other from `topY`; every block whose top is at or below `moveFrom` (but those in `keep`) moves
 * down to make room first. Returns the chain's blocks as on the canvas.
 */
function insertChain(
  s: Services,
  opts: {
    source?: { shape: SfcShape; pin: number };
    target?: { shape: SfcShape; pin: number };
    oldWire?: SfcConnection;
    chain: SfcShape[];
    axisX: number;
    topY: number;
    moveFrom: number;
    keep: SfcShape[];
  },
): SfcShape[] {
  const { chain } = opts;
  const delta = chain.reduce((h, b) => h + b.height + STRUCT_GAP, 0);
  const keep = new Set<SfcShape>([...opts.keep, ...chain]);
  const below = shapesOf(s.elementRegistry).filter(
    (b) => !keep.has(b) && b.businessObject.kind !== 'actionBlock' && b.y >= opts.moveFrom - 0.5,
  );
  if (below.length > 0) s.modeling.moveElements(below, { x: 0, y: delta });
  if (opts.oldWire && s.elementRegistry.get(opts.oldWire.id)) s.modeling.removeConnection(opts.oldWire);
  const root = s.canvas.getRootElement();
  const placed: SfcShape[] = [];
  let y = opts.topY;
  for (const b of chain) {
    const x = Math.round(opts.axisX - b.width / 2);
    if (s.elementRegistry.get(b.id) === b) {
      if (b.x !== x || b.y !== y) s.modeling.moveShape(b, { x: x - b.x, y: y - b.y });
      placed.push(b);
    } else {
      placed.push(s.modeling.createShape(b, { x: x + b.width / 2, y: y + b.height / 2 }, root));
    }
    y += b.height + STRUCT_GAP;
  }
  let prev = opts.source;
  for (const b of placed) {
    if (prev) connect(s, prev.shape, prev.pin, b, 0);
    prev = { shape: b, pin: 0 };
  }
  if (opts.target && prev) connect(s, prev.shape, prev.pin, opts.target.shape, opts.target.pin);
  return placed;
}

/** The two kinds inserted next to a block of `kind`: the first one adjacent to it. */
function pairFor(kind: 'step' | 'transition'): ['step' | 'transition', 'step' | 'transition'] {
  return kind === 'step' ? ['transition', 'step'] : ['step', 'transition'];
}

export class InsertStructureHandler {
  static $inject = ['modeling', 'elementFactory', 'elementRegistry', 'canvas'];
  private s: Services;

  constructor(modeling: Service, elementFactory: Service, elementRegistry: Service, canvas: Service) {
    this.s = { modeling, elementFactory, elementRegistry, canvas };
  }

  preExecute(ctx: { element: SfcShape; where: InsertWhere; created?: SfcShape[] }) {
    const e = ctx.element;
    if (!canInsert(e)) throw new Error(`sfc.structure.insert: ${(e as Service)?.id} is not a step or transition`);
    const kind = e.businessObject.kind as 'step' | 'transition';
    const used = usedNames(this.s.elementRegistry);
    if (ctx.where === 'after') {
      // Below: the kind after the block first (step → T, Step; transition → Step, T).
      const [a, b] = pairFor(kind);
      const wire = e.outgoing[0];
      const out = outputPin(e.businessObject, e, wire?.businessObject.sourcePin ?? 0);
      ctx.created = insertChain(this.s, {
        source: { shape: e, pin: wire?.businessObject.sourcePin ?? 0 },
        target: wire ? { shape: wire.target, pin: wire.businessObject.targetPin } : undefined,
        oldWire: wire,
        chain: [newBlock(this.s, a, used), newBlock(this.s, b, used)],
        axisX: out.x,
        topY: e.y + e.height + STRUCT_GAP,
        moveFrom: e.y + e.height,
        keep: [e],
      });
    } else {
      // Above: the block's own kind first, then the other one, then the block.
      const [b, a] = pairFor(kind);
      const wire = e.incoming[0];
      const inn = inputPin(e.businessObject, e, wire?.businessObject.targetPin ?? 0);
      ctx.created = insertChain(this.s, {
        source: wire ? { shape: wire.source, pin: wire.businessObject.sourcePin } : undefined,
        target: { shape: e, pin: wire?.businessObject.targetPin ?? 0 },
        oldWire: wire,
        chain: [newBlock(this.s, a, used), newBlock(this.s, b, used)],
        axisX: inn.x,
        topY: e.y,
        moveFrom: e.y,
        keep: [],
      });
    }
  }
}

export class DeleteStepHandler {
  static $inject = ['modeling', 'elementFactory', 'elementRegistry', 'canvas'];
  private s: Services;

  constructor(modeling: Service, elementFactory: Service, elementRegistry: Service, canvas: Service) {
    this.s = { modeling, elementFactory, elementRegistry, canvas };
  }

  preExecute(ctx: { step: SfcShape }) {
    const step = ctx.step;
    if (!canDeleteStep(step)) throw new Error(`sfc.structure.deleteStep: ${(step as Service)?.id} is not a step between two transitions`);
    const before = step.incoming[0];
    const prev = { shape: before.source, pin: before.businessObject.sourcePin };
    const next = step.outgoing[0].target;
    const after = next.outgoing[0];
    const follow = after ? { shape: after.target, pin: after.businessObject.targetPin } : undefined;
    this.s.modeling.removeElements([step, next]);
    if (follow) connect(this.s, prev.shape, prev.pin, follow.shape, follow.pin);
  }
}

/** A wire a step or transition dropped at `p` goes into: between a transition and a step
 *  (either way), passing within `radius` of `p`. */
export function wireAt(elementRegistry: Service, p: { x: number; y: number }, radius = 10): SfcConnection | undefined {
  let best: { c: SfcConnection; d: number } | undefined;
  for (const c of elementRegistry.filter((e: unknown) => isConnection(e)) as SfcConnection[]) {
    const ks = [kindOf(c.source), kindOf(c.target)];
    if (!(ks.includes('step') && ks.includes('transition'))) continue;
    for (let i = 1; i < c.waypoints.length; i++) {
      const d = segmentDistance(p, c.waypoints[i - 1], c.waypoints[i]);
      if (d <= radius && (!best || d < best.d)) best = { c, d };
    }
  }
  return best?.c;
}

function segmentDistance(p: { x: number; y: number }, a: { x: number; y: number }, b: { x: number; y: number }): number {
  const dx = b.x - a.x;
  const dy = b.y - a.y;
  const l2 = dx * dx + dy * dy;
  const t = l2 === 0 ? 0 : Math.max(0, Math.min(1, ((p.x - a.x) * dx + (p.y - a.y) * dy) / l2));
  return Math.hypot(p.x - (a.x + t * dx), p.y - (a.y + t * dy));
}

/** Puts `dropped` (a step or transition just created) into the sequence of `wire`, with a new
 *  block of the other kind, in the order that keeps the chart alternating. Called within the
 *  command that created it, so the drop and the insertion are one undo step. */
export function spliceDropped(s: Services, dropped: SfcShape, wire: SfcConnection): SfcShape[] {
  const source = wire.source;
  const kind = kindOf(dropped) as 'step' | 'transition';
  const other = newBlock(s, kind === 'step' ? 'transition' : 'step', usedNames(s.elementRegistry));
  // Next to the wire's source comes the kind the source may feed (step → transition → step).
  const chain = kindOf(source) === kind ? [other, dropped] : [dropped, other];
  const out = outputPin(source.businessObject, source, wire.businessObject.sourcePin);
  return insertChain(s, {
    source: { shape: source, pin: wire.businessObject.sourcePin },
    target: { shape: wire.target, pin: wire.businessObject.targetPin },
    oldWire: wire,
    chain,
    axisX: out.x,
    topY: source.y + source.height + STRUCT_GAP,
    moveFrom: source.y + source.height,
    keep: [source],
  });
}
