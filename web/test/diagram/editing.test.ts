// Copy/paste names, resizing limits and pin placement, keyboard editing, the palette.
import { describe, expect, it } from 'vitest';
import { mount, type Mounted } from './harness';
import { conveyorDoc } from './fixtures';
import { inputPin, limits, minBarWidth, outputPin, pinX } from '../../src/diagram/geometry';
import { constrainResize } from '../../src/diagram/modeling/behavior/EditBehavior';
import type { SfcShape } from '../../src/diagram/model';
import type { ElementKind } from '../../src/doc';
import csJson from '../../src/i18n/cs.json';
import enJson from '../../src/i18n/en.json';

type Tree = { [k: string]: string | Tree };

/** A catalogue as flat `a.b` keys. */
function catalogue(tree: Tree, prefix = ''): Record<string, string> {
  const out: Record<string, string> = {};
  for (const [k, v] of Object.entries(tree)) {
    if (typeof v === 'string') out[prefix + k] = v;
    else Object.assign(out, catalogue(v, `${prefix}${k}.`));
  }
  return out;
}

function paste(m: Mounted, ids: string[], at = { x: 600, y: 600 }) {
  const reg = m.get('elementRegistry');
  m.get('copyPaste').copy(ids.map((id) => reg.get(id)));
  m.get('copyPaste').paste({ element: m.get('canvas').getRootElement(), point: at });
}

describe('copy and paste', () => {
  it('gives pasted steps and transitions fresh names and ids, keeps wires between them', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    paste(m, ['step:Run', 'b1', 'b2', 'transition:Box', 'transition#3', 'c3', 'c4', 'c5']);
    const doc = m.canvas.getDoc();
    const added = doc.elements.slice(12);
    expect(added.map((e) => e.kind)).toEqual(['step', 'actionBlock', 'selectionDivergence', 'transition', 'transition']);
    const names = doc.elements.filter((e) => e.name).map((e) => e.name!.toUpperCase());
    expect(new Set(names).size).toBe(names.length);
    expect(added[0].name).toBe('S1');
    expect(added[3].name).toBe('T1');
    expect(added[4].name).toBeUndefined(); // an unnamed transition stays unnamed
    const ids = new Set([...doc.elements, ...doc.connections].map((e) => e.id));
    expect(ids.size).toBe(doc.elements.length + doc.connections.length);
    // The pasted action block belongs to the pasted step.
    expect(added[1].step).toBe(added[0].id);
    // The three wires among the pasted blocks come along, attached to the copies.
    const pastedWires = doc.connections.slice(9);
    expect(pastedWires).toHaveLength(3);
    const addedIds = new Set(added.map((e) => e.id));
    for (const c of pastedWires) {
      expect(addedIds.has(c.source) && addedIds.has(c.target)).toBe(true);
    }
    // Pasting again gives the next names.
    paste(m, ['step:Run']);
    expect(m.canvas.getDoc().elements.at(-1)!.name).toBe('S2');
  });

  it('a pasted jump follows its pasted, renamed target step', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    paste(m, ['step:Init', 'b4']);
    const added = m.canvas.getDoc().elements.slice(12);
    expect(added[0].name).toBe('S1');
    expect(added[1].target).toBe('S1');
  });

  it('undo removes the whole paste', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    const before = m.canvas.getDoc();
    paste(m, ['step:A', 'step:B']);
    m.canvas.undo();
    expect(m.canvas.getDoc()).toStrictEqual(before);
  });
});

describe('resizing', () => {
  const shape = (kind: ElementKind, x: number, y: number, w: number, h: number, pins?: number) =>
    ({ x, y, width: w, height: h, businessObject: { id: 's', kind, x, y, w, h, pins } }) as unknown as SfcShape;

  it('keeps each kind within its limits', () => {
    const step = shape('step', 100, 100, 80, 40);
    expect(constrainResize(step, 'se', { x: 100, y: 100, width: 10, height: 5 }, false)).toEqual({ x: 100, y: 100, width: 40, height: 30 });
    expect(constrainResize(step, 'nw', { x: 170, y: 130, width: 10, height: 10 }, false)).toEqual({ x: 140, y: 110, width: 40, height: 30 });
    expect(constrainResize(step, 'e', { x: 100, y: 100, width: 900, height: 40 }, false)).toEqual({ x: 100, y: 100, width: 400, height: 40 });
    const jump = shape('jump', 0, 0, 20, 20);
    expect(constrainResize(jump, 'se', { x: 0, y: 0, width: 200, height: 200 }, false)).toEqual({ x: 0, y: 0, width: 60, height: 60 });
  });

  it('Shift resizes symmetrically about the centre', () => {
    const step = shape('step', 100, 100, 80, 40);
    expect(constrainResize(step, 'e', { x: 100, y: 100, width: 100, height: 40 }, true)).toEqual({ x: 80, y: 100, width: 120, height: 40 });
    expect(constrainResize(step, 'se', { x: 100, y: 100, width: 100, height: 60 }, true)).toEqual({ x: 80, y: 80, width: 120, height: 80 });
    // Limits hold around the centre too.
    expect(constrainResize(step, 'w', { x: 139, y: 100, width: 41, height: 40 }, true)).toEqual({ x: 120, y: 100, width: 40, height: 40 });
  });

  it('bars change only their width, never narrower than their pins need', () => {
    const bar = shape('selectionDivergence', 0, 0, 120, 10, 4);
    expect(constrainResize(bar, 'e', { x: 0, y: 0, width: 300, height: 40 }, false)).toEqual({ x: 0, y: 0, width: 300, height: 10 });
    expect(constrainResize(bar, 'e', { x: 0, y: 0, width: 20, height: 10 }, false)).toEqual({ x: 0, y: 0, width: minBarWidth(4), height: 10 });
    expect(limits({ kind: 'selectionDivergence', pins: 4 }).resize).toBe('width');
  });

  it('offers handles by kind: none on transitions, only sides on bars, none on the pins of steps and jumps', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    const reg = m.get('elementRegistry');
    const resize = m.get('resize');
    const dirs = (id: string) => ['n', 'w', 's', 'e', 'nw', 'ne', 'se', 'sw'].filter((d) => resize.canResize({ shape: reg.get(id), direction: d }));
    expect(dirs('transition:Go')).toEqual([]);
    expect(dirs('b2')).toEqual(['w', 'e']);
    expect(dirs('step:Run')).toEqual(['w', 'e', 'nw', 'ne', 'se', 'sw']);
    expect(dirs('b4')).toEqual(['w', 'e', 'nw', 'ne', 'se', 'sw']);
  });

  it('pins of a resized bar stay equidistant on the grid and keep their wires', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    const reg = m.get('elementRegistry');
    const b3 = reg.get('b3');
    m.get('modeling').resizeShape(b3, { x: 0, y: 320, width: 200, height: 10 });
    const doc = m.canvas.getDoc();
    const bar = doc.elements.find((e) => e.id === 'b3')!;
    const box = { x: bar.x, y: bar.y, width: bar.w, height: bar.h };
    expect([outputPin(bar, box, 0).x, outputPin(bar, box, 1).x]).toEqual([10, 190]);
    expect(inputPin(bar, box, 0)).toEqual({ x: 100, y: 320 });
    for (const id of ['c6', 'c7', 'c8']) {
      const c = doc.connections.find((x) => x.id === id)!;
      const wp = c.waypoints!;
      if (c.source === 'b3') expect(wp[0]).toEqual(outputPin(bar, box, c.sourcePin));
      else expect(wp.at(-1)).toEqual(inputPin(bar, box, c.targetPin));
      expect(wp.every((p, i) => i === 0 || p.x === wp[i - 1].x || p.y === wp[i - 1].y)).toBe(true);
    }
    // Equidistant, grid-aligned pins for any count.
    const xs = [0, 1, 2, 3].map((i) => pinX({ x: 0, y: 0, width: 160, height: 10 }, 4, i));
    expect(xs).toEqual([10, 60, 100, 150]);
    expect([0, 1, 2].map((i) => pinX({ x: 0, y: 0, width: 120, height: 10 }, 3, i))).toEqual([10, 60, 110]);
  });
});

describe('keyboard', () => {
  const key = (m: Mounted, k: string, mods: KeyboardEventInit = {}) => {
    const svg = m.get('canvas')._svg as SVGSVGElement;
    svg.dispatchEvent(new KeyboardEvent('keydown', { key: k, bubbles: true, ...mods }));
  };

  it('arrows move by the grid step, Shift+arrows by one unit', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    m.canvas.select(['step:A']);
    key(m, 'ArrowRight');
    expect(m.canvas.getDoc().elements.find((e) => e.id === 'step:A')).toMatchObject({ x: 10, y: 360 });
    key(m, 'ArrowDown', { shiftKey: true });
    expect(m.canvas.getDoc().elements.find((e) => e.id === 'step:A')).toMatchObject({ x: 10, y: 361 });
  });

  it('Delete removes the selection; Ctrl+Z, Ctrl+Y and Ctrl+Shift+Z undo and redo', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    const before = m.canvas.getDoc();
    m.canvas.select(['step:B', 'c8']);
    key(m, 'Delete');
    const after = m.canvas.getDoc();
    expect(after.elements.map((e) => e.id)).not.toContain('step:B');
    expect(after.connections.map((e) => e.id)).not.toContain('c8');
    key(m, 'z', { ctrlKey: true });
    expect(m.canvas.getDoc()).toStrictEqual(before);
    key(m, 'y', { ctrlKey: true });
    expect(m.canvas.getDoc()).toStrictEqual(after);
    key(m, 'z', { ctrlKey: true });
    key(m, 'z', { ctrlKey: true, shiftKey: true });
    expect(m.canvas.getDoc()).toStrictEqual(after);
  });

  it('Enter asks for the properties of the selected block', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    const asked: string[] = [];
    m.canvas.on('properties', (id) => asked.push(id));
    m.canvas.select(['transition:Go']);
    key(m, 'Enter');
    expect(asked).toEqual(['transition:Go']);
  });

  it('selection events carry the ids', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    const seen: string[][] = [];
    m.canvas.on('selection', (ids) => seen.push(ids));
    m.canvas.select(['step:A', 'c1']);
    expect(seen.at(-1)).toEqual(['step:A', 'c1']);
    expect(m.canvas.selection()).toEqual(['step:A', 'c1']);
  });
});

describe('palette', () => {
  it('shows translated group titles and every block, and re-translates on relabel', () => {
    let lang = 'en';
    const en = catalogue(enJson);
    const cs = catalogue(csJson);
    const m = mount({ t: (k) => (lang === 'cs' ? cs[k] : en[k]) ?? `!${k}` });
    const titles = () => [...m.container.querySelectorAll('.sfc-palette-title')].map((e) => e.textContent);
    expect(titles()).toEqual(['SFC blocks', 'SFC groups', 'Special blocks']);
    const entries = [...m.container.querySelectorAll('.sfc-entry')].map((e) => e.textContent);
    expect(entries).toEqual([
      'Initial step', 'Step', 'Transition', 'Jump',
      'Selection divergence', 'Selection convergence', 'Simultaneous divergence', 'Simultaneous convergence',
      'Text', 'Action block',
    ]);
    lang = 'cs';
    m.canvas.relabel();
    expect(titles()).toEqual([cs['palette.blocks'], cs['palette.groups'], cs['palette.special']]);
    expect([...m.container.querySelectorAll('.sfc-entry')].map((e) => e.textContent)).toContain(cs['palette.step']);
  });

  it('greys simultaneous branches and action blocks on ATMT and EATMT charts, and refuses to create them there', () => {
    const m = mount();
    // The entries offered: those not greyed (refused ones stay visible with the reason).
    const kinds = () =>
      [...m.container.querySelectorAll('.djs-palette [data-action^="create."]')].filter((e) => !e.classList.contains('refused')).map((e) => e.getAttribute('data-action'));
    m.canvas.load({ ...conveyorDoc(), target: 'atmt' });
    expect(kinds()).not.toContain('create.simultaneous-divergence');
    expect(kinds()).not.toContain('create.simultaneous-convergence');
    expect(kinds()).toContain('create.selection-divergence');
    const palette = m.get('sfcPalette');
    const rules = m.get('rules');
    const shape = (id: string) => palette.newShape(palette['specs']().find((s: { id: string }) => s.id === id));
    const root = m.get('canvas').getRootElement();
    expect(rules.allowed('shape.create', { shape: shape('simultaneous-divergence'), target: root })).toBe(false);
    expect(rules.allowed('elements.create', { elements: [shape('step'), shape('simultaneous-convergence')], target: root })).toBe(false);
    expect(rules.allowed('shape.create', { shape: shape('selection-divergence'), target: root })).toBe(true);
    // Changing the chart's target back (an undoable edit) offers them again.
    m.canvas.updateDoc({ target: 'blank' });
    expect(kinds()).toContain('create.simultaneous-divergence');
    expect(rules.allowed('shape.create', { shape: shape('simultaneous-divergence'), target: root })).toBe(true);
    m.canvas.undo();
    expect(kinds()).not.toContain('create.simultaneous-divergence');
    m.canvas.load({ ...conveyorDoc(), target: 'eatmt' });
    expect(kinds()).not.toContain('create.simultaneous-convergence');
    expect(kinds()).not.toContain('create.action-block');
    expect(rules.allowed('shape.create', { shape: shape('action-block'), target: root })).toBe(false);
  });

  it('new steps and transitions get unique names', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    m.canvas.updateElement('step:A', { name: 'S1' });
    const palette = m.get('sfcPalette');
    const root = m.get('canvas').getRootElement();
    const add = (id: string, x: number) => {
      const spec = palette['specs']().find((s: { id: string }) => s.id === id);
      m.get('modeling').createShape(palette.newShape(spec), { x, y: 600 }, root);
    };
    add('step', 100);
    add('step', 200);
    add('initial-step', 300);
    add('transition', 400);
    add('transition', 500);
    const added = m.canvas.getDoc().elements.slice(12);
    expect(added.map((e) => e.name)).toEqual(['S2', 'S3', 'S4', 'T1', 'T2']);
    expect(added[2].initial).toBe(true);
    // Snapped to the grid by the create tool's position.
    for (const e of added) expect(e.x % 10).toBe(0);
  });

  it('gives a new transition no condition (saved as FALSE until one is written)', () => {
    const m = mount();
    // A Blank chart (an ATMT chart's new transition reads the next free input, C<n>).
    m.canvas.load({ ...conveyorDoc(), target: 'blank' });
    const palette = m.get('sfcPalette');
    const spec = palette['specs']().find((s: { id: string }) => s.id === 'transition');
    m.get('modeling').createShape(palette.newShape(spec), { x: 400, y: 600 }, m.get('canvas').getRootElement());
    const made = m.canvas.getDoc().elements.at(-1)!;
    expect(made.kind).toBe('transition');
    expect(made.condition ?? '').toBe('');
  });

  it('refuses a move onto another block, and allows one to free room', () => {
    const m = mount();
    m.canvas.load(conveyorDoc());
    const registry = m.get('elementRegistry');
    const rules = m.get('rules');
    const root = m.get('canvas').getRootElement();
    const steps = registry.filter((e: { businessObject?: { kind?: string } }) => e.businessObject?.kind === 'step');
    const [a, b] = steps;
    const onto = { x: b.x - a.x + 5, y: b.y - a.y + 5 };
    expect(rules.allowed('elements.move', { shapes: [a], delta: onto, target: root })).toBe(false);
    expect(rules.allowed('elements.move', { shapes: [a], delta: { x: -400, y: 0 }, target: root })).toBe(true);
  });

  it('is absent on a read-only canvas', () => {
    const m = mount({ readOnly: true });
    m.canvas.load(conveyorDoc());
    expect(m.container.querySelector('.djs-palette')).toBeNull();
  });
});
