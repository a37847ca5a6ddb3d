// Keeps wires on their pins: edited bends stay orthogonal, end on the pins and go round the
// blocks and labels they would cross, a reconnected
// end takes the nearest free pin of its new block, and blocks whose pins gained or lost a wire
// are drawn again (input pins become arrows when wired).
import CommandInterceptor from 'diagram-js/lib/command/CommandInterceptor.js';
import type { Point } from '../../../doc';
import { normalizeWire } from '../../geometry';
import { obstaclesOf, wireEnds } from '../../layout/SfcLayouter';
import { hits, route } from '../../layout/router';
import { isConnection, type Service, type SfcConnection, type SfcShape } from '../../model';
import { freeInputs, freeOutputs, nearestFreePin } from '../../rules/SfcRules';

export class WireBehavior extends CommandInterceptor {
  static $inject = ['eventBus', 'elementRegistry', 'modeling'];

  private pending = new Set<SfcShape>();

  constructor(eventBus: Service, elementRegistry: Service, modeling: Service) {
    super(eventBus);

    this.preExecute('connection.updateWaypoints', (event: Service) => {
      const ctx = event.context;
      const c = ctx.connection as SfcConnection;
      const { start, end } = wireEnds(c);
      let points = normalizeWire(ctx.newWaypoints as Point[], start, end, true);
      // A bend dragged across a block or a label: the wire goes round it, along the vertical
      // run the user dragged when that is free.
      const obstacles = obstaclesOf(elementRegistry);
      if (hits(points, obstacles) > 0) points = route(start, end, obstacles, draggedLane(points, start, end));
      ctx.newWaypoints = points;
    });

    this.preExecute('connection.reconnect', (event: Service) => {
      const ctx = event.context;
      const c = ctx.connection as SfcConnection;
      const docking = ctx.dockingOrPoints;
      const props: Record<string, number> = {};
      if (ctx.newTarget && ctx.newTarget !== c.target) {
        const at: Point = Array.isArray(docking) ? docking[docking.length - 1] : (docking ?? c.waypoints[c.waypoints.length - 1]);
        const pin = nearestFreePin(ctx.newTarget, 'in', at, Infinity, c)?.pin ?? freeInputs(ctx.newTarget, c)[0];
        if (pin === undefined) throw new Error(`reconnect ${c.id}: block ${ctx.newTarget.id} has no free input pin`);
        if (pin !== c.businessObject.targetPin) props.targetPin = pin;
      }
      if (ctx.newSource && ctx.newSource !== c.source) {
        const at: Point = Array.isArray(docking) ? docking[0] : (docking ?? c.waypoints[0]);
        const pin = nearestFreePin(ctx.newSource, 'out', at, Infinity, c)?.pin ?? freeOutputs(ctx.newSource, c)[0];
        if (pin === undefined) throw new Error(`reconnect ${c.id}: block ${ctx.newSource.id} has no free output pin`);
        if (pin !== c.businessObject.sourcePin) props.sourcePin = pin;
      }
      if (Object.keys(props).length > 0) modeling.updateElement(c, props);
    });

    // Remember the blocks at both ends of every wire a command touched.
    const collect = (event: Service) => {
      const ctx = event.context ?? {};
      for (const k of ['source', 'target', 'oldSource', 'oldTarget', 'newSource', 'newTarget']) {
        const s = ctx[k];
        if (s && !isConnection(s) && s.businessObject) this.pending.add(s);
      }
      const c = ctx.connection;
      if (c && isConnection(c)) {
        if (c.source) this.pending.add(c.source);
        if (c.target) this.pending.add(c.target);
      }
    };
    this.executed(collect);
    this.reverted(collect);

    eventBus.on('elements.changed', 1500, (event: Service) => {
      const elements: Service[] = event.elements;
      const seen = new Set(elements);
      for (const s of this.pending) {
        if (!seen.has(s) && elementRegistry.get(s.id) === s) {
          elements.push(s);
          seen.add(s);
        }
      }
      this.pending.clear();
      // Action blocks draw the link to their step: redraw them when the step changed.
      const steps = new Set(elements.filter((e) => e.businessObject?.kind === 'step').map((e) => e.id));
      if (steps.size > 0) {
        for (const ab of elementRegistry.filter((e: Service) => e.businessObject?.kind === 'actionBlock')) {
          if (steps.has(ab.businessObject.step) && !seen.has(ab)) {
            elements.push(ab);
            seen.add(ab);
          }
        }
      }
    });
  }
}

/** The x of a vertical run of a wire off both pins' axes (the run a user dragged sideways). */
function draggedLane(points: Point[], start: Point, end: Point): number | undefined {
  for (let i = 1; i < points.length; i++) {
    const a = points[i - 1];
    const b = points[i];
    if (a.x === b.x && a.y !== b.y && a.x !== start.x && a.x !== end.x) return a.x;
  }
  return undefined;
}
