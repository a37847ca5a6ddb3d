// `updateElement`: changes properties of a block or wire as one undoable command. Geometry goes
// through diagram-js resize (so wires follow), a smaller pin count drops the wires of the
// removed pins, a renamed step takes the jumps to it along.
import type { Association, Element } from '../../../doc';
import { actionBlockSize, stepSize } from '../../drawing';
import { isBar, limits, minBarWidth } from '../../geometry';
import { isConnection, type Service, type SfcConnection, type SfcElement, type SfcShape } from '../../model';

const SHAPE_GEOMETRY = ['x', 'y', 'w', 'h'];
const FIXED = ['id', 'kind'];
const CONNECTION_FIXED = ['id', 'source', 'target', 'waypoints'];

export interface UpdateElementContext {
  element: SfcElement;
  props: Record<string, unknown>;
  old?: Record<string, unknown>;
  /** Whether the property was present before (to delete it again on undo). */
  had?: Record<string, boolean>;
}

export class UpdateElementHandler {
  static $inject = ['modeling', 'elementRegistry'];

  constructor(
    private modeling: Service,
    private elementRegistry: Service,
  ) {}

  preExecute(ctx: UpdateElementContext) {
    const e = ctx.element;
    if (isConnection(e)) return this.preConnection(e, ctx.props);
    const bo = e.businessObject;
    for (const k of FIXED) {
      if (k in ctx.props && ctx.props[k] !== bo[k as 'id']) {
        throw new Error(`updateElement(${e.id}): "${k}" cannot be changed`);
      }
    }
    const p = ctx.props;
    // Pin count: drop wires on pins that go away; widen a bar that could not hold them.
    let minW = 0;
    if ('pins' in p && isBar(bo.kind)) {
      const n = Number(p.pins ?? 2);
      if (!Number.isInteger(n) || n < 2) throw new Error(`updateElement(${e.id}): pins must be an integer ≥ 2, got ${String(p.pins)}`);
      for (const c of [...e.outgoing]) if (bo.kind.endsWith('Divergence') && c.businessObject.sourcePin >= n) this.modeling.removeConnection(c);
      for (const c of [...e.incoming]) if (bo.kind.endsWith('Convergence') && c.businessObject.targetPin >= n) this.modeling.removeConnection(c);
      minW = minBarWidth(n);
    }
    const bounds = {
      x: num(p, 'x', e.x, e.id),
      y: num(p, 'y', e.y, e.id),
      width: Math.max(num(p, 'w', e.width, e.id), minW),
      height: num(p, 'h', e.height, e.id),
    };
    if (bo.kind === 'transition') {
      const lim = limits(bo);
      bounds.width = lim.min.w;
      bounds.height = lim.min.h;
    }
    // Blocks grow to fit their text: a step its name, tag and timeout (about its axis, so its
    // wires stay straight), an action block its rows.
    if (bo.kind === 'step' && !('w' in p) && ['name', 'tag', 'timeout', 'initial'].some((k) => k in p)) {
      const need = stepSize({ ...bo, ...(p as Partial<Element>) }).w;
      if (need > bounds.width) {
        bounds.x -= (need - bounds.width) / 2;
        bounds.width = need;
      }
    }
    if (bo.kind === 'actionBlock' && 'associations' in p && Array.isArray(p.associations)) {
      const need = actionBlockSize(p.associations as Association[]);
      if (!('w' in p)) bounds.width = Math.max(bounds.width, need.w);
      if (!('h' in p)) bounds.height = need.h;
    }
    if (bounds.x !== e.x || bounds.y !== e.y || bounds.width !== e.width || bounds.height !== e.height) {
      this.modeling.resizeShape(e, bounds);
    }
    // Jumps name their target step: follow a rename.
    if (bo.kind === 'step' && typeof p.name === 'string' && bo.name && p.name !== bo.name) {
      for (const j of this.elementRegistry.filter((x: Service) => x.businessObject?.kind === 'jump' && x.businessObject.target === bo.name)) {
        this.modeling.updateElement(j, { target: p.name });
      }
    }
  }

  private preConnection(c: SfcConnection, p: Record<string, unknown>) {
    const bo = c.businessObject;
    if ('id' in p && p.id !== bo.id) throw new Error(`updateElement(${c.id}): "id" cannot be changed`);
    const src = 'source' in p ? this.block(String(p.source), c.id) : c.source;
    const tgt = 'target' in p ? this.block(String(p.target), c.id) : c.target;
    if (src !== c.source || tgt !== c.target) {
      this.modeling.reconnect(c, src, tgt, [...c.waypoints], {});
    }
    if ('waypoints' in p && Array.isArray(p.waypoints) && p.waypoints.length >= 2) {
      this.modeling.updateWaypoints(c, (p.waypoints as { x: number; y: number }[]).map((q) => ({ x: q.x, y: q.y })));
    }
  }

  private block(id: string, where: string): SfcShape {
    const s = this.elementRegistry.get(id);
    if (!s || isConnection(s)) throw new Error(`updateElement(${where}): no block "${id}"`);
    return s;
  }

  execute(ctx: UpdateElementContext): SfcElement[] {
    const e = ctx.element;
    const bo = e.businessObject as unknown as Record<string, unknown>;
    const skip = isConnection(e) ? CONNECTION_FIXED : [...SHAPE_GEOMETRY, ...FIXED];
    ctx.old = {};
    ctx.had = {};
    for (const [k, v] of Object.entries(ctx.props)) {
      if (skip.includes(k)) continue;
      ctx.had[k] = k in bo;
      ctx.old[k] = bo[k];
      if (v === undefined || v === null) delete bo[k];
      else bo[k] = v;
    }
    return affected(e);
  }

  revert(ctx: UpdateElementContext): SfcElement[] {
    const e = ctx.element;
    const bo = e.businessObject as unknown as Record<string, unknown>;
    for (const k of Object.keys(ctx.old ?? {})) {
      if (ctx.had?.[k]) bo[k] = ctx.old![k];
      else delete bo[k];
    }
    return affected(e);
  }

  postExecute(ctx: UpdateElementContext) {
    const e = ctx.element;
    const p = ctx.props;
    // Pins moved (pin count or wire pins changed): wires keep their bends, ends follow the pins.
    if (isConnection(e)) {
      if ('sourcePin' in p || 'targetPin' in p) this.modeling.layoutConnection(e, {});
      return;
    }
    if ('pins' in p) {
      for (const c of [...e.incoming, ...e.outgoing]) this.modeling.layoutConnection(c, {});
    }
  }
}

function num(p: Record<string, unknown>, k: string, dflt: number, id: string): number {
  if (!(k in p) || p[k] === undefined) return dflt;
  const v = p[k];
  if (typeof v !== 'number' || !Number.isFinite(v)) throw new Error(`updateElement(${id}): "${k}" must be a number, got ${String(v)}`);
  return v;
}

/** The element and the blocks whose drawing depends on it (pin arrows, action block links). */
function affected(e: SfcElement): SfcElement[] {
  if (isConnection(e)) return [e, e.source, e.target].filter(Boolean) as SfcElement[];
  return [e, ...e.incoming, ...e.outgoing];
}
