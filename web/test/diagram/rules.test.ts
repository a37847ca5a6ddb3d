// Which wires may be drawn: the valid pairs of sfc-doc, output → input of another block, one
// wire per pin, snapping to the nearest free valid pin within PIN_SNAP.
import { describe, expect, it } from 'vitest';
import { mount } from './harness';
import { VALID_TARGETS, type EditorDoc, type Element, type ElementKind } from '../../src/doc';
import { defaultSize, inputPin } from '../../src/diagram/geometry';
import { canWire } from '../../src/diagram/rules/SfcRules';

const KINDS = Object.keys(VALID_TARGETS) as ElementKind[];

function block(id: string, kind: ElementKind, x: number, y: number): Element {
  const s = defaultSize(kind);
  return { id, kind, x, y, w: s.w, h: s.h, ...(kind.endsWith('gence') ? { pins: 2 } : {}) };
}

function twoBlocks(a: ElementKind, b: ElementKind): EditorDoc {
  return {
    pou: 'P',
    pouKind: 'program',
    target: 'blank',
    declarations: '',
    actions: [],
    elements: [block('a', a, 100, 100), block('b', b, 100, 300)],
    connections: [],
  };
}

/** sfc-doc's `valid_pair` (crates/sfc-doc/src/graph.rs), pair by pair: the canvas accepts
 *  exactly these wires, the three mixed branch structures included. */
const SFC_DOC_PAIRS: [ElementKind, ElementKind][] = [
  ['step', 'transition'],
  ['step', 'selectionDivergence'],
  ['step', 'simultaneousConvergence'],
  ['selectionDivergence', 'transition'],
  ['selectionDivergence', 'simultaneousConvergence'],
  ['simultaneousConvergence', 'transition'],
  ['transition', 'step'],
  ['transition', 'simultaneousDivergence'],
  ['transition', 'selectionConvergence'],
  ['transition', 'jump'],
  ['simultaneousDivergence', 'step'],
  ['simultaneousDivergence', 'selectionConvergence'],
  ['simultaneousDivergence', 'jump'],
  ['selectionConvergence', 'step'],
];

describe('connection rules', () => {
  it("are sfc-doc's valid pairs", () => {
    const pairs = KINDS.flatMap((a) => VALID_TARGETS[a].map((b) => `${a} → ${b}`)).sort();
    expect(pairs).toEqual(SFC_DOC_PAIRS.map(([a, b]) => `${a} → ${b}`).sort());
  });

  for (const a of KINDS) {
    for (const b of KINDS) {
      const expected = VALID_TARGETS[a].includes(b);
      it(`${a} → ${b}: ${expected ? 'allowed' : 'refused'}`, () => {
        const { canvas, get } = mount();
        canvas.load(twoBlocks(a, b));
        const reg = get('elementRegistry');
        const rules = get('rules');
        expect(rules.allowed('connection.create', { source: reg.get('a'), target: reg.get('b') })).toBe(expected);
        expect(canWire(reg.get('a'), 0, reg.get('b'), 0)).toBe(expected);
        // The drawing tool snaps only to pins it may connect to.
        const connect = get('sfcConnect');
        const target = reg.get('b');
        const pin = inputPin(target.businessObject, target, 0);
        const found = connect.findCandidate({ shape: reg.get('a'), side: 'out' }, { x: pin.x + 3, y: pin.y - 5 });
        expect(!!found).toBe(expected);
      });
    }
  }

  it('keeps the chart flat: nothing is created or moved into a block or a wire', () => {
    const { canvas, get } = mount();
    const doc = twoBlocks('step', 'transition');
    doc.connections.push({ id: 'w', source: 'a', sourcePin: 0, target: 'b', targetPin: 0 });
    canvas.load(doc);
    const reg = get('elementRegistry');
    const rules = get('rules');
    const root = get('canvas').getRootElement();
    const shape = get('sfcPalette').newShape(get('sfcPalette')['specs']().find((x: { id: string }) => x.id === 'step'));
    for (const target of [reg.get('a'), reg.get('w')]) {
      expect(rules.allowed('shape.create', { shape, target })).toBe(false);
      expect(rules.allowed('elements.move', { shapes: [reg.get('b')], target })).toBe(false);
    }
    expect(rules.allowed('shape.create', { shape, target: root })).toBe(true);
    expect(rules.allowed('elements.move', { shapes: [reg.get('b')], target: root })).toBe(true);
    // Dragged over a block, the block under the cursor is not the new parent: the chart is.
    let seen: unknown;
    get('eventBus').on('create.hover', 100, (e: { hover: unknown }) => void (seen = e.hover));
    get('eventBus').fire('create.hover', { hover: reg.get('a'), context: {} });
    expect(seen).toBe(root);
  });

  it('refuses a wire from a block to itself', () => {
    const { canvas, get } = mount();
    canvas.load(twoBlocks('step', 'transition'));
    const s = get('elementRegistry').get('a');
    expect(get('rules').allowed('connection.create', { source: s, target: s })).toBe(false);
  });

  it('allows one wire per pin', () => {
    const { canvas, get } = mount();
    const doc = twoBlocks('step', 'transition');
    doc.elements.push(block('t2', 'transition', 300, 300), block('s2', 'step', 300, 100));
    doc.connections.push({ id: 'w', source: 'a', sourcePin: 0, target: 'b', targetPin: 0 });
    canvas.load(doc);
    const reg = get('elementRegistry');
    const rules = get('rules');
    // a's only output is taken, and so is b's only input.
    expect(rules.allowed('connection.create', { source: reg.get('a'), target: reg.get('t2') })).toBe(false);
    expect(rules.allowed('connection.create', { source: reg.get('s2'), target: reg.get('b') })).toBe(false);
    expect(rules.allowed('connection.create', { source: reg.get('s2'), target: reg.get('t2') })).toBe(true);
    // Reconnecting the wire's own end to where it is stays allowed.
    expect(rules.allowed('connection.reconnect', { connection: reg.get('w'), source: reg.get('a'), target: reg.get('b') })).toBe(true);
    expect(rules.allowed('connection.reconnect', { connection: reg.get('w'), source: reg.get('a'), target: reg.get('t2') })).toBe(true);
    expect(rules.allowed('connection.reconnect', { connection: reg.get('w'), source: reg.get('s2'), target: reg.get('t2') })).toBe(true);
  });

  it('snaps to the nearest free pin within 15 units, and to none farther', () => {
    const { canvas, get } = mount();
    const doc = twoBlocks('step', 'simultaneousConvergence');
    doc.elements[1] = { ...doc.elements[1], w: 120, pins: 3 };
    canvas.load(doc);
    const reg = get('elementRegistry');
    const connect = get('sfcConnect');
    const from = { shape: reg.get('a'), side: 'out' };
    // Pins of a 120-wide bar at x=100 with 3 inputs: 110, 160, 210.
    expect(connect.findCandidate(from, { x: 158, y: 295 })).toMatchObject({ pin: 1, at: { x: 160, y: 300 } });
    expect(connect.findCandidate(from, { x: 200, y: 305 })).toMatchObject({ pin: 2 });
    expect(connect.findCandidate(from, { x: 135, y: 300 })).toBeUndefined();
    expect(connect.findCandidate(from, { x: 160, y: 270 })).toBeUndefined();
  });

  it('a read-only canvas allows nothing', () => {
    const { canvas, get } = mount({ readOnly: true });
    canvas.load(twoBlocks('step', 'transition'));
    const reg = get('elementRegistry');
    const rules = get('rules');
    expect(rules.allowed('connection.create', { source: reg.get('a'), target: reg.get('b') })).toBe(false);
    expect(rules.allowed('elements.move', { shapes: [reg.get('a')] })).toBe(false);
    expect(rules.allowed('shape.resize', { shape: reg.get('a') })).toBe(false);
    expect(rules.allowed('elements.delete', { elements: [reg.get('a')] })).toBe(false);
  });
});

describe('drawing a wire with the mouse', () => {
  it('drags from an output pin to an input pin and connects them', () => {
    const { canvas, get } = mount();
    canvas.load(twoBlocks('step', 'transition'));
    const reg = get('elementRegistry');
    const svg = get('canvas')._svg as SVGSVGElement;
    const a = reg.get('a');
    const from = { x: a.x + a.width / 2, y: a.y + a.height - 2 };
    const gfx = reg.getGraphics(a);
    const hit = gfx.querySelector('.djs-hit') as SVGElement;
    hit.dispatchEvent(new MouseEvent('mousedown', { bubbles: true, clientX: from.x, clientY: from.y, button: 0 }));
    const move = (x: number, y: number) => document.dispatchEvent(new MouseEvent('mousemove', { bubbles: true, clientX: x, clientY: y }));
    move(from.x, from.y + 30);
    move(121, 292); // near the transition's input pin (120, 300)
    document.dispatchEvent(new MouseEvent('mouseup', { bubbles: true, clientX: 121, clientY: 292 }));
    expect(svg).toBeTruthy();
    const doc = canvas.getDoc();
    expect(doc.connections).toHaveLength(1);
    expect(doc.connections[0]).toMatchObject({ source: 'a', sourcePin: 0, target: 'b', targetPin: 0 });
    expect(doc.connections[0].waypoints).toEqual([{ x: 140, y: 140 }, { x: 140, y: 220 }, { x: 120, y: 220 }, { x: 120, y: 300 }]);
  });

  it('refuses the drop on a block that cannot take the wire', () => {
    const { canvas, get } = mount();
    canvas.load(twoBlocks('step', 'step'));
    const reg = get('elementRegistry');
    const a = reg.get('a');
    const hit = reg.getGraphics(a).querySelector('.djs-hit') as SVGElement;
    hit.dispatchEvent(new MouseEvent('mousedown', { bubbles: true, clientX: 140, clientY: 139, button: 0 }));
    document.dispatchEvent(new MouseEvent('mousemove', { bubbles: true, clientX: 140, clientY: 200 }));
    document.dispatchEvent(new MouseEvent('mousemove', { bubbles: true, clientX: 140, clientY: 298 }));
    document.dispatchEvent(new MouseEvent('mouseup', { bubbles: true, clientX: 140, clientY: 298 }));
    expect(canvas.getDoc().connections).toHaveLength(0);
  });
});

describe('ATMT/EATMT target rules while drawing', () => {
  const chart = (target: 'atmt' | 'eatmt'): EditorDoc => ({
    ...twoBlocks('step', 'transition'),
    target,
  });

  it('an action block is refused at the drop, with the reason', () => {
    const { canvas, get } = mount();
    canvas.load(chart('atmt'));
    const shape = get('elementFactory').createShape({ businessObject: block('', 'actionBlock', 0, 0), width: 180, height: 20 });
    const root = get('canvas').getRootElement();
    expect(get('rules').allowed('shape.create', { shape, target: root })).toBe(false);
    const entries = get('palette')._entries ?? get('sfcPalette').getPaletteEntries();
    const html: string = entries['create.action-block'].html;
    expect(html).toContain('refused');
    expect(html).toContain('palette.noActions');
    canvas.load({ ...chart('atmt'), target: 'blank' });
    expect(get('rules').allowed('shape.create', { shape, target: root })).toBe(true);
  });

  it("a transition's Tag is its condition number", () => {
    const { canvas } = mount();
    canvas.load(chart('atmt'));
    canvas.updateElement('b', { tag: 5 });
    expect(canvas.getDoc().elements.find((e) => e.id === 'b')).toMatchObject({ tag: 5, condition: 'C5' });
    canvas.undo();
    expect(canvas.getDoc().elements.find((e) => e.id === 'b')?.tag).toBeUndefined();
    canvas.redo();
    // A condition typed as an input sets the Tag.
    canvas.updateElement('b', { condition: 'C7' });
    expect(canvas.getDoc().elements.find((e) => e.id === 'b')).toMatchObject({ tag: 7, condition: 'C7' });
    // EATMT: lower-case inputs, negation kept.
    canvas.load(chart('eatmt'));
    canvas.updateElement('b', { condition: '!c3' });
    canvas.updateElement('b', { tag: 20 });
    expect(canvas.getDoc().elements.find((e) => e.id === 'b')).toMatchObject({ tag: 20, condition: '!c20' });
  });
});
