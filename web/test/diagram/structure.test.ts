// Structured editing (docs/editor.md, "Structured editing"): insert a step and a transition
// after or before the selection, delete a step with its transition and reconnect, a drop on a
// wire inserts into it; each one command on the undo stack. Pins are easy to hit.
import { describe, expect, it } from 'vitest';
import { mount, type Mounted } from './harness';
import type { Connection, EditorDoc, Element } from '../../src/doc';
import { wireAt } from '../../src/diagram/modeling/cmd/StructureHandlers';

/** Init → T1 → S1 → T2 → S2 → T3 → jump Init; beside it a selection branch:
 *  Q0 → div → (Ta → A → Tb | Tc → B → Td) → conv → Q1. */
function seqDoc(): EditorDoc {
  const step = (id: string, x: number, y: number, extra: Partial<Element> = {}): Element => ({ id, kind: 'step', x, y, w: 80, h: 40, name: id.split(':')[1], ...extra });
  const tr = (id: string, x: number, y: number): Element => ({ id, kind: 'transition', x, y, w: 40, h: 20, name: id.split(':')[1], condition: 'TRUE' });
  const elements: Element[] = [
    step('step:Init', 100, 40, { initial: true }),
    tr('transition:T1', 120, 110),
    step('step:S1', 100, 160),
    { id: 'ab1', kind: 'actionBlock', x: 220, y: 170, w: 180, h: 20, step: 'step:S1', associations: [{ qualifier: 'N', action: 'x' }] },
    tr('transition:T2', 120, 230),
    step('step:S2', 100, 280),
    tr('transition:T3', 120, 350),
    { id: 'j1', kind: 'jump', x: 130, y: 400, w: 20, h: 20, target: 'Init' },
    step('step:Q0', 500, 40),
    { id: 'div', kind: 'selectionDivergence', x: 470, y: 110, w: 140, h: 10, pins: 2 },
    tr('transition:Ta', 460, 150),
    tr('transition:Tc', 580, 150),
    step('step:A', 440, 200),
    step('step:B', 560, 200),
    tr('transition:Tb', 460, 270),
    tr('transition:Td', 580, 270),
    { id: 'conv', kind: 'selectionConvergence', x: 470, y: 320, w: 140, h: 10, pins: 2 },
    step('step:Q1', 500, 360),
  ];
  const w = (id: string, source: string, target: string, sourcePin = 0, targetPin = 0): Connection => ({ id, source, sourcePin, target, targetPin });
  return {
    pou: 'Seq',
    pouKind: 'program',
    target: 'blank',
    declarations: 'VAR\n  x : BOOL;\nEND_VAR\n',
    actions: [],
    elements,
    connections: [
      w('c1', 'step:Init', 'transition:T1'),
      w('c2', 'transition:T1', 'step:S1'),
      w('c3', 'step:S1', 'transition:T2'),
      w('c4', 'transition:T2', 'step:S2'),
      w('c5', 'step:S2', 'transition:T3'),
      w('c6', 'transition:T3', 'j1'),
      w('c10', 'step:Q0', 'div'),
      w('c11', 'div', 'transition:Ta', 0, 0),
      w('c12', 'div', 'transition:Tc', 1, 0),
      w('c13', 'transition:Ta', 'step:A'),
      w('c14', 'transition:Tc', 'step:B'),
      w('c15', 'step:A', 'transition:Tb'),
      w('c16', 'step:B', 'transition:Td'),
      w('c17', 'transition:Tb', 'conv', 0, 0),
      w('c18', 'transition:Td', 'conv', 0, 1),
      w('c19', 'conv', 'step:Q1'),
    ],
  };
}

const el = (d: EditorDoc, id: string) => d.elements.find((e) => e.id === id);
const named = (d: EditorDoc, name: string) => d.elements.find((e) => e.name === name)!;
/** The chart's wires as `SOURCE>TARGET` names (pins when not 0), sorted. */
const links = (d: EditorDoc) =>
  d.connections
    .map((c) => {
      const n = (id: string) => el(d, id)?.name || id;
      return `${n(c.source)}${c.sourcePin ? `.${c.sourcePin}` : ''}>${n(c.target)}${c.targetPin ? `.${c.targetPin}` : ''}`;
    })
    .sort();
const orthogonal = (d: EditorDoc) =>
  d.connections.every((c) => (c.waypoints ?? []).every((p, i, a) => i === 0 || p.x === a[i - 1].x || p.y === a[i - 1].y));

/** Runs `op` on the sequence chart; checks it is one undoable step, then `check`. */
function oneCommand(op: (m: Mounted) => void, check: (before: EditorDoc, after: EditorDoc, m: Mounted) => void) {
  const m = mount();
  m.canvas.load(seqDoc());
  const before = m.canvas.getDoc();
  op(m);
  const after = m.canvas.getDoc();
  expect(after).not.toStrictEqual(before);
  expect(orthogonal(after)).toBe(true);
  check(before, after, m);
  m.canvas.undo();
  expect(m.canvas.getDoc()).toStrictEqual(before);
  expect(m.canvas.canUndo()).toBe(false);
  m.canvas.redo();
  expect(m.canvas.getDoc()).toStrictEqual(after);
}

const key = (m: Mounted, k: string, mods: KeyboardEventInit = {}) => {
  const svg = m.get('canvas')._svg as SVGSVGElement;
  svg.dispatchEvent(new KeyboardEvent('keydown', { key: k, bubbles: true, ...mods }));
};

describe('insert a step and a transition', () => {
  it('after a step: S1 → T → Step → T2, the blocks below moved down', () => {
    oneCommand(
      (m) => {
        m.canvas.select(['step:S1']);
        expect(m.canvas.canStructure('insertAfter')).toBe(true);
        expect(m.canvas.structure('insertAfter')).toBe(true);
      },
      (b, a, m) => {
        expect(links(a)).toContain('S1>T4');
        expect(links(a)).toContain('T4>Step1');
        expect(links(a)).toContain('Step1>T2');
        expect(links(a)).not.toContain('S1>T2');
        expect(named(a, 'T4')).toMatchObject({ kind: 'transition', x: 120, y: 230, condition: 'TRUE' });
        expect(named(a, 'Step1')).toMatchObject({ kind: 'step', x: 100, y: 280 });
        // 20 + 30 + 40 + 30 = 120 down: everything below S1, in every column.
        for (const id of ['transition:T2', 'step:S2', 'transition:T3', 'j1', 'transition:Tb', 'conv', 'step:Q1']) {
          expect(el(a, id)!.y).toBe(el(b, id)!.y + 120);
        }
        for (const id of ['step:Init', 'step:S1', 'ab1', 'transition:Ta', 'div']) expect(el(a, id)!.y).toBe(el(b, id)!.y);
        // The new step is selected: Insert again goes on below it.
        expect(m.canvas.selection()).toEqual([named(a, 'Step1').id]);
      },
    );
  });

  it('after a transition: T1 → Step → T → S1; Insert again goes on from the new transition', () => {
    const m = mount();
    m.canvas.load(seqDoc());
    m.canvas.select(['transition:T1']);
    key(m, 'Insert');
    let d = m.canvas.getDoc();
    expect(links(d)).toEqual(expect.arrayContaining(['T1>Step1', 'Step1>T4', 'T4>S1']));
    expect(m.canvas.selection()).toEqual([named(d, 'T4').id]);
    key(m, 'Insert');
    d = m.canvas.getDoc();
    expect(links(d)).toEqual(expect.arrayContaining(['T1>Step1', 'Step1>T4', 'T4>Step2', 'Step2>T5', 'T5>S1']));
    m.canvas.undo();
    expect(links(m.canvas.getDoc())).toEqual(expect.arrayContaining(['T1>Step1', 'Step1>T4', 'T4>S1']));
  });

  it('before a step (Shift+Insert): T2 → Step → T → S2, S2 and below moved down', () => {
    oneCommand(
      (m) => {
        m.canvas.select(['step:S2']);
        key(m, 'Insert', { shiftKey: true });
      },
      (b, a) => {
        expect(links(a)).toEqual(expect.arrayContaining(['T2>Step1', 'Step1>T4', 'T4>S2']));
        expect(links(a)).not.toContain('T2>S2');
        expect(named(a, 'Step1')).toMatchObject({ x: 100, y: 280 });
        expect(named(a, 'T4')).toMatchObject({ x: 120, y: 350 });
        expect(el(a, 'step:S2')!.y).toBe(el(b, 'step:S2')!.y + 120);
        expect(el(a, 'transition:T2')!.y).toBe(el(b, 'transition:T2')!.y);
      },
    );
  });

  it('before a transition: S1 → T → Step → T2', () => {
    oneCommand(
      (m) => {
        m.canvas.select(['transition:T2']);
        m.canvas.structure('insertBefore');
      },
      (_b, a) => {
        expect(links(a)).toEqual(expect.arrayContaining(['S1>T4', 'T4>Step1', 'Step1>T2']));
      },
    );
  });

  it('after the last transition of a branch: the new pair goes before the convergence, same pin', () => {
    oneCommand(
      (m) => {
        m.canvas.select(['transition:Td']);
        m.canvas.structure('insertAfter');
      },
      (_b, a) => {
        expect(links(a)).toEqual(expect.arrayContaining(['Td>Step1', 'Step1>T4', 'T4>conv.1']));
      },
    );
  });

  it('applies only to one selected step or transition', () => {
    const m = mount();
    m.canvas.load(seqDoc());
    m.canvas.select(['div']);
    expect(m.canvas.canStructure('insertAfter')).toBe(false);
    m.canvas.select(['step:S1', 'step:S2']);
    expect(m.canvas.structure('insertBefore')).toBe(false);
    expect(m.canvas.canUndo()).toBe(false);
  });
});

describe('delete a step with its transition and reconnect', () => {
  it('in a sequence: S1 and T2 go, T1 → S2; the action block goes with its step', () => {
    oneCommand(
      (m) => {
        m.canvas.select(['step:S1']);
        expect(m.canvas.canStructure('deleteStep')).toBe(true);
        key(m, 'Delete');
      },
      (_b, a) => {
        for (const id of ['step:S1', 'transition:T2', 'ab1']) expect(el(a, id)).toBeUndefined();
        expect(links(a)).toContain('T1>S2');
        // Nothing dangles: every step and transition of the sequence has both wires.
        for (const n of ['T1', 'S2']) {
          const id = named(a, n).id;
          expect(a.connections.some((c) => c.source === id)).toBe(true);
          expect(a.connections.some((c) => c.target === id)).toBe(true);
        }
      },
    );
  });

  it('inside a selection branch: B and Td go, Tc → the convergence on the same pin', () => {
    oneCommand(
      (m) => {
        m.canvas.select(['step:B']);
        m.canvas.structure('deleteStep');
      },
      (_b, a) => {
        expect(el(a, 'step:B')).toBeUndefined();
        expect(el(a, 'transition:Td')).toBeUndefined();
        expect(links(a)).toContain('Tc>conv.1');
        expect(links(a)).toContain('Tb>conv');
      },
    );
  });

  it('plain Delete elsewhere removes only the selection', () => {
    const m = mount();
    m.canvas.load(seqDoc());
    m.canvas.select(['step:Init']);
    expect(m.canvas.canStructure('deleteStep')).toBe(false);
    key(m, 'Delete');
    const d = m.canvas.getDoc();
    expect(el(d, 'step:Init')).toBeUndefined();
    expect(el(d, 'transition:T1')).toBeDefined();
    m.canvas.select(['transition:T1']);
    key(m, 'Delete');
    expect(el(m.canvas.getDoc(), 'transition:T1')).toBeUndefined();
    expect(el(m.canvas.getDoc(), 'step:S1')).toBeDefined();
  });
});

describe('a drop on a wire inserts into it', () => {
  const drop = (m: Mounted, kind: 'step' | 'transition', wire: string) => {
    const palette = m.get('sfcPalette');
    const spec = palette['specs']().find((s: { id: string }) => s.id === kind);
    const shape = palette.newShape(spec);
    const reg = m.get('elementRegistry');
    const c = reg.get(wire);
    const mid = c.waypoints[0];
    const at = { x: mid.x, y: mid.y + 10 };
    expect(wireAt(reg, at)?.id).toBe(wire);
    m.get('modeling').createElements([shape], at, m.get('canvas').getRootElement(), { sfcSpliceWire: wire });
  };

  it('a step on T1 → S1: T1 → Step → T → S1', () => {
    oneCommand(
      (m) => drop(m, 'step', 'c2'),
      (_b, a) => {
        expect(links(a)).toEqual(expect.arrayContaining(['T1>S3', 'S3>T4', 'T4>S1']));
        expect(named(a, 'S3')).toMatchObject({ x: 100, y: 160 });
        expect(el(a, 'step:S1')!.y).toBe(160 + 120);
      },
    );
  });

  it('a step on S1 → T2: S1 → T → Step → T2', () => {
    oneCommand(
      (m) => drop(m, 'step', 'c3'),
      (_b, a) => {
        expect(links(a)).toEqual(expect.arrayContaining(['S1>T4', 'T4>S3', 'S3>T2']));
      },
    );
  });

  it('a transition on T1 → S1: T1 → Step → T → S1', () => {
    oneCommand(
      (m) => drop(m, 'transition', 'c2'),
      (_b, a) => {
        expect(links(a)).toEqual(expect.arrayContaining(['T1>Step1', 'Step1>T4', 'T4>S1']));
      },
    );
  });

  it('no wire of a transition and a step near the point: none', () => {
    const m = mount();
    m.canvas.load(seqDoc());
    const reg = m.get('elementRegistry');
    expect(wireAt(reg, { x: 300, y: 300 })).toBeUndefined();
    // A wire from a divergence is not a sequence wire.
    expect(wireAt(reg, { x: 480, y: 130 })).toBeUndefined();
  });
});

describe('pins are easy to hit', () => {
  it('a press 8 px beyond a free output pin, outside the block, starts a wire', () => {
    const m = mount();
    m.canvas.load(seqDoc());
    m.canvas.select([]);
    // Q1's output pin is free: (540, 400).
    const pc = m.get('sfcConnect');
    expect(pc.pinAt({ x: 540, y: 408 })).toMatchObject({ side: 'out', pin: 0 });
    expect(pc.pinAt({ x: 546, y: 406 })?.shape.id).toBe('step:Q1');
    expect(pc.pinAt({ x: 540, y: 420 })).toBeUndefined();
    // Q0's input pin (540, 40), from above.
    expect(pc.pinAt({ x: 540, y: 32 })).toMatchObject({ side: 'in' });
  });
});
