import { hits } from '../../src/diagram/layout/router';
import { describe, expect, it } from 'vitest';
import { mount } from './harness';
import { conveyorDoc } from './fixtures';
import { makeBigDoc } from './big';
import { inputPin, outputPin } from '../../src/diagram/geometry';
import type { EditorDoc } from '../../src/doc';

function orthogonal(points: { x: number; y: number }[]): boolean {
  return points.every((p, i) => i === 0 || p.x === points[i - 1].x || p.y === points[i - 1].y);
}

describe('load → getDoc', () => {
  it('gives back the conveyor document unchanged', () => {
    const { canvas } = mount();
    const d = conveyorDoc();
    canvas.load(d);
    expect(canvas.getDoc()).toStrictEqual(d);
    expect(JSON.stringify(canvas.getDoc())).toBe(JSON.stringify(d));
  });

  it("keeps sfc-doc's additions: final steps and the attributes the editor does not edit", () => {
    const { canvas } = mount();
    const d = conveyorDoc();
    const attrs = [{ name: 'sfc.adddata', value: '<data/>' }, { name: 'vendor.flag' }];
    d.attributes = [{ name: 'vendor.pou', value: '1' }];
    d.actions = [{ name: 'Horn', language: 'ST', body: 'x := 1;', attributes: attrs }];
    const step = d.elements.find((e) => e.kind === 'step' && !e.initial)!;
    step.final = true;
    step.attributes = attrs;
    const transition = d.elements.find((e) => e.kind === 'transition')!;
    transition.attributes = [{ name: 'sfc.reference', value: 'Cond' }];
    canvas.load(d);
    expect(canvas.getDoc()).toStrictEqual(d);
    // Through edits of other fields, of the chart, and their undo.
    canvas.updateElement(step.id, { description: 'moved' });
    canvas.updateDoc({ description: 'changed' });
    const edited = canvas.getDoc();
    expect(edited.attributes).toEqual(d.attributes);
    expect(edited.actions[0].attributes).toEqual(attrs);
    const s = edited.elements.find((e) => e.id === step.id)!;
    expect([s.final, s.attributes, s.description]).toEqual([true, attrs, 'moved']);
    canvas.undo();
    canvas.undo();
    expect(canvas.getDoc()).toStrictEqual(d);
  });

  it('keeps the comments of steps, transitions and actions and the trailing comments', () => {
    const { canvas, get } = mount();
    const d = conveyorDoc();
    const step = d.elements.find((e) => e.kind === 'step')!;
    step.comments = ['(* fill the tank *)', '// two'];
    const transition = d.elements.find((e) => e.kind === 'transition')!;
    transition.comments = ['(* when full *)'];
    d.actions = [{ name: 'Horn', language: 'ST', body: 'x := 1;', comments: ['// horn'] }];
    d.trailingComments = ['(* the end *)'];
    canvas.load(d);
    expect(canvas.getDoc()).toStrictEqual(d);
    // A moved step keeps its comments; another block's edit leaves them.
    canvas.updateElement(transition.id, { description: 'edited' });
    get('modeling').moveElements([get('elementRegistry').get(step.id)], { x: 40, y: 0 });
    const edited = canvas.getDoc();
    expect(edited.elements.find((e) => e.id === step.id)!.comments).toEqual(step.comments);
    expect(edited.elements.find((e) => e.id === transition.id)!.comments).toEqual(transition.comments);
    expect(edited.actions[0].comments).toEqual(['// horn']);
    expect(edited.trailingComments).toEqual(['(* the end *)']);
  });

  it('a pasted copy of a step has no comments; deleting a step deletes its comments', () => {
    const { canvas, get } = mount();
    const d = conveyorDoc();
    const step = d.elements.find((e) => e.kind === 'step')!;
    step.comments = ['(* fill the tank *)'];
    canvas.load(d);
    get('copyPaste').copy([get('elementRegistry').get(step.id)]);
    get('copyPaste').paste({ element: get('canvas').getRootElement(), point: { x: 600, y: 600 } });
    const pasted = canvas.getDoc().elements.at(-1)!;
    expect([pasted.kind, pasted.comments]).toEqual(['step', undefined]);
    expect(canvas.getDoc().elements.find((e) => e.id === step.id)!.comments).toEqual(['(* fill the tank *)']);
    get('modeling').removeShape(get('elementRegistry').get(step.id));
    expect(JSON.stringify(canvas.getDoc())).not.toContain('fill the tank');
  });

  it('gives back a 500-step document unchanged', () => {
    const { canvas } = mount();
    const d = makeBigDoc(500);
    expect(d.elements.filter((e) => e.kind === 'step')).toHaveLength(500);
    const t0 = performance.now();
    canvas.load(d);
    const ms = performance.now() - t0;
    expect(canvas.getDoc()).toStrictEqual(d);
    // jsdom is several times slower than a browser; the browser test (e2e/tests/perf.mjs)
    // prints the real figures. Tests assert no timings.
    console.log(`500 steps loaded in jsdom in ${ms.toFixed(0)} ms`);
  }, 60_000);

  it('keeps doc-level fields and clears the undo history', () => {
    const { canvas } = mount();
    canvas.load(conveyorDoc());
    canvas.updateDoc({ pou: 'Other' });
    expect(canvas.canUndo()).toBe(true);
    canvas.load(conveyorDoc());
    expect(canvas.canUndo()).toBe(false);
    expect(canvas.getDoc().pou).toBe('Conveyor');
    expect(canvas.isDirty()).toBe(false);
  });

  it('routes wires that come without waypoints, orthogonally from pin to pin', () => {
    const { canvas } = mount();
    const d = conveyorDoc();
    for (const c of d.connections) delete c.waypoints;
    canvas.load(d);
    const out = canvas.getDoc();
    const byId = new Map(out.elements.map((e) => [e.id, e]));
    for (const c of out.connections) {
      const wp = c.waypoints!;
      expect(wp.length).toBeGreaterThanOrEqual(2);
      expect(orthogonal(wp)).toBe(true);
      const s = byId.get(c.source)!;
      const t = byId.get(c.target)!;
      expect(wp[0]).toEqual(outputPin(s, { x: s.x, y: s.y, width: s.w, height: s.h }, c.sourcePin));
      expect(wp[wp.length - 1]).toEqual(inputPin(t, { x: t.x, y: t.y, width: t.w, height: t.h }, c.targetPin));
    }
    // Everything else is as loaded.
    const strip = (doc: EditorDoc) => ({ ...doc, connections: doc.connections.map(({ waypoints: _w, ...c }) => c) });
    expect(strip(out)).toStrictEqual(strip(d));
  });

  it('routes a loop back up a lane beside the blocks, through none of them', () => {
    const { canvas } = mount();
    const d = conveyorDoc();
    d.connections.push({ id: 'back', source: 'step:A', sourcePin: 0, target: 'transition:Go', targetPin: 0 });
    d.connections = d.connections.filter((c) => c.id !== 'c1');
    canvas.load(d);
    const wp = canvas.getDoc().connections.find((c) => c.id === 'back')!.waypoints!;
    expect(orthogonal(wp)).toBe(true);
    expect(wp[1].y).toBeGreaterThan(wp[0].y); // leaves downwards
    expect(wp[wp.length - 2].y).toBeLessThan(wp[wp.length - 1].y); // enters from above
    const blocks = canvas.getDoc().elements.map((e) => ({ x: e.x, y: e.y, width: e.w, height: e.h }));
    expect(hits(wp, blocks)).toBe(0);
  });
});

describe('load rejects what it cannot show, naming the culprit', () => {
  const cases: [string, (d: EditorDoc) => void, RegExp][] = [
    ['duplicate element id', (d) => d.elements.push({ ...d.elements[0] }), /element #12 "step:Init": duplicate id/],
    ['unknown kind', (d) => ((d.elements[1] as { kind: string }).kind = 'blob'), /unknown kind "blob"/],
    ['size not a number', (d) => ((d.elements[2] as { w: unknown }).w = 'wide'), /"step:Run": "w" is not a number/],
    ['missing source block', (d) => (d.connections[0].source = 'nope'), /connection #0 "c1": no source block "nope"/],
    ['no such output pin', (d) => (d.connections[3].sourcePin = 2), /"b2" has no output pin 2/],
    ['no such input pin', (d) => (d.connections[0].targetPin = 1), /"transition:Go" has no input pin 1/],
    ['input pin wired twice', (d) => d.connections.push({ id: 'x', source: 'step:A', sourcePin: 0, target: 'transition:Go', targetPin: 0 }), /input pin 0 of "transition:Go" already has a wire/],
    ['connection id equal to a block id', (d) => (d.connections[0].id = 'b1'), /id already used/],
  ];
  for (const [what, spoil, message] of cases) {
    it(what, () => {
      const { canvas } = mount();
      const d = conveyorDoc();
      spoil(d);
      expect(() => canvas.load(d)).toThrow(message);
    });
  }
});
