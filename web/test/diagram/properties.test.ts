// updateElement of each property: the document changes, the drawing shows it, undo restores.
import { describe, expect, it } from 'vitest';
import { mount } from './harness';
import { conveyorDoc } from './fixtures';

type Case = [id: string, props: Record<string, unknown>, drawn?: string];

const CASES: Case[] = [
  ['step:Run', { name: 'Running' }, 'Running : 1'],
  ['step:Run', { tag: 7 }, 'Run : 7'],
  ['step:Run', { tag: undefined }],
  ['step:Run', { initial: true }],
  ['step:Run', { timeout: 'T#2m' }, 'T#2m'],
  ['step:Run', { description: 'Belt running' }, 'Belt running'],
  ['step:Run', { background: '#dcfce7' }],
  ['step:Run', { foreground: '#7c2d12' }],
  ['step:Run', { lineWidth: 3 }],
  ['transition:Go', { condition: 'start AND ready' }, 'start AND ready'],
  ['transition:Go', { conditionLanguage: 'IL', condition: 'LD start\nAND ready' }, 'LD start'],
  ['transition:Go', { priority: 2 }],
  ['transition:Go', { hideLabel: true }],
  ['transition:Go', { name: 'Start' }, 'Start'],
  ['b2', { pins: 3 }],
  ['b4', { target: 'Run' }, 'Run'],
  ['b5', { text: 'Another note' }, 'Another note'],
  ['b5', { align: 'center' }],
  ['b5', { font: 'italic 14px serif' }],
  ['b1', { associations: [{ qualifier: 'S', action: 'Motor' }, { qualifier: 'L', duration: 'T#5s', action: 'Horn', indicator: 'h' }] }, 'L, T#5s'],
  ['b1', { step: 'step:Init' }],
  ['c5', { color: '#16a34a' }],
  ['c5', { lineWidth: 3 }],
  ['step:A', { x: 10, y: 370 }],
  ['step:B', { w: 100, h: 50 }],
];

describe('updateElement', () => {
  for (const [id, props, drawn] of CASES) {
    it(`${id} ${JSON.stringify(props)}`, () => {
      const { canvas, get } = mount();
      canvas.load(conveyorDoc());
      const before = canvas.getDoc();
      canvas.updateElement(id, props);
      const after = canvas.getDoc();
      const changed = (after.elements.find((e) => e.id === id) ?? after.connections.find((c) => c.id === id)) as unknown as Record<string, unknown>;
      for (const [k, v] of Object.entries(props)) {
        if (v === undefined) expect(k in changed).toBe(false);
        else expect(changed[k]).toStrictEqual(v);
      }
      if (drawn) {
        const gfx = get('elementRegistry').getGraphics(id) as Element;
        expect(gfx.textContent).toContain(drawn);
      }
      canvas.undo();
      expect(canvas.getDoc()).toStrictEqual(before);
    });
  }

  it('renaming a step renames the jumps to it', () => {
    const { canvas } = mount();
    canvas.load(conveyorDoc());
    canvas.updateElement('step:Init', { name: 'Idle' });
    expect(canvas.getDoc().elements.find((e) => e.id === 'b4')!.target).toBe('Idle');
    canvas.undo();
    expect(canvas.getDoc().elements.find((e) => e.id === 'b4')!.target).toBe('Init');
  });

  it('fewer pins drop the wires of the removed pins; more pins widen a narrow bar', () => {
    const { canvas } = mount();
    const d = conveyorDoc();
    const b3 = d.elements.find((e) => e.id === 'b3')!;
    b3.pins = 3;
    b3.w = 160;
    d.elements.push({ id: 'step:C', kind: 'step', x: 150, y: 360, w: 60, h: 40, name: 'C' });
    d.connections.push({ id: 'c10', source: 'b3', sourcePin: 2, target: 'step:C', targetPin: 0 });
    canvas.load(d);
    const wires = () => canvas.getDoc().connections.map((c) => c.id);
    expect(wires()).toContain('c10');
    const before = canvas.getDoc();
    canvas.updateElement('b3', { pins: 2 });
    expect(wires()).not.toContain('c10');
    expect(wires()).toContain('c8');
    canvas.undo();
    expect(canvas.getDoc()).toStrictEqual(before);
    canvas.updateElement('b3', { pins: 8 });
    const wide = canvas.getDoc().elements.find((e) => e.id === 'b3')!;
    expect(wide.pins).toBe(8);
    expect(wide.w).toBe(160);
    // Wires stay on their (moved) pins.
    for (const c of canvas.getDoc().connections.filter((c) => c.source === 'b3')) {
      expect(c.waypoints![0]).toEqual({ x: 20 + 10 + Math.round((140 * c.sourcePin) / 7 / 10) * 10, y: 330 });
    }
    canvas.undo();
    canvas.updateElement('b2', { pins: 12 });
    expect(canvas.getDoc().elements.find((e) => e.id === 'b2')!.w).toBe(240);
  });

  it('refuses bad values with a located message', () => {
    const { canvas } = mount();
    canvas.load(conveyorDoc());
    expect(() => canvas.updateElement('nope', { name: 'x' })).toThrow(/updateElement: no block or connection "nope"/);
    expect(() => canvas.updateElement('step:A', { kind: 'transition' })).toThrow(/updateElement\(step:A\): "kind" cannot be changed/);
    expect(() => canvas.updateElement('step:A', { x: 'left' as unknown as number })).toThrow(/updateElement\(step:A\): "x" must be a number/);
    expect(() => canvas.updateElement('b2', { pins: 1 })).toThrow(/pins must be an integer ≥ 2/);
    expect(canvas.canUndo()).toBe(false);
  });

  it('a transition keeps its fixed size', () => {
    const { canvas } = mount();
    canvas.load(conveyorDoc());
    canvas.updateElement('transition:Go', { w: 200, h: 80, x: 130 });
    expect(canvas.getDoc().elements.find((e) => e.id === 'transition:Go')).toMatchObject({ x: 130, w: 40, h: 20 });
  });
});
