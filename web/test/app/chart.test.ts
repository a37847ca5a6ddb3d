import { describe, expect, it } from 'vitest';
import { freshName, isIecName, legendRows, stepNames, stepsAfter, stepsBefore, witnessSituations } from '../../src/app/chart';
import type { EditorDoc } from '../../src/doc';
import mixer from './fixtures/mixer.doc.json';

const doc = mixer as EditorDoc;

describe('legend', () => {
  it('lists every block: steps by tag, then transitions, branches, jumps, action blocks, texts', () => {
    const rows = legendRows(doc);
    expect(rows.length).toBe(doc.elements.length);
    expect(rows.map((r) => [r.kind, r.name, r.tag])).toEqual([
      ['step', 'Init', '0'],
      ['step', 'A', '1'],
      ['step', 'B', '2'],
      ['step', 'Done', '3'],
      ['transition', 'T1', '0'],
      ['transition', 'T2', ''],
      ['transition', 'T3', ''],
      ['simultaneousDivergence', '', ''],
      ['simultaneousConvergence', '', ''],
      ['jump', '→ Init', ''],
      ['actionBlock', 'A: N Fill, L Horn', ''],
      ['text', 'Mixer cycle', ''],
    ]);
    expect(rows.find((r) => r.id === 'step:A')?.description).toBe('Fill the tank');
  });
  it('lists every transition with its whole condition, named or not', () => {
    const long = 'Brushing.T >= MaxBrushTime AND NOT CarLeft AND NOT StopButton AND NOT Reset AND NOT Fault';
    const d: EditorDoc = {
      ...doc,
      elements: [
        { id: 'transition#1', kind: 'transition', condition: ' x AND y ', x: 0, y: 0, w: 1, h: 1 },
        { id: 'transition:T9', kind: 'transition', name: 'T9', condition: `${long}\n\n  OR Manual `, x: 0, y: 0, w: 1, h: 1 },
        { id: 'step:S', kind: 'step', name: 'S', x: 0, y: 0, w: 1, h: 1 },
      ],
    };
    const rows = legendRows(d);
    expect(rows.map((r) => [r.kind, r.name, r.condition])).toEqual([
      ['step', 'S', ''],
      ['transition', '', 'x AND y'],
      ['transition', 'T9', `${long}\nOR Manual`],
    ]);
  });
});

describe('witness', () => {
  it('walks through branches and jumps', () => {
    expect(stepsBefore(doc, 'transition:T1')).toEqual(['step:Init']);
    expect(stepsAfter(doc, 'transition:T1').sort()).toEqual(['step:A', 'step:B']);
    expect(stepsBefore(doc, 'transition:T2').sort()).toEqual(['step:A', 'step:B']);
    expect(stepsAfter(doc, 'transition:T3')).toEqual(['step:Init']);
  });
  it('derives the active steps after each firing', () => {
    const s = witnessSituations(doc, ['transition:T1', 'transition:T2', 'transition:T3']);
    expect(s.map((x) => [...x].sort())).toEqual([['step:A', 'step:B'], ['step:Done'], ['step:Init']]);
  });
});

describe('names', () => {
  it('checks IEC names', () => {
    for (const ok of ['Mixer', '_x', 'MAX_U_24', 'a1']) expect(isIecName(ok)).toBe(true);
    for (const bad of ['', '1a', 'a b', 'MAX__U', 'MAX_U_', 'ä']) expect(isIecName(bad)).toBe(false);
  });
  it('finds fresh names and lists steps', () => {
    expect(freshName(doc, 'Action')).toBe('Action1');
    expect(freshName({ ...doc, actions: [...doc.actions, { name: 'action1', body: '' }] }, 'Action')).toBe('Action2');
    expect(stepNames(doc)).toEqual(['A', 'B', 'Done', 'Init']);
  });
});
