// Drawing a wire: press on a free pin (an output, or a free input to draw backwards) and drag;
// the wire follows the cursor with right-angle bends, the nearest free valid pin within
// PIN_SNAP is ringed, and releasing there connects. Over a block that cannot take the wire the
// cursor shows "not allowed" and the drop is refused.
import { connectPoints } from 'diagram-js/lib/layout/ManhattanLayout.js';
import { set as setCursor } from 'diagram-js/lib/util/Cursor.js';
import { isPrimaryButton } from 'diagram-js/lib/util/Mouse.js';
import type { Point } from '../../doc';
import { normalizeWire, PIN_SNAP } from '../geometry';
import { isShape, shapesOf, type Service, type SfcShape } from '../model';
import { kindsMayConnect, nearestFreePin } from '../rules/SfcRules';
import { el, points } from '../render/svg';
import type { ViewTracker } from '../view/ViewTracker';

/** How close to a pin a press must be to start a wire instead of a move (or a lasso: a
 *  press just outside the block, beyond its pin, grabs the pin too). */
export const GRAB = 10;

interface Candidate {
  shape: SfcShape;
  pin: number;
  at: Point;
}

interface ConnectContext {
  shape: SfcShape;
  side: 'in' | 'out';
  pin: number;
  at: Point;
  candidate?: Candidate;
  gfx?: SVGGElement;
}

export class PinConnect {
  static $inject = ['eventBus', 'dragging', 'canvas', 'elementRegistry', 'modeling', 'elementFactory', 'config.sfc', 'sfcView'];

  constructor(
    eventBus: Service,
    private dragging: Service,
    private canvas: Service,
    private elementRegistry: Service,
    modeling: Service,
    elementFactory: Service,
    config: { readOnly?: boolean },
    private view: ViewTracker,
  ) {
    eventBus.on('element.mousedown', 1600, (event: Service) => {
      if (config?.readOnly) return;
      const oe = event.originalEvent as MouseEvent | undefined;
      if (!oe || !isPrimaryButton(oe) || oe.shiftKey || oe.ctrlKey || oe.metaKey) return;
      const pick = this.pinAt(this.toCanvas(oe), isShape(event.element) ? event.element : undefined);
      if (!pick) return;
      this.start(oe, pick.shape, pick.side, pick.pin, pick.at);
      return true;
    });

    eventBus.on('sfc.connect.start', (event: Service) => {
      const ctx = event.context as ConnectContext;
      const layer = this.canvas.getLayer('sfc-connect', 900);
      ctx.gfx = el('g', { 'pointer-events': 'none' }, layer);
    });

    eventBus.on('sfc.connect.move', (event: Service) => {
      const ctx = event.context as ConnectContext;
      const p = { x: event.x, y: event.y };
      ctx.candidate = this.findCandidate(ctx, p);
      const hover = event.hover;
      const overOther = hover && isShape(hover) && hover !== ctx.shape;
      setCursor(!ctx.candidate && overOther ? 'not-allowed' : 'crosshair');
      this.drawPreview(ctx, ctx.candidate?.at ?? p);
    });

    eventBus.on('sfc.connect.end', (event: Service) => {
      const ctx = event.context as ConnectContext;
      const c = ctx.candidate;
      if (!c) return false;
      const [source, sourcePin, target, targetPin] =
        ctx.side === 'out' ? [ctx.shape, ctx.pin, c.shape, c.pin] : [c.shape, c.pin, ctx.shape, ctx.pin];
      const connection = elementFactory.createConnection({
        businessObject: { id: '', source: source.id, sourcePin, target: target.id, targetPin },
      });
      modeling.createConnection(source, target, connection, this.canvas.getRootElement());
    });

    eventBus.on('sfc.connect.cleanup', (event: Service) => {
      (event.context as ConnectContext).gfx?.remove();
    });
  }

  /** Starts drawing a wire from `pin` of `shape` (used on a press and by tests). */
  start(event: MouseEvent, shape: SfcShape, side: 'in' | 'out', pin: number, at: Point) {
    this.dragging.init(event, 'sfc.connect', {
      cursor: 'crosshair',
      data: { shape, context: { shape, side, pin, at } satisfies ConnectContext },
    });
  }

  /** The free pin within GRAB of `p`: of the block pressed on first, else of any block (a
   *  press on the chart or a wire just beyond a pin). */
  pinAt(p: Point, pressed?: SfcShape): { shape: SfcShape; side: 'in' | 'out'; pin: number; at: Point } | undefined {
    const pickOf = (shape: SfcShape) => {
      const out = nearestFreePin(shape, 'out', p, GRAB);
      const inn = nearestFreePin(shape, 'in', p, GRAB);
      if (out && (!inn || out.dist <= inn.dist)) return { shape, side: 'out' as const, ...out };
      return inn ? { shape, side: 'in' as const, ...inn } : undefined;
    };
    if (pressed) {
      const own = pickOf(pressed);
      if (own) return own;
    }
    let best: ReturnType<typeof pickOf>;
    for (const s of shapesOf(this.elementRegistry)) {
      if (s === pressed || p.x < s.x - GRAB || p.x > s.x + s.width + GRAB || p.y < s.y - GRAB || p.y > s.y + s.height + GRAB) continue;
      const hit = pickOf(s);
      if (hit && (!best || hit.dist < best.dist)) best = hit;
    }
    return best;
  }

  /** The nearest free pin of another block that the wire may end on. */
  findCandidate(ctx: Pick<ConnectContext, 'shape' | 'side'>, p: Point): Candidate | undefined {
    let best: (Candidate & { dist: number }) | undefined;
    for (const s of shapesOf(this.elementRegistry)) {
      if (s === ctx.shape) continue;
      if (p.x < s.x - PIN_SNAP || p.x > s.x + s.width + PIN_SNAP || p.y < s.y - PIN_SNAP || p.y > s.y + s.height + PIN_SNAP) continue;
      const ok = ctx.side === 'out' ? kindsMayConnect(ctx.shape, s) : kindsMayConnect(s, ctx.shape);
      if (!ok) continue;
      const hit = nearestFreePin(s, ctx.side === 'out' ? 'in' : 'out', p);
      if (hit && (!best || hit.dist < best.dist)) best = { shape: s, pin: hit.pin, at: hit.at, dist: hit.dist };
    }
    return best && { shape: best.shape, pin: best.pin, at: best.at };
  }

  private drawPreview(ctx: ConnectContext, to: Point) {
    const g = ctx.gfx;
    if (!g) return;
    while (g.firstChild) g.firstChild.remove();
    const [a, b] = ctx.side === 'out' ? [ctx.at, to] : [to, ctx.at];
    const line = ctx.candidate ? normalizeWire([a, b], a, b) : connectPoints(a, b, 'v:v');
    el('polyline', { points: points(line), fill: 'none', stroke: '#2563eb', 'stroke-width': 1.5, 'stroke-dasharray': ctx.candidate ? '' : '5 3' }, g);
    el('circle', { cx: ctx.at.x, cy: ctx.at.y, r: 4, fill: '#2563eb' }, g);
    if (ctx.candidate) {
      el('circle', { cx: ctx.candidate.at.x, cy: ctx.candidate.at.y, r: 7, fill: 'rgba(22,163,74,0.2)', stroke: '#16a34a', 'stroke-width': 2 }, g);
    }
  }

  private toCanvas(e: MouseEvent): Point {
    const vb = this.view.view();
    const rect = (this.canvas.getContainer() as HTMLElement).getBoundingClientRect();
    return { x: vb.x + (e.clientX - rect.left) / vb.scale, y: vb.y + (e.clientY - rect.top) / vb.scale };
  }
}
