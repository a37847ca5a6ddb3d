// A big chart for performance checks (browser test and demo `?big=500`): a long sequence of
// steps with a two-way selection every 20 steps and a jump back to the initial step.
import type { Connection, EditorDoc, Element } from '../../src/doc';
import { inputPin, outputPin } from '../../src/diagram/geometry';
import { route as routeAround } from '../../src/diagram/layout/router';

/** A valid document with `n` steps (n ≥ 1), every wire with its polyline. */
export function makeBigDoc(n: number): EditorDoc {
  const elements: Element[] = [];
  const connections: Connection[] = [];
  const byId = new Map<string, Element>();
  let seq = 0;
  const add = (e: Omit<Element, 'id'> & { id?: string }): Element => {
    const el = { ...e, id: e.id ?? `b${++seq}` } as Element;
    elements.push(el);
    byId.set(el.id, el);
    return el;
  };
  const wire = (from: Element, sourcePin: number, to: Element, targetPin: number) => {
    const box = (e: Element) => ({ x: e.x, y: e.y, width: e.w, height: e.h });
    const start = outputPin(from, box(from), sourcePin);
    const end = inputPin(to, box(to), targetPin);
    connections.push({
      id: `c${connections.length + 1}`,
      source: from.id,
      sourcePin,
      target: to.id,
      targetPin,
      waypoints: routeAround(start, end, []),
    });
  };
  const step = (i: number, x: number, y: number): Element =>
    add({ id: `step:S${i}`, kind: 'step', x, y, w: 80, h: 40, name: `S${i}`, ...(i === 0 ? { initial: true } : {}) });
  const transition = (name: string, x: number, y: number, condition: string): Element =>
    add({ id: `transition:${name}`, kind: 'transition', x, y, w: 40, h: 20, name, condition });

  const X = 200;
  let y = 40;
  let made = 0;
  let prev = step(made++, X, y);
  y += 60;
  let t = 0;
  while (made < n) {
    if (made % 20 === 10 && made + 2 <= n) {
      // prev → selection divergence → two branches → convergence → next step.
      const div = add({ kind: 'selectionDivergence', x: X - 60, y, w: 200, h: 10, pins: 2 });
      wire(prev, 0, div, 0);
      y += 30;
      const ta = transition(`T${++t}`, X - 60, y, `x${t} > 10`);
      const tb = transition(`T${++t}`, X + 100, y, `x${t} <= 10`);
      wire(div, 0, ta, 0);
      wire(div, 1, tb, 0);
      y += 40;
      const sa = step(made++, X - 80, y);
      const sb = step(made++, X + 80, y);
      wire(ta, 0, sa, 0);
      wire(tb, 0, sb, 0);
      y += 60;
      const ua = transition(`T${++t}`, X - 60, y, `done${t}`);
      const ub = transition(`T${++t}`, X + 100, y, `done${t}`);
      wire(sa, 0, ua, 0);
      wire(sb, 0, ub, 0);
      y += 40;
      const conv = add({ kind: 'selectionConvergence', x: X - 60, y, w: 200, h: 10, pins: 2 });
      wire(ua, 0, conv, 0);
      wire(ub, 0, conv, 1);
      y += 30;
      if (made >= n) {
        const j = add({ kind: 'jump', x: X + 30, y, w: 20, h: 20, target: 'S0' });
        wire(conv, 0, j, 0);
        prev = j;
        break;
      }
      const s = step(made++, X, y);
      wire(conv, 0, s, 0);
      prev = s;
      y += 60;
      continue;
    }
    const tr = transition(`T${++t}`, X + 20, y, `timer${t}.Q`);
    wire(prev, 0, tr, 0);
    y += 40;
    const s = step(made++, X, y);
    wire(tr, 0, s, 0);
    prev = s;
    y += 60;
  }
  if (byId.get(prev.id)?.kind === 'step') {
    const tr = transition(`T${++t}`, X + 20, y, 'restart');
    wire(prev, 0, tr, 0);
    y += 40;
    const j = add({ kind: 'jump', x: X + 30, y, w: 20, h: 20, target: 'S0' });
    wire(tr, 0, j, 0);
  }
  return {
    pou: 'Big',
    pouKind: 'program',
    target: 'blank',
    declarations: 'VAR\nEND_VAR\n',
    actions: [],
    elements,
    connections,
  };
}
