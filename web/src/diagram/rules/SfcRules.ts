// What the user may do: the valid connections of sfc-doc (an output pin to an input pin of
// another block, one wire per pin), which blocks the chart's target allows (no simultaneous
// branches in ATMT/EATMT charts), which sides of a block can be resized, and nothing at all
// on a read-only canvas.
import RuleProvider from 'diagram-js/lib/features/rules/RuleProvider.js';
import { pinCounts, VALID_TARGETS, type ChartTarget, type ElementKind, type Point } from '../../doc';
import type { DocState } from '../core/DocState';
import { inputPin, limits, outputPin, PIN_SNAP } from '../geometry';
import { isConnection, type Service, type SfcConnection, type SfcShape } from '../model';
import { movesOntoAnother, type Box } from './overlap';

export class SfcRules extends RuleProvider {
  static $inject = ['eventBus', 'config.sfc', 'sfcDocState', 'elementRegistry'];

  constructor(
    eventBus: Service,
    private config: { readOnly?: boolean },
    private state: DocState,
    private elementRegistry?: Service,
  ) {
    super(eventBus);
  }

  init() {
    const ro = () => !!this.config?.readOnly;
    /** Whether the chart's target allows every block among `shapes`. */
    const allowedHere = (shapes: unknown[]) => {
      const refused = kindsRefusedBy(this.state?.fields.target);
      return shapes.every((s) => !isBlock(s) || !refused.includes(s.businessObject.kind));
    };
    // A chart is flat: blocks go into the chart itself, never into another block or a wire.
    const intoChart = (target: unknown) => !target || (!isBlock(target) && !isConnection(target));
    this.addRule('shape.create', (ctx: Service) => !ro() && intoChart(ctx.target) && allowedHere([ctx.shape]));
    this.addRule('elements.create', (ctx: Service) => !ro() && intoChart(ctx.target) && allowedHere(ctx.elements ?? []));
    const box = (s: Service): Box => ({ id: s.id, x: s.x, y: s.y, width: s.width, height: s.height, kind: s.businessObject?.kind, step: s.businessObject?.step });
    /** Whether the move puts a block onto another (refused: blocks never lie on each other). */
    const ontoAnother = (ctx: Service) => {
      const delta = ctx.delta;
      if (!delta || !this.elementRegistry || (delta.x === 0 && delta.y === 0)) return false;
      const moved = ((ctx.shapes ?? []) as unknown[]).filter(isBlock).map(box);
      const all = (this.elementRegistry.getAll() as unknown[]).filter(isBlock).map(box);
      return movesOntoAnother(moved, delta, all);
    };
    this.addRule('elements.move', (ctx: Service) => !ro() && intoChart(ctx.target) && !ontoAnother(ctx));
    this.addRule(['elements.delete', 'element.copy'], () => !ro());
    this.addRule('connection.create', (ctx: Service) => {
      if (ro()) return false;
      const { source, target } = ctx;
      if (!isBlock(source) || !isBlock(target)) return false;
      return kindsMayConnect(source, target) && freeOutputs(source).length > 0 && freeInputs(target).length > 0;
    });
    this.addRule('connection.reconnect', (ctx: Service) => {
      if (ro()) return false;
      const { connection, source, target } = ctx;
      if (!isBlock(source) || !isBlock(target)) return false;
      if (!kindsMayConnect(source, target)) return false;
      const c = connection as SfcConnection;
      // The moved end needs a free pin on its new block (its own pin counts as free).
      if (target !== c.target && freeInputs(target, c).length === 0) return false;
      if (source !== c.source && freeOutputs(source, c).length === 0) return false;
      return true;
    });
    this.addRule('connection.updateWaypoints', () => !ro());
    this.addRule('shape.resize', (ctx: Service) => {
      if (ro()) return false;
      const shape = ctx.shape;
      if (!isBlock(shape)) return false;
      const lim = limits(shape.businessObject);
      if (lim.resize === 'none') return false;
      if (lim.resize === 'width' && ctx.direction && ctx.direction !== 'e' && ctx.direction !== 'w') return false;
      // The middle of the top and bottom edges holds the pins (steps, jumps): no handle there, so
      // a drag from a pin always draws a wire (height changes by the corners).
      if ((ctx.direction === 'n' || ctx.direction === 's') && pinCounts(shape.businessObject).inputs + pinCounts(shape.businessObject).outputs > 0) return false;
      const b = ctx.newBounds;
      if (b) {
        if (b.width < lim.min.w || b.width > lim.max.w || b.height < lim.min.h || b.height > lim.max.h) return false;
      }
      return true;
    });
  }
}

/** Block kinds a chart of `target` may not hold (interfaces.md, seed 001 chapter 3: no AND
 *  branches and no actions in ATMT/EATMT: the automaton runs one state at a time and its
 *  outputs are the states themselves). */
export function kindsRefusedBy(target: ChartTarget | undefined): ElementKind[] {
  return target === 'atmt' || target === 'eatmt' ? ['simultaneousDivergence', 'simultaneousConvergence', 'actionBlock'] : [];
}

/** Why a chart of `target` refuses a block of `kind` (translated), or '' when it does not. */
export function refusalReason(kind: ElementKind, target: ChartTarget | undefined, t: (key: string, opts?: Record<string, unknown>) => string): string {
  if (!kindsRefusedBy(target).includes(kind)) return '';
  const block = (target ?? '').toUpperCase();
  return kind === 'actionBlock' ? t('palette.noActions', { block }) : t('palette.noSimultaneous', { block });
}

function isBlock(e: unknown): e is SfcShape {
  return !!e && !isConnection(e) && !!(e as SfcShape).businessObject;
}

/** The kinds may be wired source → target (VALID_TARGETS) and they are two blocks. */
export function kindsMayConnect(source: SfcShape, target: SfcShape): boolean {
  if (source === target) return false;
  return VALID_TARGETS[source.businessObject.kind].includes(target.businessObject.kind);
}

/** Free input pins of `shape`; `ignore`'s pin counts as free (it is being reconnected). */
export function freeInputs(shape: SfcShape, ignore?: SfcConnection): number[] {
  const taken = new Set(shape.incoming.filter((c) => c !== ignore).map((c) => c.businessObject.targetPin));
  const out: number[] = [];
  for (let i = 0; i < pinCounts(shape.businessObject).inputs; i++) if (!taken.has(i)) out.push(i);
  return out;
}

export function freeOutputs(shape: SfcShape, ignore?: SfcConnection): number[] {
  const taken = new Set(shape.outgoing.filter((c) => c !== ignore).map((c) => c.businessObject.sourcePin));
  const out: number[] = [];
  for (let i = 0; i < pinCounts(shape.businessObject).outputs; i++) if (!taken.has(i)) out.push(i);
  return out;
}

/** Whether a new wire from output `sourcePin` of `source` to input `targetPin` of `target` is valid. */
export function canWire(source: SfcShape, sourcePin: number, target: SfcShape, targetPin: number, ignore?: SfcConnection): boolean {
  return (
    kindsMayConnect(source, target) &&
    freeOutputs(source, ignore).includes(sourcePin) &&
    freeInputs(target, ignore).includes(targetPin)
  );
}

/** The free pin of `shape` (inputs or outputs) nearest to `p`, within `radius`. */
export function nearestFreePin(
  shape: SfcShape,
  side: 'in' | 'out',
  p: Point,
  radius = PIN_SNAP,
  ignore?: SfcConnection,
): { pin: number; at: Point; dist: number } | undefined {
  const pins = side === 'in' ? freeInputs(shape, ignore) : freeOutputs(shape, ignore);
  let best: { pin: number; at: Point; dist: number } | undefined;
  for (const pin of pins) {
    const at = side === 'in' ? inputPin(shape.businessObject, shape, pin) : outputPin(shape.businessObject, shape, pin);
    const dist = Math.hypot(at.x - p.x, at.y - p.y);
    if (dist <= radius && (!best || dist < best.dist)) best = { pin, at, dist };
  }
  return best;
}
