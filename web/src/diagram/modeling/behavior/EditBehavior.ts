// Interactive editing details: blocks snap to the grid by their top-left corner; a block
// created or moved over another block or a wire stays a block of the chart (never a child of
// the block under it); resizing keeps each kind within its limits, bars change only their
// width, Shift resizes symmetrically about the centre.
import { limits } from '../../geometry';
import type { Service, SfcShape } from '../../model';

export class EditBehavior {
  static $inject = ['eventBus', 'injector', 'canvas'];

  constructor(eventBus: Service, injector: Service, canvas: Service) {
    // Absent on a read-only canvas.
    const resize = injector.get('resize', false);
    // diagram-js makes the hovered element the new parent: a chart is flat, so whatever is
    // under the cursor, the parent is the chart (before Create and Move read the hover).
    eventBus.on(['create.hover', 'create.move', 'shape.move.hover', 'shape.move.move'], 2000, (event: Service) => {
      const root = canvas.getRootElement();
      if (event.hover && event.hover !== root) event.hover = root;
    });
    eventBus.on(['shape.move.start', 'create.start'], 1500, (event: Service) => {
      const ctx = event.context;
      ctx.gridSnappingContext = { ...(ctx.gridSnappingContext ?? {}), snapLocation: 'top-left' };
    });

    eventBus.on('resize.move', 750, (event: Service) => {
      const ctx = event.context;
      const shape = ctx.shape as SfcShape;
      if (!resize || !shape.businessObject || !ctx.newBounds) return;
      ctx.newBounds = constrainResize(shape, ctx.direction, ctx.newBounds, !!event.originalEvent?.shiftKey);
      ctx.canExecute = resize.canResize(ctx);
    });
  }
}

export interface Bounds {
  x: number;
  y: number;
  width: number;
  height: number;
}

/** The bounds a resize of `shape` by its `direction` handle ends up with. */
export function constrainResize(shape: SfcShape, direction: string, nb: Bounds, symmetric: boolean): Bounds {
  const lim = limits(shape.businessObject);
  let left = nb.x;
  let right = nb.x + nb.width;
  let top = nb.y;
  let bottom = nb.y + nb.height;
  const oLeft = shape.x;
  const oRight = shape.x + shape.width;
  const oTop = shape.y;
  const oBottom = shape.y + shape.height;
  if (lim.resize === 'width') {
    top = oTop;
    bottom = oBottom;
  }
  if (symmetric) {
    if (direction.includes('e')) left = oLeft - (right - oRight);
    if (direction.includes('w')) right = oRight + (oLeft - left);
    if (direction.includes('s') && lim.resize !== 'width') top = oTop - (bottom - oBottom);
    if (direction.includes('n') && lim.resize !== 'width') bottom = oBottom + (oTop - top);
  }
  const fit = (a: number, b: number, min: number, max: number, fromA: boolean, fromB: boolean): [number, number] => {
    const size = Math.min(max, Math.max(min, b - a));
    if (size === b - a) return [a, b];
    if (fromA && fromB) {
      const c = (a + b) / 2;
      return [c - size / 2, c + size / 2];
    }
    return fromA ? [b - size, b] : [a, a + size];
  };
  const we = direction.includes('w');
  const ea = direction.includes('e');
  [left, right] = fit(left, right, lim.min.w, lim.max.w, we || (symmetric && ea), ea || (symmetric && we));
  const no = direction.includes('n');
  const so = direction.includes('s');
  [top, bottom] = fit(top, bottom, lim.min.h, lim.max.h, no || (symmetric && so), so || (symmetric && no));
  return { x: left, y: top, width: right - left, height: bottom - top };
}
